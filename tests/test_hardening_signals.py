"""SIGTERM and SIGHUP (a job scheduler, a closed terminal) end hmblur as Ctrl-C does: no
hidden .tmp file, no .part staging folder, nothing half-written. Each case runs the real
command and signals it at the moment its partial files exist on disk, or (from inside the
process, so at an exact step) while the k-th temporary file is written, after it, after
the sidecar's, and at the k-th rename.

Every run starts with the three signals at their defaults, set explicitly: a test run
under nohup (SIGHUP ignored) or in a background job (SIGINT ignored) would otherwise hand
the ignored signal on, and hmblur keeps a signal ignored that it started with."""
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import ROOT, default_signals

BASIC = str(ROOT / "tests" / "conformance" / "basic.toml")


def partial_files(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*")
                  if p.name.endswith((".tmp", ".part")))


ENDING = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def signal_when(argv, folder, sig, ready, timeout=120.0):
    """Run hmblur, send `sig` as soon as `ready(folder)` holds; (exit status, stderr,
    whether the signal was sent while ready held)."""
    p = subprocess.Popen([sys.executable, "-m", "viewer", *argv], cwd=ROOT,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                         preexec_fn=default_signals)
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


# hmblur run with a signal sent to itself at one step of writing its outputs (STEP K): K
# counts temporary files ("writing": inside the K-th file's write, before its fsync;
# "written": once it is complete) or renames of temporary files into place ("rename").
# K may be a file's name instead of a count: its temporary file, or its rename.
AT_STEP = """
import os, signal, sys
for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
    signal.signal(s, signal.SIG_DFL)
step, which, sig = sys.argv[1], sys.argv[2], getattr(signal, sys.argv[3])
from viewer.io import imageio
seen = []

def fire(path):
    seen.append(os.path.basename(str(path)))
    if which == seen[-1] if not which.isdigit() else len(seen) == int(which):
        os.kill(os.getpid(), sig)

if step == "rename":
    real_replace = os.replace
    def replace(a, b):
        real_replace(a, b)
        if str(a).endswith(".tmp"):
            fire(b)
    os.replace = replace
else:
    real_temp = imageio._write_temp
    def write_temp(path, write, made=None):
        if step == "writing":
            def then_fire(f):
                write(f)
                fire(path)
            return real_temp(path, then_fire, made)
        tmp = real_temp(path, write, made)
        fire(path)
        return tmp
    imageio._write_temp = write_temp
from viewer.commands.main import main
code = main(sys.argv[4:])
print("steps seen:", len(seen), file=sys.stderr)
sys.exit(code)
"""


def at_step(step, which, sig, argv):
    p = subprocess.run([sys.executable, "-c", AT_STEP, step, str(which), sig.name, *argv],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    return p.returncode, p.stderr


SHOT_FILES = {"a.png", "a.json", "buf/README.txt", "buf/color.npy"}


@pytest.mark.parametrize("step,which,sig", [
    ("writing", 1, signal.SIGTERM), ("written", 1, signal.SIGTERM),
    ("writing", 12, signal.SIGTERM), ("written", 12, signal.SIGHUP),
    ("written", 12, signal.SIGINT),
    ("writing", "a.json", signal.SIGTERM), ("written", "a.json", signal.SIGHUP),
    ("rename", 1, signal.SIGTERM), ("rename", 12, signal.SIGHUP),
    ("rename", 12, signal.SIGINT), ("rename", "a.json", signal.SIGTERM)])
def test_a_signal_at_each_step_of_a_shots_write(tmp_path, step, which, sig):
    # Signalled while a temporary file is written or once it is: nothing is left, not even
    # the buffers' folder made for them. At a rename: the renames go on to the last one,
    # then it ends; every file is there, none partial.
    argv = ["shot", BASIC, "--mode", "hybrid", "--size", "64x36", "--out",
            str(tmp_path / "a.png"), "--buffers", str(tmp_path / "buf")]
    code, err = at_step(step, which, sig, argv)
    said = "interrupted" if sig == signal.SIGINT else f"terminated ({sig.name})"
    assert code == 128 + sig and f"hmblur: {said}" in err.splitlines(), err
    assert partial_files(tmp_path) == [], err
    written = {str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*")}
    if step == "rename":
        assert SHOT_FILES <= written and len(written) > 20, sorted(written)
    else:
        assert written == set(), sorted(written)


@pytest.mark.parametrize("step,which", [("written", 3), ("rename", 3), ("written", 6),
                                        ("rename", 6), ("rename", "video.json")])
def test_a_signal_at_a_step_of_a_videos_commit(tmp_path, step, which):
    # A folder of PNG frames: each frame goes to the staging folder as it is rendered
    # (steps 1-4: a temporary file, renamed), then the commit copies the four frames and
    # the sidecar into place (steps 5-9). The frames and the sidecar appear together or
    # not at all.
    argv = ["video", BASIC, "--modes", "off", "--size", "32x18", "--frames", "4",
            "--out", str(tmp_path / "frames/")]
    code, err = at_step(step, which, signal.SIGTERM, argv)
    assert code == 128 + signal.SIGTERM, err
    assert partial_files(tmp_path) == [], err
    written = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    if step == "rename" and which != 3:
        assert written == ["frames", "frames/.hmblur-outputs.json", "frames/frame_0000.png",
                           "frames/frame_0001.png", "frames/frame_0002.png",
                           "frames/frame_0003.png", "frames/video.json"], written
    else:
        assert written == [], written
