"""What the sweep tests share: a temp dir of each test's own, an in-process runner, a
sweep call without workers, a subprocess sweep interrupted by a terminal's Ctrl-C, the
one-line error check and a folder snapshot."""
import os
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import pytest

from viewer.commands.main import version
from viewer.sweep import run as sweep_run
from viewer.sweep.cells import run_cell
from viewer.sweep.spec import load_sweep

from conftest import default_signals


@pytest.fixture(autouse=True)
def own_temp_dir(tmp_path, monkeypatch):
    """The workers' copies in a temp dir of the test's own (workers inherit TMPDIR): every
    sweep removes its copies, so the test ends with none of hmblur's there."""
    temp = tmp_path / "temp"
    temp.mkdir()
    monkeypatch.setenv("TMPDIR", str(temp))
    monkeypatch.setattr(tempfile, "tempdir", str(temp))
    yield temp
    assert sorted(p.name for p in temp.iterdir() if "hmblur" in p.name) == []


def in_process(calls=None):
    """A runner for run_sweep: every cell here, through the same run_cell as a worker."""
    def runner(tasks, bundles, on_result):
        for t in tasks:
            if calls is not None:
                calls.append(t.scene)
            on_result(t, run_cell(t, bundles[t.digest]))
        return {"engine": "test"}
    return runner


def sweep(tmp_path, path, out, runner=None, **kw):
    args = dict(version=version(), workers=0, scheduler=None, images=False, timing=False)
    args.update(kw)
    return sweep_run.run_sweep(load_sweep(path), out, stream=open(tmp_path / "progress.txt", "a"),
                               runner=runner or in_process(), **args)


def interrupted(argv, env, cwd, ready, seconds=180):
    """Runs argv in a session of its own and sends SIGINT to its whole process group (a
    terminal's Ctrl-C) the first time ready(pid) is true, polled every 5 ms.
    Returns (return code, stderr, whether the signal was sent)."""
    proc = subprocess.Popen(argv, env=env, cwd=cwd, stdout=subprocess.DEVNULL,
                            preexec_fn=default_signals,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    sent = False
    try:
        t_end = time.monotonic() + seconds
        while proc.poll() is None and time.monotonic() < t_end:
            if ready(proc.pid):
                os.killpg(proc.pid, signal.SIGINT)
                sent = True
                break
            time.sleep(0.005)
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, err, sent


def one_line_error(capsys, *words):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("hmblur: error: "), err
    assert "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    return err


def snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and not p.is_symlink()}
