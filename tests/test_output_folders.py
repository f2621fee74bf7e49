"""Output folders keep the user's files (issue 39): compare --out, shot --buffers, a
video's folder of frames and sweep --out write a file only where nothing is or over a file
hmblur wrote there and that has not changed since (viewer/io/outdir.py); a viewer
screenshot takes only free names. The folder states are a property test with a fixed
seed (hypothesis, derandomize)."""
import json
import os
import time

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from viewer.commands.main import main
from viewer.io.imageio import OutputSet
from viewer.io.outdir import MANIFEST, OutputFolder
from world.errors import UserError

from conftest import CONFORMANCE
from sweep_helpers import one_line_error, snapshot

BASIC = CONFORMANCE / "basic.toml"
PROPS = dict(derandomize=True, deadline=None,
             suppress_health_check=[HealthCheck.function_scoped_fixture,
                                    HealthCheck.too_slow])


NAMES = ["a.png", "a.json", "notes.md", "sub/b.png", "cells/k.json", "images/c/x.png"]


@settings(max_examples=60, **PROPS)
@given(st.dictionaries(st.sampled_from(NAMES + ["cells", "images", "sub"]),
                       st.sampled_from(["user file", "user folder", "link out", "hmblur's",
                                        "hmblur's, edited", "hmblur's, replaced by a link"]),
                       max_size=4),
       st.lists(st.sampled_from(NAMES), min_size=1, max_size=4, unique=True))
def test_an_output_folder_replaces_only_what_hmblur_wrote(tmp_path_factory, before, writes):
    """Whatever the folder holds (the user's files, folders and links at the names a
    command writes, hmblur's own files, edited or not), a commit either writes every file
    of its set or, when one would replace something hmblur did not write, refuses in one
    line having changed nothing; a second hmblur run replaces its own files."""
    root = tmp_path_factory.mktemp("out")
    out = root / "out"
    outside = root / "outside.txt"
    outside.write_bytes(b"outside")
    folder = OutputFolder(out, "--out", whole=("cells", "images"))
    ours = [n for n, kind in before.items() if kind.startswith("hmblur's") and n in NAMES]
    if ours:                                    # hmblur's own files, through the rule
        files = OutputSet(folder)
        for n in ours:
            files.add(out / n, lambda f, n=n: f.write(f"hmblur {n}".encode()))
        try:
            files.commit()
        except UserError:
            pass
    out.mkdir(exist_ok=True)
    for n, kind in before.items():
        p = out / n
        if kind.startswith("hmblur's") and n in NAMES:
            if kind == "hmblur's, edited" and p.is_file():
                time.sleep(0.002)
                p.write_bytes(b"edited by the user")
            elif kind == "hmblur's, replaced by a link" and p.is_file():
                p.unlink()
                p.symlink_to(outside)
            continue
        if os.path.lexists(p) or any(os.path.lexists(q) and not q.is_dir()
                                     for q in p.parents if out in q.parents):
            continue
        p.parent.mkdir(parents=True, exist_ok=True)
        if kind == "user folder" or kind.startswith("hmblur's"):
            p.mkdir()
            (p / "keep.txt").write_bytes(b"the user's")
        elif kind == "link out":
            p.symlink_to(outside)
        else:
            p.write_bytes(f"the user's {n}".encode())
    was = snapshot(out)
    links = {str(p.relative_to(out)): os.readlink(p) for p in out.rglob("*") if p.is_symlink()}
    files = OutputSet(folder)
    for n in writes:
        files.add(out / n, lambda f, n=n: f.write(f"new {n}".encode()))
    try:
        files.commit()
        ok = True
    except (UserError, OSError):
        ok = False
    now = snapshot(out)
    assert outside.read_bytes() == b"outside"
    assert {str(p.relative_to(out)): os.readlink(p)
            for p in out.rglob("*") if p.is_symlink()} == links
    if not ok:                                 # nothing changed but hmblur's list
        assert {k: v for k, v in now.items() if k != MANIFEST} == \
            {k: v for k, v in was.items() if k != MANIFEST}
        return
    for n in writes:
        assert now[n] == f"new {n}".encode()
    for k, v in was.items():                   # every other file as it was
        if k not in writes and k != MANIFEST:
            assert now[k] == v, k
    # what was replaced was hmblur's: absent, or its unchanged file, or in its folder
    doc_before = before
    for n in writes:
        if n in was and not n.startswith(("cells/", "images/")):
            assert doc_before.get(n) == "hmblur's", n


@pytest.mark.parametrize("argv, mine", [
    (["compare", str(BASIC), "--size", "16x10", "--samples", "2", "--modes", "mcguire"],
     "metrics.md"),
    (["shot", str(BASIC), "--size", "16x10", "--mode", "off"], "README.txt"),
    (["video", str(BASIC), "--size", "16x10", "--modes", "off", "--frames", "2"],
     "frame_0001.png"),
])
def test_every_command_refuses_a_folder_file_of_the_users_and_keeps_it(tmp_path, capsys,
                                                                      argv, mine):
    """compare --out, shot --buffers and video's folder of frames (sweep --out:
    tests/test_sweep_hardening.py): a file of the user's at a name the command writes is
    one line, exit 2, before any work; the folder as it was. Then, in a folder of its
    own, the command runs twice (the second replaces its own files)."""
    out = tmp_path / "out"
    (out / mine).parent.mkdir(parents=True, exist_ok=True)
    (out / mine).write_bytes(b"the user's")
    (out / "notes.txt").write_bytes(b"the user's too")
    flag = "--buffers" if argv[0] == "shot" else "--out"
    extra = ["--out", str(tmp_path / "a.png")] if argv[0] == "shot" else []
    was = snapshot(out)
    assert main(argv + extra + [flag, str(out)]) == 2
    one_line_error(capsys, str(out), mine.split("/")[0])
    assert snapshot(out) == was
    mine_too = tmp_path / "own"
    (mine_too).mkdir()
    (mine_too / "notes.txt").write_bytes(b"kept")
    for _ in range(2):
        assert main(argv + extra + [flag, str(mine_too)]) == 0
    assert (mine_too / "notes.txt").read_bytes() == b"kept"
    assert json.loads((mine_too / MANIFEST).read_text())["kind"] == "hmblur outputs"


def test_a_manifest_that_is_not_hmblurs_makes_the_folder_refused(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / MANIFEST).write_text('{"files": {"../../etc/passwd": [1, 2]}}')
    assert main(["compare", str(BASIC), "--size", "16x10", "--samples", "2", "--modes", "off",
                 "--out", str(out)]) == 2
    one_line_error(capsys, MANIFEST, "move that file away")
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST]


def test_a_viewer_screenshot_takes_only_names_where_nothing_is(tmp_path):
    from viewer.ui.capture import next_path
    (tmp_path / "shot_000.png").write_bytes(b"the user's")
    (tmp_path / "shot_001.json").write_bytes(b"the user's sidecar")
    (tmp_path / "shot_002.png").symlink_to(tmp_path / "nowhere")
    assert next_path(tmp_path, "shot") == tmp_path / "shot_003.png"
