"""User blur passes (viewer/render/modes/user/, docs/api.md): the numpy example against a
per-pixel loop over the same buffers, the GLSL example against the numpy one, a Python
callable and a shader with the noise library, bench and graph showing the pass, a sweep
carrying the method's bytes, and every mistake in user code as its documented output."""
from __future__ import annotations

import json
import math
import pickle
import textwrap

import numpy as np
import pytest

import hybrid_mblur as hm
from viewer.commands.main import main
from viewer.sweep import run as sweep_run
from viewer.sweep.bundle import remove_copies
from viewer.sweep.cells import run_cell
from viewer.sweep.spec import load_sweep
from viewer.commands.main import version

from conftest import CONFORMANCE, ROOT
from sweep_helpers import own_temp_dir  # noqa: F401 (a fixture: no sweep copy left behind)

BASIC = str(CONFORMANCE / "basic.toml")
GLSL = str(ROOT / "docs/examples/naive_gather.frag")
NUMPY = str(ROOT / "docs/examples/numpy_gather.py")
SIZE = (40, 24)


def naive_gather_loop(color, velocity, k, taps=9):
    """The examples' filter written pixel by pixel from docs/api.md, in GL coordinates
    (row 0 at the bottom) and float32: the mean of `taps` colours at
    floor(x + 0.5 + t v), v = D/2 clamped to k, t evenly from -1 to 1."""
    h, w = color.shape[:2]
    out = np.zeros_like(color)
    f = np.float32
    for row in range(h):
        y = h - 1 - row
        for x in range(w):
            v = f(0.5) * velocity[row, x]
            n = np.sqrt(v[0] * v[0] + v[1] * v[1])
            if n > f(k):
                v = v * (f(k) / n)
            acc = np.zeros(3, np.float32)
            for i in range(taps):
                t = f(-1.0 + 2.0 * i / (taps - 1))
                px = min(max(math.floor(f(x) + f(0.5) + t * v[0]), 0), w - 1)
                py = min(max(math.floor(f(y) + f(0.5) + t * v[1]), 0), h - 1)
                acc += color[h - 1 - py, px]
            out[row, x] = acc / f(taps)
    return out


@pytest.fixture
def renderer(ctx):
    with hm.Renderer(size=SIZE, context=ctx) as r:
        r.register("np", hm.py_pass(NUMPY, "gather"))
        r.register("gl", hm.glsl_pass(GLSL))
        yield r


def test_the_numpy_example_is_the_filter_computed_pixel_by_pixel(renderer):
    scene = hm.load_scene(BASIC)
    res = renderer.render(scene, "np", buffers=True)
    b = res.buffers
    k = math.ceil(0.08 * SIZE[0])                  # blur.max_radius's default, in pixels
    want = naive_gather_loop(b["color"][..., :3], b["velocity"], k)
    assert np.allclose(res.image, want, rtol=0, atol=1e-6)
    off = renderer.render(scene, "off").image
    assert np.abs(res.image - off).max() > 0.05     # it blurs: the scene moves
    # The inputs are the G-buffer's: the user pipeline's colour is off's frame.
    assert np.array_equal(b["color"][..., :3], off)


def test_the_glsl_example_matches_the_numpy_example(renderer):
    scene = hm.load_scene(BASIC)
    for seed in (0, 5):
        gl = renderer.render(scene, "gl", seed=seed).image
        py = renderer.render(scene, "np", seed=seed).image
        assert np.abs(gl - py).max() < 1e-4
    off = renderer.render(scene, "off").image
    assert np.abs(gl - off).max() > 0.05


def test_a_callable_and_a_shader_with_the_noise_library(renderer, tmp_path):
    scene = hm.load_scene(BASIC)
    renderer.register("half", lambda inputs: inputs.color * np.float32(0.5))
    off = renderer.render(scene, "off").image
    assert np.array_equal(renderer.render(scene, "half").image, off * np.float32(0.5))
    frag = tmp_path / "noisy.frag"
    frag.write_text(textwrap.dedent("""\
        #version 330 core
        #include "graph/noise.glsl"
        uniform sampler2D u_color;
        out vec4 out_color;
        void main() {
            ivec2 x = ivec2(gl_FragCoord.xy);
            out_color = vec4(texelFetch(u_color, x, 0).rgb * hash01(x, 3u), 1.0);
        }
        """))
    renderer.register("noisy", hm.glsl_pass(frag))
    a, b = (renderer.render(scene, "noisy", seed=s).image for s in (1, 2))
    assert np.array_equal(a, renderer.render(scene, "noisy", seed=1).image)
    assert not np.array_equal(a, b)                  # keyed by the seed
    assert (a <= off + 1e-6).all()


def test_a_shader_reads_the_documented_inputs_and_uniforms(renderer, tmp_path):
    scene = hm.load_scene(BASIC)
    frag = tmp_path / "probe.frag"
    frag.write_text(textwrap.dedent("""\
        #version 330 core
        uniform sampler2D u_depth;
        uniform usampler2D u_id;
        uniform sampler2D u_neighbormax;
        uniform int u_tile;
        uniform float u_exposure;
        uniform vec2 u_size;
        out vec4 out_color;
        void main() {
            ivec2 x = ivec2(gl_FragCoord.xy);
            float depth = min(texelFetch(u_depth, x, 0).r, 1e6);
            float id = float(texelFetch(u_id, x, 0).r);
            float nm = texelFetch(u_neighbormax, x / u_tile, 0).x;
            out_color = vec4(x.x < 2 ? vec3(u_exposure, u_size.x, float(u_tile))
                                     : vec3(depth, id, nm), 1.0);
        }
        """))
    renderer.register("probe", hm.glsl_pass(frag))
    res = renderer.render(scene, "probe", buffers=True)
    b, img = res.buffers, res.image
    assert img[0, 0].tolist() == pytest.approx([scene.camera.shutter, SIZE[0], 4])
    assert np.array_equal(img[:, 2:, 0], np.minimum(b["depth"], 1e6)[:, 2:])
    assert np.array_equal(img[:, 2:, 1], b["id"][:, 2:].astype(np.float32))
    assert len(np.unique(b["id"])) > 2
    rows, cols = np.mgrid[0:SIZE[1], 0:SIZE[0]]
    inputs = hm.BlurInputs(b["color"][..., :3], b["depth"], b["velocity"], b["id"],
                           b["normal"][..., :3], b["user_tilemax"], b["user_neighbormax"],
                           tile=4, exposure=scene.camera.shutter, time=0.0, seed=0)
    tr, tc = inputs.tile_of(rows, cols)           # (the tiles count from the bottom-left)
    assert len(np.unique(b["user_neighbormax"][..., 0])) > 1
    assert np.array_equal(img[:, 2:, 2], b["user_neighbormax"][tr, tc, 0][:, 2:])


def test_motion_steps_average_the_user_pass_over_sub_exposures(renderer):
    scene = hm.load_scene(BASIC)
    one = renderer.render(scene, "np").image
    four = renderer.render(scene, "np", params={"motion.steps": 4})
    assert four.stats["steps"] == 4 and not np.array_equal(one, four.image)


def test_bench_times_the_glsl_pass_and_graph_shows_it(tmp_path, capsys):
    rep = tmp_path / "bench.json"
    assert main(["bench", BASIC, "--size", "32x18", "--frames", "2", "--warmup", "0",
                 "--modes", "mcguire", "--variant", f"mine=glsl:{GLSL}",
                 "--variant", f"np=py:{NUMPY}:gather", "--json", str(rep)]) == 0
    doc = json.loads(rep.read_text())
    assert list(doc["modes"]) == ["mcguire", "mine", "np"]
    assert doc["modes"]["mine"]["passes"]["glsl:naive_gather.frag"] > 0
    assert doc["modes"]["np"]["passes"]["py:numpy_gather.py:gather"] > 0
    assert "| mine |" in capsys.readouterr().out
    assert main(["graph", "--variant", f"mine=glsl:{GLSL}"]) == 0
    text = capsys.readouterr().out
    assert text.startswith("mode mine -> user")
    assert ("  glsl:naive_gather.frag: color, depth, velocity, id, normal, user_tilemax, "
            "user_neighbormax -> user") in text


def test_a_sweep_carries_the_method_bytes_and_keys_cells_by_them(tmp_path):
    method = tmp_path / "gather.frag"
    method.write_bytes((ROOT / "docs/examples/naive_gather.frag").read_bytes())
    (tmp_path / "blur.py").write_bytes((ROOT / "docs/examples/numpy_gather.py").read_bytes())
    spec_file = tmp_path / "s.toml"
    spec_file.write_text(textwrap.dedent(f"""\
        scenes = ["{BASIC}"]
        size = "32x18"
        samples = 2
        [variants.mine]
        mode = "glsl:gather.frag"
        [variants.np]
        mode = "py:blur.py:gather"
        """))
    spec = load_sweep(spec_file)
    (task,), bundles = sweep_run.tasks_of(spec, version(), False, False, "u1")
    moved = pickle.loads(pickle.dumps(task))          # as Dask sends it to a worker
    key = task.key
    method.write_text(method.read_text() + "\n// an edit\n")
    assert sweep_run.tasks_of(load_sweep(spec_file), version(), False, False,
                              "u2")[0][0].key != key
    method.unlink()                                   # the worker needs no copy of it
    result = run_cell(moved, bundles[moved.digest])
    remove_copies("u1")                               # (a sweep's end removes them)
    assert result["error"] is None
    rows = {(r["variant"], r["region"]): r for r in result["rows"]}
    assert rows[("mine", "all")]["flip"] == pytest.approx(rows[("np", "all")]["flip"], abs=1e-3)
    facts = sweep_run.run_sweep(spec, tmp_path / "out", version(), 0, None, False, False,
                                stream=open(tmp_path / "log", "w"))
    assert facts["failed"] == 0
    table = (tmp_path / "out/table.csv").read_text().splitlines()
    assert any(",mine,glsl," in line for line in table)
    assert any(",np,py," in line for line in table)


def cli_error(capsys, args) -> tuple[int, str]:
    code = main(args)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("name,text,variant,words", [
    ("broken.frag", "#version 330 core\nuniform sampler2D u_color;\nout vec4 out_color;\n"
     "void main() {\n    out_color = vec4(undefined_gain);\n}\n", "glsl:{}",
     "broken.frag:5: error:"),
    ("old.frag", "void main() {}\n", "glsl:{}", "old.frag:1: expected '#version 330 core'"),
    ("shape.py", "def f(inputs):\n    return inputs.color.mean(axis=2)\n", "py:{}:f",
     "returned an array of shape (18, 32), dtype float32; expected a numpy array of shape "
     "(18, 32, 3), dtype float (linear RGB)"),
    ("dtype.py", "def f(inputs):\n    return (inputs.color * 255).astype('uint8')\n",
     "py:{}:f", "returned an array of shape (18, 32, 3), dtype uint8; expected"),
    ("nan.py", "import numpy as np\ndef f(inputs):\n    return inputs.color * np.nan\n",
     "py:{}:f", "returned 1728 values that are not finite"),
    ("list.py", "def f(inputs):\n    return [0, 0, 0]\n", "py:{}:f", "returned list;"),
    ("nofn.py", "def g(inputs):\n    return inputs.color\n", "py:{}:f",
     "no function 'f' (it defines g)"),
    ("syntax.py", "def f(inputs)\n    return 1\n", "py:{}:f", "syntax.py:1: SyntaxError"),
])
def test_mistakes_in_user_code_are_one_line_and_write_nothing(tmp_path, capsys, name, text,
                                                              variant, words):
    (tmp_path / name).write_text(text)
    out = tmp_path / "out"
    code, err = cli_error(capsys, ["compare", BASIC, "--size", "32x18", "--samples", "2",
                                   "--out", str(out), "--variant",
                                   "mine=" + variant.format(tmp_path / name)])
    lines = [line for line in err.splitlines() if not line.startswith("reference")]
    assert code == 2 and len(lines) == 1 and lines[0].startswith("hmblur: error: ")
    assert words in lines[0]
    assert str(tmp_path / name) in lines[0]
    assert not out.exists()


def test_a_raising_method_shows_its_own_frames_only(tmp_path, capsys):
    blur = tmp_path / "blur.py"
    blur.write_text("def weights(n):\n    return [1 / (n - 4)] * n\n\n\n"
                    "def gather(inputs):\n    w = weights(4)\n    return inputs.color * sum(w)\n")
    out = tmp_path / "out"
    code, err = cli_error(capsys, ["compare", BASIC, "--size", "32x18", "--samples", "2",
                                   "--out", str(out), "--variant", f"mine=py:{blur}:gather"])
    lines = [line for line in err.splitlines() if not line.startswith("reference")]
    assert code == 2 and not out.exists()
    assert lines == [
        f"hmblur: error: method mine (py:{blur}:gather): ZeroDivisionError: division by zero",
        f'  File "{blur}", line 6, in gather',
        "    w = weights(4)",
        f'  File "{blur}", line 2, in weights',
        "    return [1 / (n - 4)] * n"]
    # In Python: MethodError, chained to the user's own exception.
    with hm.Renderer(size=(32, 18)) as r:
        r.register("mine", hm.py_pass(blur, "gather"))
        with pytest.raises(hm.MethodError) as info:
            r.render(hm.load_scene(BASIC), "mine")
    assert isinstance(info.value.__cause__, ZeroDivisionError)
    assert info.value.frames[0] == f'  File "{blur}", line 6, in gather'


def test_a_raising_method_in_a_sweep_is_an_error_row(tmp_path):
    (tmp_path / "bad.py").write_text("def f(inputs):\n    raise RuntimeError('no')\n")
    p = tmp_path / "s.toml"
    p.write_text(f'scenes = ["{BASIC}"]\nsize = "32x18"\nsamples = 2\n'
                 '[variants.mcguire]\nmode = "mcguire"\n[variants.bad]\nmode = "py:bad.py:f"\n')
    facts = sweep_run.run_sweep(load_sweep(p), tmp_path / "out", version(), 0, None, False,
                                False, stream=open(tmp_path / "log", "w"))
    assert facts["failed"] == 1
    assert "method bad (py:bad.py:f): RuntimeError: no" in (tmp_path / "out/summary.md").read_text()


def test_shot_renders_a_user_pass_and_its_sidecar_renders_it_again(tmp_path, capsys):
    """`hmblur shot --mode glsl:PATH` (and py:PATH:FUNCTION): the pass's image, the same
    pixels as the API's, and a sidecar that `--params` renders again byte for byte."""
    for spec in (f"glsl:{GLSL}", f"py:{ROOT / 'docs/examples/numpy_gather.py'}:gather"):
        out = tmp_path / "a.png"
        assert main(["shot", str(CONFORMANCE / "basic.toml"), "--size", "64x36", "--mode",
                     spec, "--out", str(out)]) == 0
        side = json.loads(out.with_suffix(".json").read_text())
        assert side["mode"] == spec and sorted(side["params"]) == ["blur", "motion"]
        again = tmp_path / "b.png"
        assert main(["shot", "--params", str(out.with_suffix(".json")), "--out",
                     str(again)]) == 0
        assert again.read_bytes() == out.read_bytes()
        with hm.Renderer((64, 36)) as r:
            r.register("mine", spec)
            api = r.render(str(CONFORMANCE / "basic.toml"), "mine")
        from PIL import Image
        assert np.array_equal(np.asarray(Image.open(out))[..., :3], api.srgb)
    capsys.readouterr()
    bad = tmp_path / "broken.frag"
    bad.write_text("#version 330 core\nout vec4 c;\nvoid main() { c = nothing; }\n")
    assert main(["shot", str(CONFORMANCE / "basic.toml"), "--mode", f"glsl:{bad}",
                 "--out", str(tmp_path / "c.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "broken.frag:3" in err and not (tmp_path / "c.png").exists()


def test_video_draws_a_user_pass_as_shot_does_and_its_sidecar_draws_it_again(tmp_path):
    """`hmblur video --variant mine=glsl:PATH`: one variant alone is its bare image, the
    pixels shot writes at that time; the sidecar names the variant, so --params draws the
    same frames."""
    folder = tmp_path / "frames"
    assert main(["video", BASIC, "--size", "64x36", "--frames", "2", "--variant",
                 f"mine=glsl:{GLSL}", "--out", f"{folder}/"]) == 0
    side = json.loads((folder / "video.json").read_text())
    assert side["modes"] == [] and side["variants"] == [f"mine=glsl:{GLSL}"]
    shot = tmp_path / "s.png"
    assert main(["shot", BASIC, "--size", "64x36", "--mode", f"glsl:{GLSL}",
                 "--out", str(shot)]) == 0
    assert (folder / "frame_0000.png").read_bytes() == shot.read_bytes()
    again = tmp_path / "again"
    assert main(["video", "--params", str(folder / "video.json"), "--out", f"{again}/"]) == 0
    for k in range(2):
        name = f"frame_{k:04d}.png"
        assert (again / name).read_bytes() == (folder / name).read_bytes()
