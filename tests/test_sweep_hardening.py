"""The sweep and compare against hostile inputs and endings (issue 39), and the sweep as
Dask is meant (issue 37): sweep --out keeps the user's files (the rule itself:
tests/test_output_folders.py), every path a sweep touches through the loader's asset rule, counts bounded before work, the seed and shutter
under the scene file's limits, damaged cell files redone, a cell key that moves with every
input, a clean Ctrl-C, the worker plugin, scatter and resources.

Families of inputs are property tests with a fixed seed (hypothesis, derandomize)."""
import json
import os
import pickle
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from viewer.commands.main import main, version
from viewer.sweep import run as sweep_run
from viewer.sweep.bundle import Budget, scene_bundle
from viewer.sweep.cells import CellTask, run_cell
from viewer.sweep.spec import load_sweep
from world import limits
from world.errors import UserError

from conftest import CONFORMANCE, ROOT
from sweep_helpers import (in_process, interrupted, one_line_error, own_temp_dir,  # noqa: F401
                           snapshot, sweep)

BASIC = CONFORMANCE / "basic.toml"
PROPS = dict(derandomize=True, deadline=None,
             suppress_health_check=[HealthCheck.function_scoped_fixture,
                                    HealthCheck.too_slow])
ONE = """
    scenes = ["basic.toml"]
    size = "32x18"
    samples = 2
    [variants.m]
    mode = "mcguire"
"""


def sweep_file(folder: Path, text=ONE, name="sweep.toml") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(BASIC, folder / "basic.toml")
    p = folder / name
    p.write_text(textwrap.dedent(text))
    return p


# --- 1. sweep --out keeps the user's files (the rule: tests/test_output_folders.py) ----------

@pytest.mark.parametrize("mine", ["table.csv", "summary.md", "plots/flip_vs_seed.png",
                                  "cells/x.json", "cells"])
def test_sweep_refuses_a_folder_file_of_the_users_and_keeps_it(tmp_path, capsys, mine):
    """A file (or the cells/ folder) of the user's at a name the sweep writes: one line,
    exit 2, before any work, the folder as it was; in a folder of its own the sweep runs,
    is resumed and rerun (its own files replaced)."""
    p = sweep_file(tmp_path / "s", ONE.replace("samples = 2", "samples = 2\nseed = [0, 1]"))
    out = tmp_path / "out"
    (out / mine).parent.mkdir(parents=True, exist_ok=True)
    if mine == "cells":
        (out / "cells").mkdir()
        (out / "cells" / "notes.txt").write_bytes(b"the user's")
    else:
        (out / mine).write_bytes(b"the user's")
    was = snapshot(out)
    assert main(["sweep", str(p), "--out", str(out), "--workers", "0"]) == 2
    one_line_error(capsys, str(out), mine.split("/")[0])
    assert snapshot(out) == was
    own = tmp_path / "own"
    own.mkdir()
    (own / "notes.txt").write_bytes(b"kept")

    def stop_after_one(tasks, bundles, on_result):
        on_result(tasks[0], run_cell(tasks[0], bundles[tasks[0].digest]))
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        sweep(tmp_path, p, own, stop_after_one)
    calls = []
    sweep(tmp_path, p, own, in_process(calls))            # resumed: the other cell
    assert len(calls) == 1
    assert main(["sweep", str(p), "--out", str(own), "--workers", "0"]) == 0
    assert (own / "notes.txt").read_bytes() == b"kept"


def test_a_sweep_removes_only_its_own_plots_that_it_no_longer_makes(tmp_path):
    p = sweep_file(tmp_path, ONE.replace('size = "32x18"', 'size = "32x18"\nshutters = [0.02, 0.04]'))
    out = tmp_path / "out"
    sweep(tmp_path, p, out)
    plots = sorted(f.name for f in (out / "plots").iterdir())
    assert "flip_vs_shutter.png" in plots
    (out / "plots" / "mine.png").write_bytes(b"the user's")
    p.write_text(p.read_text().replace("shutters = [0.02, 0.04]", "shutters = [0.02]"))
    sweep(tmp_path, p, out)
    assert sorted(f.name for f in (out / "plots").iterdir()) == ["mine.png"]


# --- 2. every path a sweep touches: the asset rule, sized, copies removed -------------------

HOSTILE = ["/dev/zero", "/dev/null", "/etc/passwd", "/proc/self/status", "fifo.obj",
           "../outside.obj", "link_out.obj", "folder.obj", "missing.obj", "big.obj",
           "/", "", "a\0b.obj"]


def hostile_scene(folder: Path, where: str, path: str) -> Path:
    """A scene naming `path` at `where`: an object's mesh, its image texture, a glTF
    entry, a glTF buffer's uri, an OBJ's mtllib or its texture map."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder.parent / "outside.obj").write_text("v 0 0 0\n")
    if not os.path.lexists(folder / "fifo.obj"):
        os.mkfifo(folder / "fifo.obj")
        (folder / "link_out.obj").symlink_to(folder.parent / "outside.obj")
        (folder / "folder.obj").mkdir()
        with open(folder / "big.obj", "wb") as f:
            f.truncate(limits.MAX_MESH_BYTES + 1)          # sparse: no disk, no memory
    shutil.copy(ROOT / "scenes/assets/quad_uv.obj", folder / "q.obj")
    head = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y = 45.0\n"
    esc = json.dumps(path)
    if where == "mesh":
        obj = f"[[objects]]\nmesh = {esc}\n"
    elif where == "texture":
        obj = f"[[objects]]\nmesh = \"q.obj\"\nmaterial = {{ texture = {{ kind = \"image\", path = {esc} }} }}\n"
    elif where == "gltf":
        obj = f"[[objects]]\ngltf = {esc}\n"
    elif where == "gltf uri":
        (folder / "a.gltf").write_text(json.dumps({"asset": {"version": "2.0"},
                                                   "buffers": [{"uri": path, "byteLength": 1}]}))
        obj = "[[objects]]\ngltf = \"a.gltf\"\n"
    elif where == "mtllib":
        (folder / "m.obj").write_text(f"mtllib {path}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        obj = "[[objects]]\nmesh = \"m.obj\"\n"
    else:                                               # an OBJ material's texture map
        (folder / "t.mtl").write_text(f"newmtl x\nmap_Kd {path}\n")
        (folder / "t.obj").write_text("mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        obj = "[[objects]]\nmesh = \"t.obj\"\n"
    scene = folder / "scene.toml"
    scene.write_text(head + obj)
    return scene


@settings(max_examples=80, **PROPS)
@given(st.sampled_from(["mesh", "texture", "gltf", "gltf uri", "mtllib", "map"]),
       st.sampled_from(HOSTILE))
def test_a_hostile_asset_path_is_the_scenes_error_found_before_opening(tmp_path_factory,
                                                                      where, path):
    """Devices, FIFOs, system files, paths out of the scene's folder (by .. or a link),
    folders, missing files and files past their size limit, at every place a scene names
    a file: the bundle is the scene's error, in the loader's words (the scene file and
    the key), at once (a FIFO would hang a read, /dev/zero fill the memory), holding no
    bytes. (An OBJ line whose word is empty names no file: that bundle has no error.)"""
    folder = tmp_path_factory.mktemp("hostile") / "scene"
    if "\0" in path and where in ("mtllib", "map"):
        return                                          # (not a word an OBJ line holds)
    scene = hostile_scene(folder, where, path)
    b = scene_bundle(scene)
    names = {rel for rel, _ in b.files}
    assert b.size < 1 << 20                             # nothing big was read
    assert not any(n.endswith(("outside.obj", "passwd", "zero", "null", "status", "fifo.obj",
                               "big.obj")) for n in names), names
    if path == "" and where in ("mtllib", "map"):
        assert b.error is None, b.error
        return
    assert b.error is not None, (where, path, sorted(names))
    assert b.error.startswith(f"{scene}: objects[1]") and b.files == ()
    assert "\n" not in b.error


def test_a_file_swapped_for_a_fifo_after_the_rule_is_refused_by_its_descriptor(tmp_path):
    """Between asset_file's check and the read a file can become a FIFO: the read opens
    it without blocking and checks the descriptor, so it is the scene's error at once."""
    from viewer.sweep.bundle import _read
    os.mkfifo(tmp_path / "swapped.obj")
    with pytest.raises(UserError, match="is not a regular file"):
        _read(tmp_path / "swapped.obj", 1 << 20, Budget("x"), UserError)


def test_a_glob_never_enters_a_symlinked_folder(tmp_path):
    """`**` walks the real folders only: a link back up (a loop) or across is not
    followed, so each scene is found once, by its own path."""
    (tmp_path / "loop/a").mkdir(parents=True)
    (tmp_path / "loop/a/up").symlink_to("..")
    (tmp_path / "loop/a/across").symlink_to(tmp_path / "other")
    (tmp_path / "other").mkdir()
    shutil.copy(BASIC, tmp_path / "other/o.toml")
    shutil.copy(BASIC, tmp_path / "loop/a/s.toml")
    p = sweep_file(tmp_path, ONE.replace('["basic.toml"]', '["loop/**/*.toml"]'))
    assert [sc.label for sc in load_sweep(p).scenes] == ["s"]


def test_the_bytes_of_a_sweeps_scenes_are_bounded_before_they_are_read(tmp_path):
    scene = hostile_scene(tmp_path / "s", "mesh", "q.obj")
    budget = Budget("sweep.toml: scenes", limit=(scene.stat().st_size
                                                 + (tmp_path / "s/q.obj").stat().st_size - 1))
    with pytest.raises(UserError, match="sweep.toml: scenes: the scene files and the files "
                                        "they name come to more than"):
        scene_bundle(scene, budget)


def test_a_hostile_asset_is_an_error_row_no_worker_sees_and_no_copy_is_left(tmp_path, capsys):
    folder = tmp_path / "s"
    hostile_scene(folder, "mesh", "/dev/zero")
    (folder / "scene.toml").rename(folder / "zero.toml")
    hostile_scene(folder, "texture", "fifo.obj")
    p = sweep_file(folder, ONE.replace('["basic.toml"]', '["zero.toml", "scene.toml", "basic.toml"]'))
    calls = []
    facts = sweep(tmp_path, p, tmp_path / "out", in_process(calls))
    assert calls == ["basic"] and facts["failed"] == 2
    rows = pq.read_table(tmp_path / "out/table.parquet").to_pylist()
    errors = sorted(r["error"] for r in rows if r["error"])
    assert "outside the scene file's folder" in errors[1] and "/dev/zero" in errors[1]
    assert "not a regular file" in errors[0] and "fifo.obj" in errors[0]


def test_the_copies_go_when_the_sweep_fails_or_is_interrupted(tmp_path, own_temp_dir):
    p = sweep_file(tmp_path)

    def fails(tasks, bundles, on_result):
        from viewer.sweep.bundle import materialise
        materialise(bundles[tasks[0].digest], tasks[0].run)
        assert any("hmblur" in q.name for q in own_temp_dir.iterdir())
        raise RuntimeError("a worker's failure")

    def interrupted(tasks, bundles, on_result):
        on_result(tasks[0], run_cell(tasks[0], bundles[tasks[0].digest]))
        raise KeyboardInterrupt
    with pytest.raises(RuntimeError):
        sweep(tmp_path, p, tmp_path / "a", fails)
    with pytest.raises(KeyboardInterrupt):
        sweep(tmp_path, p, tmp_path / "b", interrupted)
    # (the fixture checks that no copy is left)


# --- 3, 4. counts bounded before work; seed and shutter under the scene file's rule ------

def _past(limit: int, n: int) -> int:
    """A count past `limit`, from n (up to limit + 1000, so that the file stays small)."""
    return limit + 1 + n % 1000


def _list(values) -> str:
    return "[" + ", ".join(map(repr, values)) + "]"


def _offs(k: int) -> str:
    return "".join(f'[variants.v{i}]\nmode = "off"\n' for i in range(k))


def count_case(kind: str, n: int) -> tuple[str, list]:
    """(sweep file, extra flags) with one count past its limit."""
    scene, size, grid, more = '["basic.toml"]', '"32x18"', "", ""
    variants = '[variants.m]\nmode = "mcguire"\n'
    flags = []
    if kind == "workers":
        flags = ["--workers", str(_past(limits.MAX_LOCAL_WORKERS, n) if n % 3 else 10 ** (6 + n % 40))]
    elif kind == "seeds":
        more = f"seed = {_list(range(_past(limits.MAX_SWEEP_CELLS, n)))}"
    elif kind == "cells":
        k = 101 + n % 50                                # k * k > MAX_SWEEP_CELLS
        more = f"times = {_list([i / 1e3 for i in range(k)])}\nseed = {_list(range(k))}"
    elif kind == "grid":
        variants = ('[variants.g]\nmode = "hybrid"\nset = { "motion.curve_px" = '
                    f"{_list([0.1 + i / 1e4 for i in range(_past(limits.MAX_VARIANTS, n))])} }}\n")
    elif kind == "grid product":
        variants = ('[variants.g]\nmode = "hybrid"\nset = { "hybrid.curve_steps" = [1, 2, 3, 4], '
                    '"hybrid.segments" = [1, 2, 3, 4], "motion.steps" = '
                    f"{_list(range(1, 4 + n % 5))} }}\n")
    elif kind == "variants":
        variants = _offs(_past(limits.MAX_VARIANTS, n) % 100 + limits.MAX_VARIANTS + 1)
    elif kind == "renders":                             # cells x variants
        more = f"seed = {_list(range(limits.MAX_SWEEP_RENDERS // 30 + 1 + n % 100))}"
        variants = _offs(30)
    elif kind == "glob":
        scene = '["/**/*.toml"]' if n % 2 else '["loop/**/x*.toml"]'
    else:                                               # the pixels a cell holds
        size, variants = '"2048x2048"', _offs(6 + n % 20)
    text = (f"scenes = {scene}\nsize = {size}\nsamples = 2\n{more}\n{grid}{variants}")
    return text, flags


@settings(max_examples=36, **PROPS)
@given(st.sampled_from(["workers", "seeds", "cells", "grid", "grid product", "variants",
                        "renders", "glob", "frame"]),
       st.integers(min_value=0, max_value=10 ** 12))
def test_a_count_past_its_limit_is_one_line_before_any_work(tmp_path_factory, capsys, kind, n):
    """--workers, seeds, cells, a grid's values, variants, a grid's product, renders,
    globs that would walk the file system or a symlink loop, the pixels a cell holds: past
    its limit, one line and exit 2, at once, no folder made, nothing rendered."""
    folder = tmp_path_factory.mktemp("counts")
    (folder / "loop" / "a").mkdir(parents=True)
    (folder / "loop/a/up").symlink_to("..")
    out = folder / "out"
    text, flags = count_case(kind, n)
    p = sweep_file(folder, text)
    code = main(["sweep", str(p), "--out", str(out)] + flags)
    err = one_line_error(capsys)
    assert code == 2, (kind, err)
    assert not out.exists()


def test_compare_variants_are_bounded_by_count_and_by_the_pixels_they_hold(tmp_path, capsys):
    many = [a for i in range(limits.MAX_VARIANTS + 1) for a in ("--variant", f"v{i}=off")]
    assert main(["compare", str(BASIC), "--size", "16x10", *many, "--out", str(tmp_path / "a")]) == 2
    one_line_error(capsys, f"more than the {limits.MAX_VARIANTS}")
    assert main(["compare", str(BASIC), "--size", "2048x2048", "--variant", "a=off",
                 "--variant", "b=off", "--variant", "c=off", "--variant", "d=off",
                 "--variant", "e=off", "--variant", "f=off", "--out", str(tmp_path / "b")]) == 2
    one_line_error(capsys, "pixels, more than the")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


SHUTTERS = st.one_of(st.sampled_from([0.0, -0.0, -1e-300, 1e-300, limits.MAX_SHUTTER,
                                      limits.MAX_SHUTTER * (1 + 1e-15), 1e300, -1.0, 0.5]),
                     st.floats(min_value=-1e8, max_value=1e8, allow_nan=False))
SEEDS = st.one_of(st.sampled_from([0, 1, limits.MAX_SEED, limits.MAX_SEED + 1, -1, 2 ** 63]),
                  st.integers(min_value=-2 ** 40, max_value=2 ** 40))


@settings(max_examples=60, **PROPS)
@given(SHUTTERS, SEEDS)
def test_the_sweeps_seed_and_shutter_follow_the_rule_of_seed_and_scene_files(tmp_path_factory,
                                                                            shutter, seed):
    """A shutter the scene file's camera.shutter takes is one --shutter and a sweep's
    shutters take, and no other; a seed --seed takes is one a sweep's seed takes."""
    from viewer.cli.args import parse_seed, parse_shutter
    from world.loader import load_scene
    folder = tmp_path_factory.mktemp("rule")
    scene = folder / "s.toml"
    scene.write_text(BASIC.read_text().replace("shutter = 0.05", f"shutter = {shutter!r}"))

    def takes(fn) -> bool:
        try:
            fn()
            return True
        except UserError:
            return False
    by_scene = takes(lambda: load_scene(scene))
    by_flag = takes(lambda: parse_shutter("--shutter", repr(shutter)))
    shutter_file = sweep_file(folder, ONE.replace("samples = 2",
                                                  f"samples = 2\n    shutters = [{shutter!r}]"),
                              "a.toml")
    by_sweep = takes(lambda: load_sweep(shutter_file))
    assert by_scene == by_flag == by_sweep, (shutter, by_scene, by_flag, by_sweep)
    seed_file = folder / "b.toml"
    seed_file.write_text(textwrap.dedent(ONE).replace("samples = 2", f"samples = 2\nseed = {seed}"))
    assert takes(lambda: parse_seed("--seed", str(seed))) == takes(lambda: load_sweep(seed_file))


def test_compare_shutter_past_the_limit_is_one_line(tmp_path, capsys):
    assert main(["compare", str(BASIC), "--size", "16x10", "--shutter", "1e300",
                 "--out", str(tmp_path / "c")]) == 2
    one_line_error(capsys, "--shutter", f"from 0 to {limits.MAX_SHUTTER:g}")


# --- 5. damaged cell files are redone; out of memory is one line ---------------------------

def _damage(kind: str, path: Path, rng: int):
    text = path.read_text()
    doc = json.loads(text)
    if kind == "truncated":
        path.write_text(text[:rng % max(1, len(text) - 1)])
    elif kind == "not json":
        path.write_bytes(b"\xff\xfe not json")
    elif kind == "a field missing":
        doc.pop(sorted(sweep_run._CELL_FIELDS)[rng % len(sweep_run._CELL_FIELDS)])
        path.write_text(json.dumps(doc))
    elif kind == "a field of another type":
        k = sorted(sweep_run._CELL_FIELDS)[rng % len(sweep_run._CELL_FIELDS)]
        doc[k] = [{"x": 1}] if not isinstance(doc[k], list) else "text"
        path.write_text(json.dumps(doc))
    elif kind == "a row's field missing":
        row = doc["rows"][rng % len(doc["rows"])]
        row.pop(sorted(sweep_run._ROW_FIELDS)[rng % len(sweep_run._ROW_FIELDS)])
        path.write_text(json.dumps(doc))
    elif kind == "a variant's rows missing":
        doc["rows"] = [r for r in doc["rows"] if r["variant"] != "m"]
        path.write_text(json.dumps(doc))
    elif kind == "another cell's key":
        doc["key"] = "0" * 32
        path.write_text(json.dumps(doc))
    elif kind == "deep":
        path.write_text("[" * 100_000)
    elif kind == "huge":
        with open(path, "ab") as f:
            f.truncate(limits.MAX_CELL_FILE_BYTES + 1)
    elif kind == "a link":
        other = path.with_suffix(".real")
        path.rename(other)
        path.symlink_to(other.name)
    else:
        path.write_text("null")


# Each kind is a case of its own (drawn from the list, hypothesis need not reach them all);
# hypothesis draws where a kind cuts the file or which field it drops.
DAMAGE = ["truncated", "not json", "a field missing", "a field of another type",
          "a row's field missing", "a variant's rows missing", "another cell's key", "deep",
          "huge", "a link", "null"]


@pytest.mark.parametrize("kind", DAMAGE)
@settings(max_examples=2, **PROPS)
@given(st.integers(min_value=0, max_value=10 ** 6))
def test_a_damaged_cell_file_is_run_again(tmp_path_factory, kind, rng):
    tmp = tmp_path_factory.mktemp("damaged")
    p = sweep_file(tmp)
    out = tmp / "out"
    sweep(tmp, p, out)
    table = (out / "table.csv").read_bytes()
    cell = next((out / "cells").glob("*.json"))
    _damage(kind, cell, rng)
    calls = []
    facts = sweep(tmp, p, out, in_process(calls))
    assert calls == ["basic"] and facts["failed"] == 0, kind
    assert (out / "table.csv").read_bytes() == table
    assert json.loads(cell.read_text())["key"] == cell.stem


@pytest.mark.parametrize("field", sorted(sweep_run._CELL_FIELDS) + [
    f"rows.{k}" for k in sorted(sweep_run._ROW_FIELDS)])
def test_a_cell_file_lacking_a_field_or_with_one_of_another_type_is_run_again(tmp_path, field):
    p = sweep_file(tmp_path)
    out = tmp_path / "out"
    sweep(tmp_path, p, out)
    cell = next((out / "cells").glob("*.json"))
    good = json.loads(cell.read_text())
    for damage in ("missing", "another type"):
        doc = json.loads(json.dumps(good))
        where, _, k = field.rpartition(".")
        target = doc["rows"][-1] if where else doc
        if damage == "missing":
            target.pop(k)
        else:
            target[k] = {"a": "table"}
        cell.write_text(json.dumps(doc))
        calls = []
        sweep(tmp_path, p, out, in_process(calls))
        assert calls == ["basic"], (field, damage)
        assert json.loads(cell.read_text())["key"] == cell.stem


def test_out_of_memory_anywhere_in_a_command_is_one_line(tmp_path, capsys, monkeypatch):
    from viewer.sweep import spec
    monkeypatch.setattr(spec, "load_sweep", lambda *a: (_ for _ in ()).throw(MemoryError()))
    assert main(["sweep", str(sweep_file(tmp_path)), "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "out of memory")


# --- 6. Ctrl-C after the last cell ------------------------------------------------------

def test_ctrl_c_at_a_terminal_after_the_last_cell_is_one_line_and_no_table(tmp_path,
                                                                          own_temp_dir):
    """SIGINT to the whole process group (what a terminal's Ctrl-C does) once every cell
    file is written and before the table: the workers stay quiet, one line says what was
    kept, no table and no copy is left; the same command then writes the table."""
    p = sweep_file(tmp_path, ONE.replace("samples = 2", "samples = 2\nseed = [0, 1]"))
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(own_temp_dir))
    argv = [sys.executable, "-m", "viewer", "sweep", str(p), "--out", str(out), "--workers", "1"]

    def all_cells_written(_pid):
        cells = list((out / "cells").glob("*.json")) if (out / "cells").is_dir() else []
        return len(cells) == 2 and not (out / "table.csv").exists()

    code, err, sent = interrupted(argv, env, ROOT, all_cells_written)
    assert sent, err
    lines = [ln for ln in err.splitlines() if not ln.startswith("sweep: ")]
    assert code == 130, err
    assert lines == [f"hmblur: interrupted; all 2 cells kept in {out / 'cells'}; run the same "
                     "command again to write the table from them"], err
    assert not (out / "table.csv").exists()
    done = subprocess.run(argv[:-2] + ["--workers", "0"], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and (out / "table.csv").is_file(), done.stderr
    assert "cells run now: 0" in (out / "summary.md").read_text()


def _worker_pids(main_pid: int) -> list[int]:
    """The Dask worker processes a sweep started (spawned children running spawn_main)."""
    out = []
    for pid in os.listdir("/proc"):
        try:
            with open(f"/proc/{pid}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read()
        except (OSError, ValueError, IndexError):
            continue
        if ppid == main_pid and b"spawn_main" in cmd:
            out.append(int(pid))
    return out


@pytest.mark.parametrize("when", ["workers starting", "a worker restarted"])
def test_ctrl_c_at_a_terminal_while_workers_start_or_restart_prints_no_traceback(
        tmp_path, own_temp_dir, when):
    """Ctrl-C to the process group while the local worker is still starting (it ignores
    SIGINT from its first instruction, inherited), or after a worker was killed and
    restarted by its nanny (the plugin makes the new one ignore it too; the scene it held,
    lost with it, is scattered again and the cells run): one line, no Dask traceback."""
    p = sweep_file(tmp_path, ONE.replace("samples = 2", "samples = 2\nseed = [0, 1, 2, 3, 4, 5]"))
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(own_temp_dir))
    argv = [sys.executable, "-m", "viewer", "sweep", str(p), "--out", str(out), "--workers", "1"]
    killed, at_kill = None, 0

    def ready(pid):
        nonlocal killed, at_kill
        workers = _worker_pids(pid)
        cells = len(list((out / "cells").glob("*.json"))) if (out / "cells").is_dir() else 0
        if when == "workers starting" and workers:
            # (in its imports: past the interpreter's start, which dies of a SIGINT
            # quietly, and before the plugin)
            time.sleep(0.4)
            return True
        if when == "a worker restarted":
            if killed is None and cells >= 1 and workers:
                killed, at_kill = workers[0], cells
                os.kill(killed, signal.SIGKILL)
            elif killed is not None and workers and killed not in workers:
                return cells >= at_kill + 2        # (the new worker has run a cell)
        return False

    code, err, sent = interrupted(argv, env, ROOT, ready)
    assert sent, err
    assert code == 130 and "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if not ln.startswith("sweep: ")]
    assert len(lines) == 1 and lines[0].startswith("hmblur: interrupted; "), err
    if when == "a worker restarted":       # (its scene, lost with it, scattered again)
        cells = [json.loads(f.read_text()) for f in (out / "cells").glob("*.json")]
        assert len(cells) >= 2 and all(c["error"] is None for c in cells), cells


# --- 7. the cell key moves with everything a cell's numbers depend on ------------------

def _task(spec_text: str, folder: Path, version_="1.0") -> CellTask:
    p = sweep_file(folder, spec_text)
    tasks, _ = sweep_run.tasks_of(load_sweep(p), version_, False, False, "key")
    return tasks[0]


def test_the_cell_key_changes_with_each_thing_it_depends_on(tmp_path):
    base = _task(ONE, tmp_path / "a")
    assert _task(ONE, tmp_path / "a2").key == base.key          # same inputs, same key
    variants = {
        "seed": ONE.replace("samples = 2", "samples = 2\nseed = 1"),
        "time": ONE.replace("samples = 2", "samples = 2\ntimes = [0.01]"),
        "shutter": ONE.replace("samples = 2", "samples = 2\nshutters = [0.07]"),
        "size": ONE.replace('"32x18"', '"32x20"'),
        "samples": ONE.replace("samples = 2", "samples = 3"),
        "common set": ONE.replace("samples = 2", "samples = 2\nset = { \"motion.curve_px\" = 0.7 }"),
        "variant's mode": ONE.replace('mode = "mcguire"', 'mode = "ue4"'),
        "variant's name": ONE.replace("[variants.m]", "[variants.n]"),
        "variant's value": ONE.replace('mode = "mcguire"',
                                       'mode = "mcguire"\nset = { "mcguire.samples" = 9 }'),
        "a grid's value": ONE.replace('mode = "mcguire"',
                                      'mode = "mcguire"\nset = { "mcguire.samples" = [9] }'),
    }
    keys = {name: _task(text, tmp_path / name.replace(" ", "_")).key
            for name, text in variants.items()}
    keys["version"] = _task(ONE, tmp_path / "v", version_="1.1").key
    folder = tmp_path / "edited"
    sweep_file(folder)
    (folder / "basic.toml").write_text((folder / "basic.toml").read_text() + "\n# edited\n")
    keys["scene file's bytes"] = sweep_run.tasks_of(
        load_sweep(folder / "sweep.toml"), "1.0", False, False, "key")[0][0].key
    asset = tmp_path / "asset"
    scene = hostile_scene(asset, "mesh", "q.obj")
    sweep_file(asset, ONE.replace("basic.toml", "scene.toml"))
    k1 = sweep_run.tasks_of(load_sweep(asset / "sweep.toml"), "1.0", False, False, "key")[0][0].key
    with open(asset / "q.obj", "a") as f:
        f.write("\n# an asset edited\n")
    keys["an asset's bytes"] = sweep_run.tasks_of(
        load_sweep(asset / "sweep.toml"), "1.0", False, False, "key")[0][0].key
    assert keys["an asset's bytes"] != k1
    keys["scene's label"] = sweep_run.tasks_of(
        load_sweep(_two_copies(tmp_path / "copies")), "1.0", False, False, "key")[0][1].key
    for name, key in keys.items():
        assert key != base.key, name
    assert len(set(keys.values())) == len(keys)


def _two_copies(folder: Path) -> Path:
    """A sweep of two copies of basic.toml, a/ and b/: one bundle, two labels."""
    for sub in ("a", "b"):
        (folder / sub).mkdir(parents=True)
        shutil.copy(BASIC, folder / sub / "basic.toml")
    return sweep_file(folder, ONE.replace('["basic.toml"]', '["a/basic.toml", "b/basic.toml"]'))


def test_two_copies_of_a_scene_are_two_cells_each_with_its_label(tmp_path):
    """Two scene files of the same bytes share a bundle but not a cell: both run, each
    row under its own label; a rerun runs neither."""
    p = _two_copies(tmp_path / "s")
    tasks, bundles = sweep_run.tasks_of(load_sweep(p), version(), False, False, "copies")
    assert len(bundles) == 1 and tasks[0].digest == tasks[1].digest
    calls = []
    sweep(tmp_path, p, tmp_path / "out", in_process(calls))
    assert calls == ["a/basic.toml", "b/basic.toml"]
    rows = pq.read_table(tmp_path / "out/table.parquet").to_pylist()
    assert sorted({r["scene"] for r in rows}) == ["a/basic.toml", "b/basic.toml"]
    calls.clear()
    sweep(tmp_path, p, tmp_path / "out", in_process(calls))
    assert calls == []


@pytest.mark.parametrize("first, then", [({}, {"timing": True}), ({}, {"images": True})])
def test_a_resumed_sweep_redoes_cells_that_lack_what_it_asks_for(tmp_path, first, then):
    """Cells run without --timing (or --images) are run again when the sweep is resumed
    with it; resumed once more, none is; an image file lost: its cell again."""
    p = sweep_file(tmp_path, ONE.replace("samples = 2", "samples = 2\nseed = [0, 1]"))
    out = tmp_path / "out"
    sweep(tmp_path, p, out, **first)
    calls = []
    sweep(tmp_path, p, out, in_process(calls), **then)
    assert sorted(calls) == ["basic", "basic"]
    calls.clear()
    sweep(tmp_path, p, out, in_process(calls), **then)
    assert calls == []
    if then.get("images"):
        cell = json.loads(next((out / "cells").glob("*.json")).read_text())
        (out / cell["image_files"][0]).unlink()
        sweep(tmp_path, p, out, in_process(calls), **then)
        assert calls == ["basic"]
    else:
        rows = pq.read_table(out / "table.parquet").to_pylist()
        assert all(r["frame_ms"] > 0 for r in rows)


# --- 8. the sweep as Dask is meant --------------------------------------------------------

def test_a_task_carries_no_scene_bytes_and_each_bundle_is_scattered_once(tmp_path, monkeypatch):
    """The cells name their scene by its digest; a LocalCluster run scatters each scene's
    bundle once (not once per cell); each worker's GL context is made by the plugin when
    it joins and released when the sweep ends; the table is the in-process one."""
    import distributed
    folder = tmp_path / "s"
    big = hostile_scene(folder, "mesh", "q.obj")
    with open(folder / "q.obj", "a") as f:
        f.write("# " + "x" * (1 << 20) + "\n")                # a 1 MB asset
    p = sweep_file(folder, ONE.replace('["basic.toml"]', f'["basic.toml", "{big.name}"]')
                   .replace("samples = 2", "samples = 2\nseed = [0, 1, 2]"))
    tasks, bundles = sweep_run.tasks_of(load_sweep(p), version(), False, False, "pickle")
    assert max(len(pickle.dumps(t)) for t in tasks) < 20_000
    assert max(b.size for b in bundles.values()) > 1 << 20
    scattered = []
    real_scatter = distributed.Client.scatter

    def counting(self, data, *a, **kw):
        scattered.append(data.digest)
        return real_scatter(self, data, *a, **kw)
    monkeypatch.setattr(distributed.Client, "scatter", counting)
    sweep(tmp_path, p, tmp_path / "here")
    facts = sweep_run.run_sweep(load_sweep(p), tmp_path / "dask", version(), 1, None, False,
                                False, stream=open(tmp_path / "progress.txt", "a"))
    assert sorted(scattered) == sorted(bundles) and facts["failed"] == 0
    assert len(facts["ran"]) == 6
    assert (tmp_path / "dask/table.csv").read_bytes() == (tmp_path / "here/table.csv").read_bytes()


def test_timed_cells_ask_for_the_timer_that_the_local_worker_declares(tmp_path, monkeypatch,
                                                                   capsys):
    """--timing: every cell's task asks for the resource `timer`; the local cluster's one
    worker declares it (so the cells run, one at a time); --timing with two local
    workers is one line."""
    import distributed
    asked = []
    real_submit = distributed.Client.submit

    def recording(self, fn, *a, **kw):
        asked.append(kw.get("resources"))
        return real_submit(self, fn, *a, **kw)
    monkeypatch.setattr(distributed.Client, "submit", recording)
    p = sweep_file(tmp_path, ONE.replace("samples = 2", "samples = 2\nseed = [0, 1]"))
    facts = sweep_run.run_sweep(load_sweep(p), tmp_path / "out", version(), 1, None, False,
                                True, stream=open(tmp_path / "progress.txt", "a"))
    assert facts["failed"] == 0 and asked == [{"timer": 1}] * 2
    assert all(r["frame_ms"] > 0 for r in pq.read_table(tmp_path / "out/table.parquet").to_pylist())
    # (refused before any worker starts: checked on a one-core machine too)
    monkeypatch.setattr(limits, "MAX_LOCAL_WORKERS", max(2, limits.MAX_LOCAL_WORKERS))
    assert main(["sweep", str(p), "--out", str(tmp_path / "o2"), "--timing",
                 "--workers", "2"]) == 2
    one_line_error(capsys, "--timing with --workers 2")
    assert not (tmp_path / "o2").exists()


def test_the_worker_plugin_makes_the_context_once_and_releases_it(tmp_path):
    from dask.distributed import Client, LocalCluster
    from viewer.sweep.bundle import copies_folder, materialise
    from viewer.sweep.cells import gl_is_open
    from viewer.sweep.plugin import SweepWorker
    bundle = scene_bundle(BASIC)
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        assert client.submit(gl_is_open, pure=False).result() is False
        plugin = SweepWorker("plug")
        client.register_plugin(plugin)
        # made when the plugin came, in the thread the cells run in, before any cell
        assert client.submit(gl_is_open, pure=False).result() is True
        made = client.submit(lambda: str(materialise(bundle, "plug")), pure=False).result()
        assert Path(made).is_file()
        client.unregister_worker_plugin(plugin.name)
        assert client.submit(gl_is_open, pure=False).result() is False
        assert not copies_folder("plug").exists()


def _dask_bin(name: str) -> str:
    return str(Path(sys.executable).with_name(name))


def test_a_scheduler_and_a_worker_started_by_hand_get_the_plugin_and_the_resource(
        tmp_path, capsys, own_temp_dir):
    """`dask scheduler` + `dask worker` by hand: a worker without the resource `timer` is
    refused for --timing in one line; the sweep runs on it (the plugin registered through
    the client reaches it: the context released and the copies gone after) and gives the
    in-process table."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), TMPDIR=str(own_temp_dir))
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([_dask_bin("dask"), "scheduler", "--port", "0",
                               "--dashboard-address", ":0", "--scheduler-file", str(sched_file)],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        t_end = time.monotonic() + 60
        while not sched_file.exists() and time.monotonic() < t_end:
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen([_dask_bin("dask"), "worker", address, "--nthreads", "1",
                                       "--nworkers", "1", "--no-dashboard"],
                                      env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL))
        p = sweep_file(tmp_path)
        assert main(["sweep", str(p), "--out", str(tmp_path / "t"), "--scheduler", address,
                     "--timing"]) == 2
        one_line_error(capsys, "--timing", "resource timer")
        assert main(["sweep", str(p), "--out", str(tmp_path / "d"), "--scheduler", address]) == 0
        sweep(tmp_path, p, tmp_path / "here")
        assert (tmp_path / "d/table.csv").read_bytes() == (tmp_path / "here/table.csv").read_bytes()
        assert f"dask scheduler {address}, 1 worker" in (tmp_path / "d/summary.md").read_text()
        from dask.distributed import Client
        from viewer.sweep.cells import gl_is_open
        with Client(address) as client:
            assert client.submit(gl_is_open, pure=False).result() is False
            assert not any(n.startswith("hmblur-sweep") for plugins in
                           client.run(lambda dask_worker: list(dask_worker.plugins)).values()
                           for n in plugins)
    finally:
        for proc in reversed(procs):
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
