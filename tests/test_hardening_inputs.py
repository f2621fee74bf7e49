"""Hostile input: every count, size, rate and file a user can give is bounded before work
starts and refused on one printable line with exit 2; names and paths cannot split that
line or reach the terminal; scene files name only regular files in their own folder."""
from __future__ import annotations

import json
import os
import textwrap

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from PIL import Image

from conftest import CONFORMANCE, ROOT, srgb_to_linear
from viewer.commands.main import main
from world import images, limits
from world import loader as loader_mod
from world.errors import SceneError, UserError, printable
from world.loader import builtin_dir, load_scene

BASIC = str(CONFORMANCE / "basic.toml")
HEAD = """
    [camera]
    position = [0.0, 0.0, 4.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 45.0
    [render]
    width = 64
    height = 36
"""


def write_scene(folder, body, name="s.toml", head=HEAD):
    p = folder / name
    p.write_text(textwrap.dedent(head) + textwrap.dedent(body))
    return p


def one_line(capsys, argv) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, (argv, code, err)
    assert lines[0].startswith("hmblur: error: ") and lines[0].isprintable(), err
    return lines[0]


# --- one printable line ------------------------------------------------------------------

@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8"), max_size=40))
def test_printable_is_one_line_that_keeps_what_was_printable(text):
    out = printable(text)
    assert out.isprintable() and "\n" not in out and "\x1b" not in out
    if text.isprintable():
        assert out == text
    # what was printable is still there, in order
    kept = "".join(c for c in text if c.isprintable())
    it = iter(out)
    assert all(c in it for c in kept)


@settings(derandomize=True, max_examples=50, deadline=None)
@given(st.text(alphabet=st.sampled_from("ab\n\r\t\x1b[31m\x07\x00\u2028\u0085\x9b;"),
               min_size=1, max_size=20))
def test_a_scene_error_naming_any_object_name_is_one_printable_line(text):
    err = SceneError("/tmp/s\n.toml", f"objects[1] ({text}).mesh", "expected a table")
    assert str(err).isprintable() and str(err).startswith("/tmp/s\\n.toml: objects[1] (")
    assert str(UserError(f"--out {text}")).isprintable()


def test_a_name_with_a_terminal_escape_reaches_stderr_escaped(tmp_path, capsys):
    scene = write_scene(tmp_path, """
        [[objects]]
        name = "evil\\u001b]0;owned\\u0007\\nsecond line"
        mesh = { box = [1.0, 1.0, "x"] }
    """, name="a\x1b[2Jb.toml")
    line = one_line(capsys, ["shot", str(scene), "--out", str(tmp_path / "o.png")])
    assert "evil\\x1b]0;owned\\x07\\nsecond line" in line and "a\\x1b[2Jb.toml" in line


def test_an_unwritable_output_path_is_printed_escaped(tmp_path, capsys):
    blocker = tmp_path / "f"
    blocker.write_text("a file, not a folder")
    line = one_line(capsys, ["shot", BASIC, "--out", str(blocker / "x\ny.png")])
    assert "x\\ny.png" in line


# --- scene numbers and counts ------------------------------------------------------------

KEYS = {
    "object position": ("[[objects]]\nmesh = {{ box = [1.0, 1.0, 1.0] }}\nposition = [{v}, 0.0, 0.0]\n",
                        "objects[1] (object1).position[0]"),
    "velocity": ("[[objects]]\nmesh = {{ box = [1.0, 1.0, 1.0] }}\nvelocity = [0.0, {v}, 0.0]\n",
                 "objects[1] (object1).velocity[1]"),
    "box size": ("[[objects]]\nmesh = {{ box = [1.0, 1.0, {v}] }}\n", "objects[1] (object1).mesh.box[2]"),
    "albedo": ("[[objects]]\nmesh = {{ box = [1.0, 1.0, 1.0] }}\nmaterial = {{ albedo = [{v}, 0.0, 0.0] }}\n",
               "objects[1] (object1).material.albedo[0]"),
    "light colour": ("[[lights]]\ndirection = [0.0, -1.0, 0.0]\ncolor = [1.0, {v}, 1.0]\n",
                     "lights[1].color[1]"),
    "scale": ("[[objects]]\nmesh = {{ box = [1.0, 1.0, 1.0] }}\nscale = {v}\n", "objects[1] (object1).scale"),
    "key time": ("[[objects]]\nmesh = {{ box = [1.0, 1.0, 1.0] }}\n[[objects.keys]]\ntime = {v}\n",
                 "objects[1] (object1).keys[1].time"),
}


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.sampled_from(sorted(KEYS)),
       st.one_of(st.floats(min_value=1.0000001e7, max_value=1.7e308),
                 st.integers(min_value=10 ** 7 + 1, max_value=10 ** 400)),
       st.booleans())
def test_numbers_past_float32s_reach_are_a_scene_error_naming_the_key(tmp_path_factory, which,
                                                                     value, negative):
    body, key = KEYS[which]
    v = -value if negative else value
    text = repr(float(v)) if isinstance(v, float) else str(v)
    folder = tmp_path_factory.mktemp("n")
    path = write_scene(folder, body.format(v=text))
    with pytest.raises(SceneError) as e:
        load_scene(path)
    assert e.value.key.startswith(key.split("[")[0]) and key in str(e.value), str(e.value)


def test_render_time_is_bounded_as_the_time_flag_is(tmp_path, capsys):
    path = write_scene(tmp_path, "", head=HEAD.replace("height = 36", "height = 36\ntime = 2e6"))
    with pytest.raises(SceneError, match=r"render.time: expected seconds within \+-1e\+06"):
        load_scene(path)
    line = one_line(capsys, ["shot", BASIC, "--time", "2e6", "--out", str(tmp_path / "o.png")])
    assert "within +-1e+06" in line


def test_a_huge_revolve_is_refused_before_it_is_built(tmp_path, monkeypatch):
    import trimesh
    points = ", ".join(f"[1.0, {i * 1e-3:.3f}]" for i in range(3000))
    path = write_scene(tmp_path, f"""
        [[objects]]
        mesh = {{ revolve = [{points}], sections = 10000 }}
    """)
    built = []
    monkeypatch.setattr(trimesh.creation, "revolve", lambda *a, **k: built.append(a))
    with pytest.raises(SceneError, match="60000000 triangles.*2000000"):
        load_scene(path)
    assert built == []


def test_the_scene_triangle_budget_counts_every_mesh(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "MAX_TRIANGLES", 30)
    body = "[[objects]]\nmesh = { box = [1.0, 1.0, 1.0] }\n"
    load_scene(write_scene(tmp_path, body * 2, "two.toml"))          # 24 triangles
    with pytest.raises(SceneError, match=r"objects\[3\].*36.*30"):
        load_scene(write_scene(tmp_path, body * 3, "three.toml"))


def test_objects_and_lights_are_counted(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "MAX_OBJECTS", 2)
    monkeypatch.setattr(limits, "MAX_LIGHTS", 1)
    box = "[[objects]]\nmesh = { box = [1.0, 1.0, 1.0] }\n"
    light = "[[lights]]\ndirection = [0.0, -1.0, 0.0]\n"
    load_scene(write_scene(tmp_path, box * 2 + light, "ok.toml"))
    with pytest.raises(SceneError, match="objects: expected at most 2 entries, got 3"):
        load_scene(write_scene(tmp_path, box * 3, "objects.toml"))
    with pytest.raises(SceneError, match="lights: expected at most 1 entries, got 2"):
        load_scene(write_scene(tmp_path, light * 2, "lights.toml"))


def test_a_frame_size_past_the_pixel_limit_is_refused(tmp_path):
    path = write_scene(tmp_path, "", head=HEAD.replace("width = 64", "width = 16384")
                       .replace("height = 36", "height = 16384"))
    with pytest.raises(SceneError, match="at most 4194304 pixels"):
        load_scene(path)


@pytest.mark.parametrize("flags, needle", [
    (["video", "--frames", "1000000000"], "--frames '1000000000': expected an integer from 1 to 100000"),
    (["video", "--fps", "1e10"], "--fps '1e10': expected frames per second from 0.001 to 1000"),
    (["video", "--fps", "1e-300"], "frames per second"),
    (["video", "--frames", "9" * 5000], "at most 40 characters"),
    (["video", "--out-gif", "--frames", "100000"], "a GIF holds every frame"),
    (["shot", "--size", "4097x4097"], "too large"),
    (["shot", "--size", "9" * 30 + "x2"], "expected WIDTHxHEIGHT"),
    (["shot", "--seed", "4294967296"], "from 0 to 4294967295"),
    (["shot", "--time", "1e400"], "finite"),
    (["bench", "--frames", "1000000000"], "from 1 to 100000"),
    (["bench", "--warmup", "1000000000"], "from 0 to 100000"),
])
def test_counts_sizes_and_rates_are_refused_before_work(tmp_path, capsys, flags, needle):
    command, rest = flags[0], flags[1:]
    out = tmp_path / ("o.gif" if "--out-gif" in rest else "o.mp4" if command == "video"
                      else "o.png")
    rest = [f for f in rest if f != "--out-gif"]
    argv = [command, BASIC, *rest] + ([] if command == "bench" else ["--out", str(out)])
    assert needle in one_line(capsys, argv)
    assert os.listdir(tmp_path) == []


# --- --params FILE -----------------------------------------------------------------------

def test_hostile_params_files_are_one_line(tmp_path, capsys):
    cases = {
        "deep.json": ("[" * 100000 + "]" * 100000, "nested too deeply"),
        "digits.json": ('{"params": {}, "seed": ' + "9" * 5000 + "}", "not a sidecar's JSON"),
        "seed.json": ('{"params": {}, "seed": ' + "9" * 400 + "}", "at most 40 characters"),
        "huge.json": (" " * (limits.MAX_PARAMS_BYTES + 1), "larger than"),
        "binary.json": ("\udcff", None),
    }
    for name, (text, needle) in cases.items():
        p = tmp_path / name
        if name == "binary.json":
            p.write_bytes(b"\xff\xfe\x00")
            needle = "not UTF-8"
        else:
            p.write_text(text)
        line = one_line(capsys, ["shot", BASIC, "--params", str(p), "--out",
                                 str(tmp_path / "o.png")])
        assert needle in line, (name, line)
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for special in ("/dev/zero", str(fifo), str(tmp_path)):
        line = one_line(capsys, ["shot", BASIC, "--params", special, "--out",
                                 str(tmp_path / "o.png")])
        assert "not a regular file" in line
    assert not (tmp_path / "o.png").exists()


# --- asset files -------------------------------------------------------------------------

MESH = "[[objects]]\nmesh = \"{path}\"\n"
TEXTURE = ("[[objects]]\nmesh = \"{quad}\"\n"
           "material = {{ texture = {{ kind = \"image\", path = \"{path}\" }} }}\n")


def test_asset_files_outside_the_scene_folder_are_refused_before_opening(tmp_path, monkeypatch):
    opened = []
    real_open = loader_mod.trimesh.load
    monkeypatch.setattr(loader_mod.trimesh, "load",
                        lambda p, *a, **k: opened.append(p) or real_open(p, *a, **k))
    scene_dir = tmp_path / "scene"
    (scene_dir / "meshes").mkdir(parents=True)
    quad = (builtin_dir() / "assets" / "quad_uv.obj").read_text()
    (scene_dir / "meshes" / "quad.obj").write_text(quad)
    (tmp_path / "outside.obj").write_text(quad)
    os.symlink(tmp_path / "outside.obj", scene_dir / "link.obj")
    os.mkfifo(scene_dir / "fifo.obj")
    refused = {
        "/etc/passwd": "outside the scene file's folder",
        "../outside.obj": "outside the scene file's folder",
        "meshes/../../outside.obj": "outside the scene file's folder",
        "link.obj": "outside the scene file's folder",          # (symlinks resolved)
        "/dev/zero": "outside the scene file's folder",
        "fifo.obj": "not a regular file",
        "meshes": "not a regular file",
        "missing.obj": "not found",
    }
    for rel, needle in refused.items():
        path = write_scene(scene_dir, MESH.format(path=rel))
        with pytest.raises(SceneError, match=needle) as e:
            load_scene(path)
        assert e.value.key == "objects[1] (object1).mesh", rel
    assert opened == []
    # inside the folder, and the built-in assets by their absolute path, are read
    for rel in ("meshes/quad.obj", "meshes/../meshes/quad.obj",
                str(builtin_dir() / "assets" / "quad_uv.obj")):
        load_scene(write_scene(scene_dir, MESH.format(path=rel)))
    monkeypatch.setattr(limits, "MAX_MESH_BYTES", 100)
    with pytest.raises(SceneError, match=r"holds \d+ bytes, more than the 100"):
        load_scene(write_scene(scene_dir, MESH.format(path="meshes/quad.obj")))


def test_a_texture_past_the_pixel_limit_is_refused_from_its_header(tmp_path, monkeypatch):
    quad = builtin_dir() / "assets" / "quad_uv.obj"
    Image.fromarray(np.zeros((30, 40, 3), np.uint8)).save(tmp_path / "tex.png")
    monkeypatch.setattr(limits, "MAX_IMAGE_PIXELS", 1000)
    decoded = []
    monkeypatch.setattr(images, "linear_rgb", lambda im: decoded.append(im))
    with pytest.raises(SceneError, match=r"texture.path: .*tex.png: 40x30 pixels, more than the "
                                         r"limit of 1000 for one image"):
        load_scene(write_scene(tmp_path, TEXTURE.format(quad=quad, path="tex.png")))
    assert decoded == []


@pytest.mark.parametrize("mode", ["L", "LA", "P", "RGB", "RGBA", "I;16", "F"])
def test_textures_decode_to_the_same_float32_as_the_float64_formula(mode):
    rng = np.random.default_rng(3)
    if mode in ("I;16", "F"):
        a = rng.integers(0, 65536, (5, 7)).astype(np.uint16)
        im = Image.fromarray(a).convert(mode) if mode == "F" else Image.fromarray(a)
    else:
        im = Image.fromarray(rng.integers(0, 256, (5, 7, 3)).astype(np.uint8)).convert(mode)
    got = images.linear_rgb(im)
    if mode in ("I;16", "F"):
        scale = 65535.0 if mode == "I;16" else 1.0
        srgb = np.repeat(np.clip(np.asarray(im, np.float64) / scale, 0, 1)[..., None], 3, -1)
    else:
        srgb = np.asarray(im.convert("RGB"), np.float64) / 255.0
    want = srgb_to_linear(srgb).astype(np.float32)
    assert got.dtype == np.float32 and got.shape == (5, 7, 3)
    np.testing.assert_array_equal(got, want)


def test_the_limits_are_in_the_scene_format_doc():
    doc = (ROOT / "docs" / "scene-format.md").read_text()
    for value in (f"+-{limits.MAX_SCENE_NUMBER:.0e}".replace("e+0", "e"),
                  f"+-{limits.MAX_TIME:.0e}".replace("e+0", "e"),
                  f"{limits.MAX_TRIANGLES:,}", f"{limits.MAX_FRAME_PIXELS:,}",
                  f"{limits.MAX_IMAGE_PIXELS:,}", f"{limits.MAX_SCENE_IMAGE_PIXELS:,}",
                  f"{limits.MAX_GLTF_VERTICES:,}", f"{limits.MAX_GLTF_COMPONENTS:,}",
                  f"{limits.MAX_GLTF_FILE_BYTES >> 20} MiB", f"{limits.MAX_GLTF_NODES}",
                  f"{limits.MAX_GLTF_JOINTS}", f"{limits.MAX_GLTF_ITEMS}",
                  f"{limits.MAX_GLTF_JSON_DEPTH} levels", f"{limits.MAX_NAME_CHARS} characters",
                  f"{limits.MAX_OBJECTS}", "asset_file"):
        assert value in doc, value
