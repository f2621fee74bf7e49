"""SIGTERM and SIGHUP (a job scheduler, a closed terminal) end hmblur as Ctrl-C does: no
hidden .tmp file, no .part staging folder, nothing half-written. Each case runs the real
command and signals it at the moment its partial files exist on disk."""
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import ROOT

BASIC = str(ROOT / "tests" / "conformance" / "basic.toml")


def partial_files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                  if p.name.endswith((".tmp", ".part")))


def signal_when(argv, folder, sig, ready, timeout=120.0):
    """Run hmblur, send `sig` as soon as `ready(folder)` holds; (exit status, stderr,
    whether the signal was sent while ready held)."""
    p = subprocess.Popen([sys.executable, "-m", "viewer", *argv], cwd=ROOT,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    sent = False
    t_end = time.monotonic() + timeout
    try:
        while p.poll() is None and time.monotonic() < t_end:
            if ready(folder):
                p.send_signal(sig)
                sent = True
                break
            time.sleep(0.002)
        _, err = p.communicate(timeout=timeout)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    return p.returncode, err, sent


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_a_signal_during_the_buffers_write_leaves_nothing(tmp_path, sig):
    # Signalled while the image, its sidecar and ~50 buffer files sit as temp files.
    argv = ["shot", BASIC, "--mode", "hybrid", "--size", "320x180", "--out",
            str(tmp_path / "a.png"), "--buffers", str(tmp_path / "buf")]
    code, err, sent = signal_when(argv, tmp_path, sig,
                                  lambda f: any(p.name.endswith(".tmp") for p in f.rglob("*")))
    assert sent, err
    assert code == 128 + sig, err
    said = "interrupted" if sig == signal.SIGINT else f"terminated ({signal.Signals(sig).name})"
    assert err.strip().splitlines()[-1] == f"hmblur: {said}"
    assert partial_files(tmp_path) == [], err
    # all or nothing: a signal during the renames waits for the last one
    written = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    assert written == [] or {"a.png", "a.json", "buf/README.txt", "buf/color.npy"} <= set(written)


@pytest.mark.parametrize("out", ["frames/", "clip.mp4", "clip.gif"])
def test_sigterm_during_a_video_leaves_nothing(tmp_path, out):
    argv = ["video", BASIC, "--modes", "off", "--size", "64x36", "--frames", "2000",
            "--out", str(tmp_path / out)]
    # The staging folder exists from the first frame to the commit.
    code, err, sent = signal_when(argv, tmp_path, signal.SIGTERM,
                                  lambda f: any(p.name.endswith(".part") for p in f.iterdir()))
    assert sent, err
    assert code == 128 + signal.SIGTERM, err
    assert partial_files(tmp_path) == [], err
    assert sorted(os.listdir(tmp_path)) == [], err


def test_an_ignored_sighup_stays_ignored():
    # nohup's promise: a SIGHUP ignored before hmblur starts is not turned into an exit.
    code = ("import signal; signal.signal(signal.SIGHUP, signal.SIG_IGN);"
            "from viewer.commands.main import catch_signals; catch_signals();"
            "assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN;"
            "assert signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL")
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True)
