"""A bare glTF asset as a scene (world/asset_scene.py, docs/scene-format.md "A glTF file as a
scene"): the document it stands for, its framing, `hmblur scene` writing it as TOML that
loads back to the same scene, the render commands taking the asset, and the TOML writer.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tomllib

import numpy as np
import pytest
from PIL import Image

from tests.conftest import CONFORMANCE, ROOT
from viewer.commands.main import main
from world import toml_out
from world.camera import Camera

GLB = ROOT / "scenes" / "assets" / "rover.glb"


def scene_files():
    return sorted([*(ROOT / "scenes").glob("*.toml"), *(ROOT / "scenes" / "bench").glob("*.toml"),
                   *(ROOT / "scenes" / "examples").glob("*.toml"), *CONFORMANCE.glob("*.toml")])


# ---------------------------------------------------------------- the TOML writer

@pytest.mark.parametrize("path", scene_files(), ids=lambda p: p.name)
def test_writer_round_trips_every_scene_file(path):
    doc = tomllib.loads(path.read_text())
    assert tomllib.loads(toml_out.dumps(doc)) == doc


def test_writer_escapes_strings_and_quotes_keys():
    doc = {"name": 'a "b" \\ c\nd\te\x7f é 🚗', "n": -3, "x": 1e-300, "y": -0.0, "ok": False,
           "empty": [], "t": {"odd key": [1.5, 2], "in": {"z": "w"}},
           "objects": [{"name": "k", "keys": [{"time": 0.0}, {"time": 1.0}]}, {"name": "l"}]}
    text = toml_out.dumps(doc, header="line one\nline two")
    assert text.startswith("# line one\n# line two\n")
    back = tomllib.loads(text)
    assert back == doc and math.copysign(1.0, back["y"]) == -1.0


@pytest.mark.parametrize("bad", [math.inf, -math.inf, math.nan])
def test_writer_refuses_non_finite_numbers(bad):
    with pytest.raises(ValueError):
        toml_out.dumps({"x": [1.0, bad]})


# ---------------------------------------------------------------- the asset's scene

@pytest.fixture(scope="module")
def asset():
    from world.loader import load_asset
    return load_asset(GLB)


def corners(lo, hi):
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                     for z in (lo[2], hi[2])])


def test_the_document_and_its_framing(asset):
    from world import asset_scene
    scene, doc = asset
    assert doc["name"] == scene.name == "rover"
    assert doc["objects"] == [{"name": "rover", "gltf": "rover.glb", "loop": True}]
    (inst,) = scene.assets
    assert inst.loop and [inst.asset.animations[i].name for i in inst.animations] == [
        "drive", "swing"]
    assert scene.objects[0].name == "rover/body" and len(scene.objects) == 7
    assert scene.render.time == 2.5                         # the middle of the keys' 0..5 s
    assert (scene.render.width, scene.render.height) == (1280, 720)
    cam = scene.camera
    assert cam.fov_y == 40.0 and cam.shutter == pytest.approx(1 / 60, abs=1e-7)
    assert len(scene.lights) == 2 and not cam.moving
    # the box over the animation: the view from front-right-above at its centre, every
    # corner in the middle 60% of the frame, one of them at that edge; the asset in the
    # frame at every one of the nine times
    times = np.linspace(0.0, 5.0, 9)
    lo, hi = asset_scene.bounds(scene, times)
    np.testing.assert_allclose(cam.look_at, 0.5 * (lo + hi), rtol=1e-5, atol=1e-5)
    view = cam.position - cam.look_at
    assert view[0] > 0 and view[1] > 0 and view[2] > 0
    c = Camera(cam, 1280, 720)
    xy, depth = c.project(0.0, corners(lo, hi))
    ndc = np.abs(xy / [640.0, 360.0] - 1.0)
    assert ndc.max() == pytest.approx(0.6, abs=1e-4)
    assert cam.near < depth.min() and cam.far > depth.max()
    for t in times:
        for o in scene.objects:
            v = o.vertices_at(t)
            m = o.matrix(t)
            xy, _ = c.project(t, v @ m[:3, :3].T + m[:3, 3])
            assert np.abs(xy / [640.0, 360.0] - 1.0).max() <= 0.6 + 1e-4


def test_an_asset_without_animation_is_framed_at_time_0(tmp_path):
    from world.loader import load_asset
    path = tmp_path / "still.gltf"
    path.write_text(json.dumps(triangle_gltf()))
    scene, doc = load_asset(path)
    assert doc["render"]["time"] == 0.0 and scene.render.time == 0.0
    np.testing.assert_allclose(scene.camera.look_at, [0.5, 0.5, 0.0], atol=1e-6)


def triangle_gltf(with_mesh: bool = True) -> dict:
    """A one-triangle glTF with its buffer embedded as a data URI."""
    import base64
    data = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"name": "tri"}]}
    if with_mesh:
        doc["nodes"][0]["mesh"] = 0
        doc.update(
            meshes=[{"primitives": [{"attributes": {"POSITION": 0}}]}],
            accessors=[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                        "min": [0, 0, 0], "max": [1, 1, 0]}],
            bufferViews=[{"buffer": 0, "byteLength": len(data)}],
            buffers=[{"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                      + base64.b64encode(data).decode()}])
    return doc


def same_scene(a, b):
    assert a.name == b.name
    assert [(o.name, o.id) for o in a.objects] == [(o.name, o.id) for o in b.objects]
    for f in ("position", "look_at", "up"):
        assert np.array_equal(getattr(a.camera, f), getattr(b.camera, f))
    for f in ("fov_y", "near", "far", "shutter"):
        assert getattr(a.camera, f) == getattr(b.camera, f)
    assert a.render == b.render
    assert np.array_equal(a.background, b.background) and np.array_equal(a.ambient, b.ambient)
    for la, lb in zip(a.lights, b.lights, strict=True):
        assert np.array_equal(la.direction, lb.direction) and np.array_equal(la.color, lb.color)
    for oa, ob in zip(a.objects, b.objects):
        for t in (0.0, 1.3, 2.5, 4.9, 7.0):                # 7: past the end, looped
            assert np.array_equal(oa.matrix(t), ob.matrix(t))
            assert np.array_equal(oa.vertices_at(t), ob.vertices_at(t))


def test_printed_scene_loads_back_to_the_same_scene(asset, tmp_path, capsys, monkeypatch):
    from world.loader import load_scene
    scene, doc = asset
    out = tmp_path / "edit" / "rover.toml"
    assert main(["scene", str(GLB), "--out", str(out)]) == 0
    written = tomllib.loads(out.read_text())
    assert written["objects"][0]["gltf"] == str(GLB)         # a built-in asset: absolute
    assert {k: v for k, v in written.items() if k != "objects"} == {
        k: v for k, v in doc.items() if k != "objects"}
    same_scene(load_scene(out), scene)
    # to stdout: the asset's path relative to the current folder
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    assert main(["scene", os.path.relpath(GLB)]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith(f"# Written by `hmblur scene {os.path.relpath(GLB)}`:\n")
    (tmp_path / "here.toml").write_text(printed)
    same_scene(load_scene(tmp_path / "here.toml"), scene)


def spun_box_asset(folder):
    """A box turning about +Y over 0..2 s with its buffer in an external .bin."""
    from tests.gltf_builder import Builder
    import trimesh
    box = trimesh.creation.box(extents=[1.0, 0.6, 0.4])
    b = Builder()
    m = b.triangle_mesh(box.vertices.astype(np.float32), box.faces.astype(np.uint16))
    b.add("nodes", {"mesh": m, "name": "box"})
    b.doc["scenes"] = [{"nodes": [0]}]
    s = math.sqrt(0.5)
    ti = b.accessor(np.float32([0.0, 1.0, 2.0]))
    ri = b.accessor(np.float32([[0, 0, 0, 1], [0, s, 0, s], [0, 1, 0, 0]]))
    b.add("animations", {"samplers": [{"input": ti, "output": ri}],
                         "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}]})
    folder.mkdir(parents=True)
    return b.write(folder, "box.gltf", external="box.bin")


def test_scene_out_writes_where_it_loads_else_refuses(tmp_path, ctx):
    from viewer.render.renderer import Renderer
    from world.loader import load_asset, load_scene
    asset = spun_box_asset(tmp_path / "assets" / "box")
    bare, _ = load_asset(asset)

    def image(scene):
        r = Renderer(ctx, scene, (64, 36))
        try:
            return r.render("off", scene.render.time).image
        finally:
            r.release()
    want = image(bare)
    (tmp_path / "link").symlink_to(tmp_path / "assets")
    # the asset's folder, folders above it, one reached through a link
    for out in (asset.parent / "box.toml", tmp_path / "assets" / "box.toml",
                tmp_path / "box.toml", tmp_path / "link" / "box.toml"):
        assert main(["scene", str(asset), "--out", str(out)]) == 0
        loaded = load_scene(out)
        same_scene(loaded, bare)
        assert np.array_equal(image(loaded), want)
    assert tomllib.loads((tmp_path / "box.toml").read_text())["objects"][0]["gltf"] == \
        "assets/box/box.gltf"
    # outside the asset's folder and every folder above it: one line, nothing written
    for out in (tmp_path / "elsewhere" / "box.toml", asset.parent / "deeper" / "box.toml"):
        line = one_line_error(["scene", str(asset), "--out", str(out)], f"--out {out}",
                              f"write it in {asset.parent} or a folder above it")
        assert "Asset files" in line and not out.exists() and not out.parent.exists()
    # a scene printed to stdout names the asset from the current folder; where no scene
    # saved there would load it, a note says so
    for cwd in (tmp_path, asset.parent, tmp_path / "link"):
        p = subprocess.run([sys.executable, "-m", "viewer", "scene", str(asset)], cwd=cwd,
                           capture_output=True, text=True, timeout=240)
        assert p.returncode == 0 and p.stderr == "", p.stderr
        (cwd / "printed.toml").write_text(p.stdout)
        same_scene(load_scene(cwd / "printed.toml"), bare)
    (tmp_path / "elsewhere").mkdir()
    p = subprocess.run([sys.executable, "-m", "viewer", "scene", str(asset)],
                       cwd=tmp_path / "elsewhere", capture_output=True, text=True, timeout=240)
    assert p.returncode == 0 and len(p.stderr.splitlines()) == 1
    assert p.stderr.startswith("hmblur: note: saved in the current folder, this scene would "
                               f"not load {asset}")
    assert tomllib.loads(p.stdout)["objects"][0]["gltf"] == "../assets/box/box.gltf"


def one_line_error(args, *words):
    p = subprocess.run([sys.executable, "-m", "viewer", *args], cwd=ROOT, capture_output=True,
                       text=True, timeout=240)
    lines = p.stderr.strip().splitlines()
    assert p.returncode == 2 and len(lines) == 1, p.stderr
    assert lines[0].startswith("hmblur: error: ")
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def test_mistakes_are_one_line_and_exit_2(tmp_path):
    one_line_error(["scene", "scenes/rover.toml"], "expected a .gltf or .glb file")
    one_line_error(["scene", str(tmp_path / "nothing.glb")], "nothing.glb", "file not found")
    junk = tmp_path / "junk.glb"
    junk.write_bytes(b"not a glb at all")
    one_line_error(["scene", str(junk)], "junk.glb")
    one_line_error(["shot", str(junk), "--out", str(tmp_path / "x.png")], "junk.glb")
    empty = tmp_path / "empty.gltf"
    empty.write_text(json.dumps(triangle_gltf(with_mesh=False)))
    one_line_error(["shot", str(empty), "--out", str(tmp_path / "y.png")], "empty.gltf",
                   "no mesh")
    one_line_error(["scene", str(GLB), "--out", str(tmp_path / "x.txt")], ".toml")
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "y.png").exists()


def shot(tmp_path, asset, *args):
    """`hmblur shot ASSET` at 320x180: (foreground mask, sidecar)."""
    from viewer.io.imageio import linear_to_srgb8
    from world import asset_scene
    out = tmp_path / f"{asset.stem}.png"
    p = subprocess.run([sys.executable, "-m", "viewer", "shot", str(asset), "--size", "320x180",
                        "--out", str(out), *args], cwd=ROOT, capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 0, p.stderr
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    bg = linear_to_srgb8(np.array(asset_scene.BACKGROUND)).astype(int)
    fg = np.abs(img - bg).max(axis=2) > 6
    # in the frame, not cut by its edges
    assert not fg[0].any() and not fg[-1].any() and not fg[:, 0].any() and not fg[:, -1].any()
    return fg, json.loads(out.with_suffix(".json").read_text())


def test_shot_of_a_bare_glb_shows_the_asset(tmp_path):
    # the rover drives ~8 m over its animation: framed over all of it, small at mid-drive
    fg, side = shot(tmp_path, GLB, "--mode", "hybrid")
    assert side["scene_name"] == "rover" and side["time"] == 2.5
    assert side["scene"] == str(GLB)
    assert fg.mean() > 0.004, fg.mean()


def test_shot_of_a_bare_gltf_in_place_is_centred(tmp_path):
    fg, side = shot(tmp_path, CONFORMANCE / "gltf" / "RiggedSimple.gltf")
    assert side["scene_name"] == "RiggedSimple"
    assert 0.01 < fg.mean() < 0.5, fg.mean()          # a thin tube
    ys, xs = np.nonzero(fg)
    assert 0.35 * 320 < xs.mean() < 0.65 * 320 and 0.3 * 180 < ys.mean() < 0.7 * 180
    # the box's extent reaches the middle 60% of the frame's height or width
    assert max(np.ptp(ys) / 180, np.ptp(xs) / 320) > 0.4


def test_compare_video_and_bench_take_a_bare_gltf(tmp_path):
    box = str(CONFORMANCE / "gltf" / "BoxAnimated.gltf")
    for args in (["compare", box, "--size", "96x54", "--samples", "4", "--out",
                  str(tmp_path / "cmp")],
                 ["video", box, "--size", "96x54", "--frames", "2", "--modes", "off,hybrid",
                  "--out", str(tmp_path / "frames")],
                 ["bench", box, "--size", "96x54", "--frames", "2", "--warmup", "1",
                  "--json", str(tmp_path / "bench.json")]):
        p = subprocess.run([sys.executable, "-m", "viewer", *args], cwd=ROOT,
                           capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, (args[0], p.stderr)
    metrics = json.loads((tmp_path / "cmp" / "metrics.json").read_text())
    assert "BoxAnimated" in json.dumps(metrics)
    assert len(list((tmp_path / "frames").glob("*.png"))) == 2
    assert json.loads((tmp_path / "bench.json").read_text())


def test_view_opens_a_bare_glb(tmp_path):
    from tests.xvfb import Xvfb
    display = Xvfb().start()
    try:
        shot_png, stats = tmp_path / "win.png", tmp_path / "win.json"
        p = subprocess.run([sys.executable, "-m", "viewer", "view", str(GLB), "--size", "480x270",
                            "--frames", "4", "--screenshot", str(shot_png), "--stats-json",
                            str(stats), "--shot-dir", str(tmp_path)], cwd=ROOT,
                           env=display.env(), capture_output=True, text=True, timeout=240)
    finally:
        display.stop()
    assert p.returncode == 0, p.stderr
    st = json.loads(stats.read_text())
    assert st["errors"] == [] and st["scene"] == str(GLB) and st["frames"] == 4
    assert shot_png.is_file()


def test_panel_lists_the_assets_animations(asset):
    from viewer.ui.panel import animation_lines
    scene, _ = asset
    assert animation_lines(scene) == [
        "rover: drive 0.00-5.00 s, swing 0.00-5.00 s (looped)"]


# ---------------------------------------------------------------- choosing an animation

def test_an_entrys_animation_can_be_chosen(asset):
    from world.errors import SceneError
    from world.loader import load_scene
    from viewer.ui.panel import animation_choices, chosen_index
    scene, _ = asset
    for choice, played in (("swing", (1,)), (0, (0,)), ("none", ()), ("all", (0, 1))):
        chosen = load_scene(str(GLB), {"rover": choice})
        assert chosen.assets[0].animations == played, choice
        inst = chosen.assets[0]
        labels, values = animation_choices(inst)
        assert labels == values == ["all", "drive", "swing", "none"]
        assert values[chosen_index(inst, values, None)] == {
            "swing": "swing", 0: "drive", "none": "none", "all": "all"}[choice]
    # a scene file's entry, by its name; the other objects as they were
    keyed = load_scene("rover", {"rover": "drive"})
    assert keyed.assets[0].animations == (0,)
    assert [o.name for o in keyed.objects] == [o.name for o in load_scene("rover").objects]
    for bad, words in (({"rover": "fly"}, "no animation named 'fly'"),
                       ({"rover": 7}, "animation index 7 out of range"),
                       ({"truck": "all"}, "animations: no gltf entry named 'truck'")):
        with pytest.raises(SceneError, match=words):
            load_scene(str(GLB), bad)


def test_a_sidecars_animations_are_checked(tmp_path):
    out = tmp_path / "a.png"
    assert main(["shot", str(GLB), "--mode", "off", "--size", "32x18", "--out", str(out)]) == 0
    side = json.loads(out.with_suffix(".json").read_text())
    assert "animations" not in side                   # (none chosen: the file's own)
    for bad, words in (({"rover": "fly"}, "no animation named 'fly'"),
                       ({"truck": "all"}, "no gltf entry named 'truck'"),
                       ({"rover": True}, "expected a table of gltf entry names"),
                       (["rover"], "expected a table of gltf entry names")):
        side["animations"] = bad
        (tmp_path / "bad.json").write_text(json.dumps(side))
        one_line_error(["shot", "--params", str(tmp_path / "bad.json"), "--out",
                        str(tmp_path / "b.png")], f"--params {tmp_path / 'bad.json'}: animations: ",
                       words)
    assert not (tmp_path / "b.png").exists()


def test_the_viewer_chooses_an_animation_above_the_fold(tmp_path):
    # 1280x720 with the hybrid's long parameter list: the animation section is drawn
    # within the window; the choice made there reaches the screenshot's sidecar, from
    # which `shot --params` renders the same image (and without it, another).
    from tests.xvfb import Xvfb
    script = tmp_path / "s.txt"
    script.write_text("2 animation rover swing\n3 key P\n")
    bad = tmp_path / "bad.txt"
    bad.write_text("2 animation rover fly\n")
    display = Xvfb().start()
    try:
        runs = [subprocess.run([sys.executable, "-m", "viewer", "view", str(GLB), "--size",
                                "1280x720", "--frames", "5", "--script", str(path),
                                "--stats-json", str(tmp_path / f"{path.stem}.json"),
                                "--shot-dir", str(tmp_path)], cwd=ROOT, env=display.env(),
                               capture_output=True, text=True, timeout=240)
                for path in (script, bad)]
    finally:
        display.stop()
    assert runs[0].returncode == 0, runs[0].stderr
    st = json.loads((tmp_path / "s.json").read_text())
    assert st["errors"] == [] and st["animations"] == {"rover": "swing"}
    sections = st["panel_sections"]
    assert sections["Animation"][0] < sections["Parameters"][0]
    assert sections["Animation"][1] <= 720 and sections["Buffer view"][1] <= 720
    assert sections["Parameters"][1] > 720                  # (what used to push it down)
    shot_png = tmp_path / "rover_hybrid_000.png"
    side = json.loads(shot_png.with_suffix(".json").read_text())
    assert side["animations"] == {"rover": "swing"}
    again, other = tmp_path / "again.png", tmp_path / "other.png"
    assert main(["shot", "--params", str(shot_png.with_suffix(".json")), "--out",
                 str(again)]) == 0
    assert again.read_bytes() == shot_png.read_bytes()
    del side["animations"]
    (tmp_path / "all.json").write_text(json.dumps(side))
    assert main(["shot", "--params", str(tmp_path / "all.json"), "--out", str(other)]) == 0
    assert other.read_bytes() != shot_png.read_bytes()
    # a choice that does not load: shown in the panel, the run exits 2 with one line
    assert runs[1].returncode == 2
    (line,) = runs[1].stderr.strip().splitlines()
    assert "animation rover fly" in line and "no animation named 'fly'" in line


# ---------------------------------------------------------------- the quick look's choices

def set_pieces(statics, movers, path):
    """A glTF asset of still boxes `statics` [(name, extents, centre)] and moving parts
    `movers` [(name, mesh (trimesh), translation, animation {path: (times, values)})],
    written to `path` (.gltf, buffer embedded)."""
    import trimesh
    from tests.gltf_builder import Builder
    b = Builder()
    roots = []
    for name, extents, centre in statics:
        box = trimesh.creation.box(extents=extents)
        m = b.triangle_mesh(box.vertices.astype(np.float32), box.faces.astype(np.uint16))
        roots.append(b.add("nodes", {"name": name, "mesh": m, "translation": list(centre)}))
    samplers, channels = [], []
    for name, mesh, translation, channels_of in movers:
        m = b.triangle_mesh(mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint16))
        node = b.add("nodes", {"name": name, "mesh": m, "translation": list(translation)})
        roots.append(node)
        for target, (times, values) in channels_of.items():
            samplers.append({"input": b.accessor(np.float32(times)),
                             "output": b.accessor(np.float32(values))})
            channels.append({"sampler": len(samplers) - 1,
                             "target": {"node": node, "path": target}})
    b.doc["scenes"] = [{"nodes": roots}]
    if samplers:
        b.add("animations", {"name": "move", "samplers": samplers, "channels": channels})
    path.parent.mkdir(parents=True, exist_ok=True)
    return b.write(path.parent, path.name)


def fan_mesh():
    import trimesh
    return trimesh.util.concatenate([trimesh.creation.box(extents=[1.2, 0.04, 0.2]),
                                     trimesh.creation.box(extents=[0.2, 0.04, 1.2])])


def turning(seconds=2.0, steps=4):
    """A turn about +Y, keyed every quarter turn."""
    times = np.linspace(0.0, seconds, steps + 1)
    half = np.linspace(0.0, math.pi, steps + 1)
    return {"rotation": (times, [[0.0, math.sin(h), 0.0, math.cos(h)] for h in half])}


def id_share(ctx, scene, names, size=(160, 90)):
    """The share of the frame the objects `names` cover at the scene's time, and the
    width and height of the box around those pixels as shares of the frame's."""
    from viewer.render.renderer import Renderer
    r = Renderer(ctx, scene, size)
    try:
        r.render("off", scene.render.time)
        ids = r.buffers()["id"].reshape(size[1], size[0])
    finally:
        r.release()
    want = [o.id for o in scene.objects if o.name.split("/")[-1] in names]
    mask = np.isin(ids, want)
    if not mask.any():
        return 0.0, 0.0, 0.0
    ys, xs = np.nonzero(mask)
    return float(mask.mean()), (np.ptp(xs) + 1) / size[0], (np.ptp(ys) + 1) / size[1]


def test_a_fan_under_a_ceiling_slab_is_seen_from_below(tmp_path, ctx):
    from world.loader import load_asset
    path = set_pieces([("ceiling", [6.0, 0.2, 6.0], [0.0, 2.2, 0.0])],
                      [("fan", fan_mesh(), [0.0, 1.8, 0.0], turning())],
                      tmp_path / "fan.gltf")
    scene, doc = load_asset(path)
    cover, width, _ = id_share(ctx, scene, {"fan"})
    assert cover > 0.02 and width > 0.3, (cover, width)
    eye = scene.camera.position - scene.camera.look_at
    assert eye[1] < 0 and doc["lights"][0]["direction"][1] > 0     # from below, lit so
    np.testing.assert_allclose(scene.camera.look_at, [0.0, 1.8, 0.0], atol=1e-6)


def test_a_mover_beside_big_still_parts_fills_the_frame(tmp_path, ctx):
    import trimesh
    from world.loader import load_asset
    path = set_pieces([("floor", [20.0, 0.2, 20.0], [0.0, -0.1, 0.0]),
                       ("wall", [20.0, 5.0, 0.2], [0.0, 2.5, -6.0]),
                       ("pillar", [0.5, 4.0, 0.5], [6.0, 2.0, 3.0])],
                      [("cart", trimesh.creation.box(extents=[0.4, 0.4, 0.4]), [0.0, 0.2, 0.0],
                        {"translation": ([0.0, 2.0], [[-0.5, 0.2, 0.0], [0.5, 0.2, 0.0]])})],
                      tmp_path / "cart.gltf")
    scene, doc = load_asset(path)
    cover, width, height = id_share(ctx, scene, {"cart"})
    # the cart's path over the animation, 1.4 m, spans the middle 60% of the frame: the
    # cart itself a fifth of it
    assert cover > 0.02 and width > 0.12 and height > 0.15, (cover, width, height)
    assert scene.camera.far > 4 * np.linalg.norm(scene.camera.position - [0.0, 2.5, -6.0])
    # the whole stage framed would leave the cart a speck (the frame of an asset that
    # does not move)
    still = set_pieces([("floor", [20.0, 0.2, 20.0], [0.0, -0.1, 0.0]),
                        ("wall", [20.0, 5.0, 0.2], [0.0, 2.5, -6.0]),
                        ("pillar", [0.5, 4.0, 0.5], [6.0, 2.0, 3.0])],
                       [("cart", trimesh.creation.box(extents=[0.4, 0.4, 0.4]),
                         [0.0, 0.2, 0.0], {})], tmp_path / "still.gltf")
    still_scene, still_doc = load_asset(still)
    assert still_doc["render"]["time"] == 0.0
    assert id_share(ctx, still_scene, {"cart"})[0] < 0.005


def test_the_time_chosen_is_one_where_the_parts_move(tmp_path, ctx):
    import trimesh
    from viewer.render.modes.reference import REGIONS
    from viewer.render.modes.regions import INNER
    from viewer.render.graph.params import ParamSet
    from viewer.render.renderer import Renderer
    from world.asset_scene import SHUTTER
    from world.loader import load_asset
    # still from 0.8 s to 1.2 s: the middle of the animation, 1 s, is a still pose
    keys = ([0.0, 0.8, 1.2, 2.0], [[0.0, 0.2, 0.0], [1.0, 0.2, 0.0], [1.0, 0.2, 0.0],
                                   [2.0, 0.2, 0.0]])
    path = set_pieces([("floor", [6.0, 0.2, 6.0], [1.0, -0.1, 0.0])],
                      [("cart", trimesh.creation.box(extents=[0.4, 0.4, 0.4]), [0.0, 0.2, 0.0],
                        {"translation": keys})], tmp_path / "pause.gltf")
    scene, doc = load_asset(path)
    t = scene.render.time
    assert t in (0.75, 1.25), t                     # the moving samples nearest the middle
    cart = next(o for o in scene.objects if o.name.endswith("cart"))
    assert not np.allclose(cart.matrix(t - SHUTTER / 2), cart.matrix(t + SHUTTER / 2))
    # and the reference finds inner blur there (none at the still middle)
    r = Renderer(ctx, scene, (96, 54))
    params = ParamSet()
    params.set("reference.samples", 8)
    try:
        inner = [int((r.render("reference", when, params, record_visibility=True).host[REGIONS]
                      == INNER).sum()) for when in (t, 1.0)]
    finally:
        r.release()
    assert inner[0] > 0 and inner[1] == 0, inner


def test_key_times_print_as_written(tmp_path):
    import trimesh
    from world.loader import load_asset
    path = set_pieces([], [("cart", trimesh.creation.box(extents=[0.4, 0.4, 0.4]),
                            [0.0, 0.0, 0.0],
                            {"translation": ([0.0, 1.2], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])})],
                      tmp_path / "short.gltf")
    _, doc = load_asset(path)
    assert doc["render"]["time"] == 0.6 and repr(doc["render"]["time"]) == "0.6"
