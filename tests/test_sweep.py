"""`hmblur sweep` and compare's variants on a tiny grid (2 scenes x 2 variants at 32x18,
4 reference sub-frames): sweep-file checks, grid expansion, compare's numbers for a cell,
resumption, failed cells, the table's files, scene bundles and one real Dask cluster."""
import json
import shutil
import textwrap

import pyarrow.parquet as pq
import pytest

from viewer.commands.main import main, version
from viewer.sweep import run as sweep_run
from viewer.sweep.bundle import materialise, remove_copies, scene_bundle
from viewer.sweep.cells import run_cell
from viewer.sweep.spec import load_sweep

from conftest import CONFORMANCE, ROOT
from sweep_helpers import in_process, own_temp_dir, sweep  # noqa: F401 (a fixture)

BASIC = str(CONFORMANCE / "basic.toml")
TINY = """
    scenes = ["living_room", "basic.toml"]
    shutters = [0.06]
    size = "32x18"
    samples = 4

    [variants.mcguire]
    mode = "mcguire"

    [variants.fast]
    mode = "hybrid"
    set = { "hybrid.curve_steps" = 1, "motion.curve_px" = 0.5 }
"""


def sweep_file(tmp_path, text=TINY, name="sweep.toml"):
    shutil.copy(BASIC, tmp_path / "basic.toml")
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


# --- the sweep file --------------------------------------------------------------------------

@pytest.mark.parametrize("text, key, words", [
    ("scenes = ['living_room']\nfoo = 1\n[variants.a]\nmode = 'off'\n", "foo", "unknown key"),
    ("[variants.a]\nmode = 'off'\n", "scenes", "required"),
    ("scenes = ['living_room']\n", "variants", "required"),
    ("scenes = []\n[variants.a]\nmode = 'off'\n", "scenes", "at least one"),
    ("scenes = ['nope']\n[variants.a]\nmode = 'off'\n", "scenes[1]", "no such scene"),
    ("scenes = ['*.obj']\n[variants.a]\nmode = 'off'\n", "scenes[1]", "matches no file"),
    ("scenes = ['living_room', 'living_room']\n[variants.a]\nmode = 'off'\n", "scenes[2]",
     "listed twice"),
    ("scenes = ['living_room']\ntimes = [0.0, 0.0]\n[variants.a]\nmode = 'off'\n",
     "times[2]", "listed twice"),
    ("scenes = ['living_room']\nshutters = [-1]\n[variants.a]\nmode = 'off'\n", "shutters[1]",
     "from 0 to 1e+07 s"),
    ("scenes = ['living_room']\nsize = '32by18'\n[variants.a]\nmode = 'off'\n", "size", "WxH"),
    ("scenes = ['living_room']\nsamples = 0\n[variants.a]\nmode = 'off'\n", "samples",
     "integer >= 1"),
    ("scenes = ['living_room']\n[variants.a]\nmode = 'hybird'\n", "variants.a", "hybird"),
    ("scenes = ['living_room']\n[variants.a]\nmode = 'hybrid'\ncolour = 1\n",
     "variants.a.colour", "unknown key"),
    ("scenes = ['living_room']\n[variants.a]\nmode = 'mcguire'\nset = { 'hybrid.curve_steps' = 1 }\n",
     "variants.a", "does not use the hybrid"),
    ("scenes = ['living_room']\n[variants.a]\nmode = 'hybrid'\nset = { 'hybrid.curve_steps' = [1, 99] }\n",
     "variants.a.set", "hybrid.curve_steps"),
    ("scenes = ['living_room']\n[variants.a]\nmode = 'hybrid'\nset = { 'hybrid.curve_steps' = [] }\n",
     "variants.a.set.hybrid.curve_steps", "at least one"),
    ("scenes = ['living_room']\nset = { 'ue4.tile' = 8 }\n[variants.a]\nmode = 'off'\n",
     "set.ue4.tile", "no variant's mode uses"),
    ("scenes = ['living_room'\n", "", "not TOML"),
])
def test_sweep_file_mistakes_are_one_line_naming_file_and_key(tmp_path, capsys, text, key, words):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    assert main(["sweep", str(p), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"hmblur: error: {p}: {key}") and words in err, err
    assert not (tmp_path / "out").exists()


def test_grids_expand_to_every_combination_named_by_their_values(tmp_path):
    p = sweep_file(tmp_path, """
        scenes = ["basic.toml", "living_room"]
        times = [0.0, 0.01]
        size = ["32x18", "64x36"]
        [variants.ue4]
        mode = "ue4"
        [variants.hyb]
        mode = "hybrid"
        set = { "hybrid.curve_steps" = [1, 2], "motion.curve_px" = 0.5, "hybrid.segments" = [1, 4] }
    """)
    s = load_sweep(p)
    assert [v.name for v in s.variants] == [
        "ue4", "hyb[curve_steps=1,segments=1]", "hyb[curve_steps=1,segments=4]",
        "hyb[curve_steps=2,segments=1]", "hyb[curve_steps=2,segments=4]"]
    assert s.variants[2].sets == {"motion.curve_px": 0.5, "hybrid.curve_steps": 1,
                                  "hybrid.segments": 4}
    assert [sc.label for sc in s.scenes] == ["basic", "living_room"]
    cells = s.cells()
    assert len(cells) == 2 * 2 * 1 * 2 * 1 * 1
    assert {(c[1], c[3]) for c in cells} == {(t, z) for t in (0.0, 0.01)
                                             for z in ((32, 18), (64, 36))}
    assert s.swept() == ["time", "size"]
    assert s.grid_keys() == ["hybrid.curve_steps", "hybrid.segments"]


# --- cells: compare's numbers, resumption, failures, files ------------------------------

def test_a_cell_has_compares_numbers_and_a_rerun_renders_nothing_twice(tmp_path, monkeypatch):
    """The sweep's rows for a cell equal `hmblur compare` of that cell exactly (the same
    function), even with another cell rendered first on the same worker's renderer; a
    rerun renders nothing, and after one cell file is lost only that cell again."""
    from viewer.render.renderer import Renderer
    renders = []
    real = Renderer.render

    def counting(self, mode, *a, **kw):
        renders.append(mode)
        return real(self, mode, *a, **kw)
    monkeypatch.setattr(Renderer, "render", counting)
    p = sweep_file(tmp_path)
    out = tmp_path / "out"
    calls = []
    facts = sweep(tmp_path, p, out, in_process(calls))
    assert facts["failed"] == 0 and calls == ["living_room", "basic"]
    # per cell: the reference once, shared by the variants, then each variant once
    assert renders == ["reference", "mcguire", "hybrid"] * 2
    rows = list(pq.read_table(out / "table.parquet").to_pylist())
    assert len(rows) == 2 * 2 * 4

    cmp_out = tmp_path / "cmp"
    assert main(["compare", BASIC, "--size", "32x18", "--samples", "4", "--shutter", "0.06",
                 "--modes", "mcguire", "--variant",
                 "fast=hybrid:hybrid.curve_steps=1,motion.curve_px=0.5",
                 "--out", str(cmp_out)]) == 0
    m = json.loads((cmp_out / "metrics.json").read_text())
    mine = [r for r in rows if r["scene"] == "basic"]
    assert len(mine) == 8
    for r in mine:
        want = m["metrics"][r["variant"]][r["region"]]
        for key in ("flip", "psnr", "ssim", "pixels"):
            assert r[key] == (float(want[key]) if want[key] == "inf" else want[key]), (r, key)
    assert {r["time"] for r in mine} == {m["time"]} and {r["shutter"] for r in mine} == {0.06}

    table = (out / "table.csv").read_bytes()
    renders.clear()
    calls.clear()
    assert sweep(tmp_path, p, out, in_process(calls))["ran"] == []
    assert renders == [] and calls == []
    cell_files = sorted((out / "cells").iterdir())
    assert len(cell_files) == 2
    living = next(f for f in cell_files if json.loads(f.read_text())["scene"] == "living_room")
    living.unlink()
    sweep(tmp_path, p, out, in_process(calls))
    assert calls == ["living_room"] and renders == ["reference", "mcguire", "hybrid"]
    assert (out / "table.csv").read_bytes() == table        # the same rows, none twice


def test_a_bad_scene_is_one_error_row_and_the_others_complete(tmp_path):
    (tmp_path / "broken.toml").write_text("[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n"
                                          "fov_y = 45.0\n[[objects]]\nmesh = 'missing.obj'\n")
    p = sweep_file(tmp_path, TINY.replace('"basic.toml"', '"broken.toml", "basic.toml"'))
    out = tmp_path / "out"
    facts = sweep(tmp_path, p, out)
    assert facts["failed"] == 1 and facts["total"] == 3
    rows = pq.read_table(out / "table.parquet").to_pylist()
    bad = [r for r in rows if r["scene"] == "broken"]
    assert len(bad) == 1 and bad[0]["variant"] is None and bad[0]["flip"] is None
    # the scene file as the user knows it, not the worker's copy
    assert bad[0]["error"].startswith(f"{tmp_path / 'broken.toml'}: objects[1]")
    assert "mesh file not found" in bad[0]["error"]
    assert {r["scene"] for r in rows if r["error"] is None} == {"living_room", "basic"}
    assert len([r for r in rows if r["error"] is None]) == 16
    assert "broken" in (out / "summary.md").read_text()
    # a failed cell is tried again on the next run, the finished ones are not; a scene
    # whose file is missing fails where it is bundled, and no worker receives it
    calls = []
    again = sweep(tmp_path, p, out, in_process(calls))
    assert [c["scene"] for c in again["ran"]] == ["broken"] and calls == []


def test_table_columns_csv_and_parquet_agree_plots_and_images(tmp_path):
    p = sweep_file(tmp_path, TINY.replace("shutters = [0.06]", "shutters = [0.02, 0.06]")
                   .replace('"living_room", ', ""))
    out = tmp_path / "out"
    sweep(tmp_path, p, out, images=True, timing=True)
    t = pq.read_table(out / "table.parquet")
    assert t.column_names == ["scene", "time", "shutter", "size", "width", "height", "samples",
                              "seed", "variant", "mode", "hybrid.curve_steps",
                              "motion.curve_px", "region", "pixels", "flip", "psnr", "ssim",
                              "frame_ms", "error", "cell"]
    assert str(t.schema.field("flip").type) == "double" and str(t.schema.field("width").type) == "int64"
    rows = t.to_pylist()
    assert len(rows) == 2 * 2 * 4
    assert all(r["frame_ms"] > 0 for r in rows)
    lines = (out / "table.csv").read_text().splitlines()
    assert lines[0].split(",") == t.column_names and len(lines) == 1 + len(rows)
    first = dict(zip(lines[0].split(","), lines[1].split(",")))
    assert float(first["flip"]) == rows[0]["flip"] and first["variant"] == rows[0]["variant"]
    plots = {f.name for f in (out / "plots").iterdir()}
    assert {"flip_vs_shutter.png", "psnr_vs_shutter.png", "frame_ms_vs_shutter.png"} <= plots
    cell = json.loads(next((out / "cells").iterdir()).read_text())
    assert {f.rsplit("/", 1)[1] for f in cell["image_files"]} == {
        "mcguire.png", "fast.png", "reference.png", "regions.png", "strip.png"}
    assert all((out / f).is_file() for f in cell["image_files"])
    # without --timing the table is the same cells' numbers, and byte for byte repeatable
    sweep(tmp_path, p, tmp_path / "o2")
    sweep(tmp_path, p, tmp_path / "o3")
    assert (tmp_path / "o2/table.csv").read_bytes() == (tmp_path / "o3/table.csv").read_bytes()
    assert [r["flip"] for r in pq.read_table(tmp_path / "o2/table.parquet").to_pylist()] == \
        [r["flip"] for r in rows]


def test_an_interrupted_sweep_leaves_whole_cells_and_continues(tmp_path, capsys):
    p = sweep_file(tmp_path)
    out = tmp_path / "out"

    def stop_after_one(tasks, bundles, on_result):
        on_result(tasks[0], run_cell(tasks[0], bundles[tasks[0].digest]))
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        sweep(tmp_path, p, out, stop_after_one)
    left = sorted(str(f.relative_to(out)) for f in out.rglob("*") if f.is_file())
    # one whole cell (and hmblur's list of its files), no temp
    assert len(left) == 2 and left[0] == ".hmblur-outputs.json" and left[1].startswith("cells/")
    assert not (out / "table.csv").exists()
    calls = []
    sweep(tmp_path, p, out, in_process(calls))
    assert calls == ["basic"]
    assert len(pq.read_table(out / "table.parquet")) == 16


# --- scene bundles --------------------------------------------------------------------------

def test_a_scene_travels_with_its_meshes_images_and_gltf_files(tmp_path):
    """Every file a scene names (and those its OBJ and glTF files name), rebuilt in a
    folder of their own, loads to the same scene; a glTF entry brings its .bin and images
    by their uris, a .glb its JSON chunk's."""
    import struct
    src = tmp_path / "proj"
    (src / "assets").mkdir(parents=True)
    shutil.copy(ROOT / "scenes/assets/quad_uv.obj", src / "assets/quad.obj")
    shutil.copy(ROOT / "scenes/assets/painting.png", src / "assets/p.png")
    with open(src / "assets/quad.obj", "a") as f:
        f.write("mtllib quad.mtl\n")
    (src / "assets/quad.mtl").write_text("newmtl m\nmap_Kd -s 1 1 1 tex.png\n")
    (src / "assets/tex.png").write_bytes(b"png")
    (src / "assets/box.gltf").write_text(json.dumps({
        "asset": {"version": "2.0"}, "buffers": [{"uri": "box%20data.bin", "byteLength": 3}],
        "images": [{"uri": "data:image/png;base64,AAAA"}, {"uri": "wood.png"}]}))
    (src / "assets/box data.bin").write_bytes(b"bin")
    (src / "assets/wood.png").write_bytes(b"wood")
    chunk = json.dumps({"buffers": [{"uri": "glb.bin"}]}).encode()
    (src / "assets/b.glb").write_bytes(b"glTF" + struct.pack("<II", 2, 0)
                                       + struct.pack("<I4s", len(chunk), b"JSON") + chunk)
    (src / "assets/glb.bin").write_bytes(b"x")
    (src / "assets/unrelated.png").write_bytes(b"not named by the scene")
    scene = src / "room.toml"
    scene.write_text(textwrap.dedent("""
        [camera]
        position = [0.0, 0.0, 3.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 45.0
        [[objects]]
        mesh = "assets/quad.obj"
        material = { texture = { kind = "image", path = "assets/p.png" } }
        [[objects]]
        gltf = "assets/box.gltf"
        [[objects]]
        gltf = "assets/b.glb"
    """))
    b = scene_bundle(scene)
    assert b.entry == "room.toml" and b.origin == str(src) and b.error is None
    assert [rel for rel, _ in b.files] == sorted([
        "room.toml", "assets/quad.obj", "assets/quad.mtl", "assets/tex.png",
        "assets/p.png", "assets/box.gltf", "assets/box data.bin", "assets/wood.png",
        "assets/b.glb", "assets/glb.bin"])
    assert [rel for rel, _ in scene_bundle(src / "assets/box.gltf").files] == [
        "box data.bin", "box.gltf", "wood.png"]            # a bare glTF as the scene
    copy = materialise(b, "t1")
    assert copy.read_bytes() == scene.read_bytes()
    assert (copy.parent / "assets/box data.bin").read_bytes() == b"bin"
    assert scene_bundle(scene).digest == b.digest
    (src / "assets/wood.png").write_bytes(b"other wood")
    assert scene_bundle(scene).digest != b.digest          # an asset's bytes are in the key

    # a built-in scene with an OBJ and an image loads from its copy as from its file
    from world.loader import builtin_scene_path, load_scene
    b = scene_bundle(builtin_scene_path("living_room"))
    a, c = load_scene(builtin_scene_path("living_room")), load_scene(materialise(b, "t1"))
    assert [o.name for o in a.objects] == [o.name for o in c.objects]
    assert (a.objects[-1].mesh.vertices == c.objects[-1].mesh.vertices).all()
    remove_copies("t1")


# --- compare's variants ---------------------------------------------------------------------

def test_compare_shows_two_settings_of_one_mode_side_by_side(tmp_path, capsys):
    out = tmp_path / "c"
    assert main(["compare", BASIC, "--size", "48x30", "--samples", "4", "--variant",
                 "lin=hybrid:hybrid.curve_steps=1,hybrid.segments=1", "--variant",
                 "seg4=hybrid:hybrid.curve_steps=1,hybrid.segments=4", "--out", str(out)]) == 0
    names = {f.name for f in out.iterdir()}
    assert names == {"lin.png", "lin.json", "seg4.png", "seg4.json", "reference.png",
                     "reference.json", "regions.png", "strip.png", "flip.png", "metrics.md",
                     "metrics.json", ".hmblur-outputs.json"}
    m = json.loads((out / "metrics.json").read_text())
    assert list(m["metrics"]) == ["lin", "seg4"]
    assert m["variants"]["seg4"] == {"mode": "hybrid",
                                     "set": {"hybrid.curve_steps": "1", "hybrid.segments": "4"}}
    assert m["metrics"]["lin"]["all"]["flip"] != m["metrics"]["seg4"]["all"]["flip"]
    md = (out / "metrics.md").read_text()
    assert "| variant | region |" in md and "| seg4 | inner |" in md
    side = json.loads((out / "seg4.json").read_text())
    assert side["mode"] == "hybrid" and side["params"]["hybrid"]["segments"] == 4
    assert side["variant"]["name"] == "seg4"
    # each image's sidecar makes that image again
    for name in ("lin", "seg4"):
        again = tmp_path / f"{name}.png"
        assert main(["shot", "--params", str(out / f"{name}.json"), "--out", str(again)]) == 0
        assert again.read_bytes() == (out / f"{name}.png").read_bytes(), name


@pytest.mark.parametrize("args, words", [
    (["--modes", "hybrid", "--variant", "hybrid=hybrid:hybrid.curve_steps=1"], "already shown"),
    (["--variant", "a=hybrid", "--variant", "a=mcguire"], "already shown"),
    (["--variant", "fast"], "expected NAME=MODE"),
    (["--variant", "x=warp"], "'warp' is not one of"),
    (["--variant", "strip=hybrid"], "taken by compare's own outputs"),
    (["--variant", "a=mcguire:hybrid.curve_steps=1"], "does not use the hybrid"),
    (["--variant", "a=hybrid:hybrid.curve_steps=99"], "hybrid.curve_steps: expected at most"),
    (["--variant", "a=hybrid:curve_steps"], "expected group.field=value"),
])
def test_compare_variant_mistakes(tmp_path, capsys, args, words):
    assert main(["compare", BASIC, "--size", "16x10", "--samples", "2", *args,
                 "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err, err
    assert not (tmp_path / "c").exists()


# --- Dask ------------------------------------------------------------------------------------

def test_a_local_dask_cluster_gives_the_in_process_table(tmp_path):
    """Two worker processes, each with its own EGL context; the scene files travel with
    the tasks; the table is the in-process one byte for byte."""
    p = sweep_file(tmp_path)
    sweep(tmp_path, p, tmp_path / "here")
    spec = load_sweep(p)
    facts = sweep_run.run_sweep(spec, tmp_path / "dask", version(), 2, None, False, False,
                                stream=open(tmp_path / "progress.txt", "a"))
    assert facts["failed"] == 0 and len(facts["ran"]) == 2
    assert len({c["worker"] for c in facts["ran"]}) >= 1
    assert all(c["worker"].split(":")[1] != str(__import__("os").getpid()) for c in facts["ran"])
    assert (tmp_path / "dask/table.csv").read_bytes() == (tmp_path / "here/table.csv").read_bytes()
    assert "dask LocalCluster, 2 workers" in (tmp_path / "dask/summary.md").read_text()


def test_a_gltf_entry_with_external_files_renders_on_a_worker_from_its_bundle(tmp_path):
    """A scene whose glTF entry keeps its buffer in a .bin beside it (a uri with a space),
    in a folder below the scene's: the cell, run from the bundle's copy, gives the numbers
    of the same cell run on a scene whose glTF holds its buffer inline; the .gltf alone as
    a scene travels with its .bin too."""
    import base64
    (tmp_path / "scenes/assets").mkdir(parents=True)
    doc = json.loads((CONFORMANCE / "gltf/BoxAnimated.gltf").read_text())
    head, data = doc["buffers"][0]["uri"].split(",", 1)
    (tmp_path / "scenes/assets/box data.bin").write_bytes(base64.b64decode(data))
    doc["buffers"][0]["uri"] = "box%20data.bin"
    (tmp_path / "scenes/assets/box.gltf").write_text(json.dumps(doc))
    scene = (CONFORMANCE / "gltf/gltf_box.toml").read_text()
    scene = scene.replace('gltf = "BoxAnimated.gltf"', 'gltf = "assets/box.gltf"')
    shutil.copy(CONFORMANCE / "gltf/BoxTextured.gltf", tmp_path / "scenes/assets")
    scene = scene.replace('gltf = "BoxTextured.gltf"', 'gltf = "assets/BoxTextured.gltf"')
    (tmp_path / "scenes/ext.toml").write_text(scene)
    p = tmp_path / "sweep.toml"
    p.write_text(textwrap.dedent(f"""
        scenes = ["scenes/ext.toml", "{CONFORMANCE / 'gltf/gltf_box.toml'}",
                  "scenes/assets/box.gltf"]
        size = "32x18"
        samples = 4
        [variants.hybrid]
        mode = "hybrid"
    """))
    spec = load_sweep(p)
    tasks, bundles = sweep_run.tasks_of(spec, version(), False, False, "t2")
    assert [rel for rel, _ in bundles[tasks[0].digest].files] == [
        "assets/BoxTextured.gltf", "assets/box data.bin", "assets/box.gltf", "ext.toml"]
    a, b = run_cell(tasks[0], bundles[tasks[0].digest]), run_cell(tasks[1], bundles[tasks[1].digest])
    assert a["error"] is None and b["error"] is None, (a["error"], b["error"])
    assert a["rows"] == b["rows"] and a["time"] == 1.6
    bare = run_cell(tasks[2], bundles[tasks[2].digest])   # the asset alone, as a scene
    assert [rel for rel, _ in bundles[tasks[2].digest].files] == ["box data.bin", "box.gltf"]
    assert bare["error"] is None and len(bare["rows"]) == 4 and tasks[2].scene == "box"
    remove_copies("t2")


def test_a_worker_of_another_version_gives_an_error_not_numbers(tmp_path):
    spec = load_sweep(sweep_file(tmp_path))
    tasks, bundles = sweep_run.tasks_of(spec, "0.0.0-other", False, False, "t3")
    got = run_cell(tasks[0], bundles[tasks[0].digest])
    assert got["rows"] == [] and "the sweep was started with 0.0.0-other" in got["error"]
