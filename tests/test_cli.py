"""The command line: a user's mistake is one line on stderr and exit status 2, with no
traceback and no output file; good input gives deterministic files."""
import json
import os
import stat
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from PIL import Image

from viewer.commands.main import main

from conftest import CONFORMANCE, ROOT

BASIC = str(CONFORMANCE / "basic.toml")


def write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return str(p)


GOOD = """
    [camera]
    position = [0.0, 0.0, 3.0]
    look_at = [0.0, 0.0, 0.0]
    fov_y = 45.0
    [[objects]]
    mesh = { box = [1.0, 1.0, 1.0] }
"""


def bad_cases(tmp_path):
    out = str(tmp_path / "o.png")
    (tmp_path / "s.json").mkdir(exist_ok=True)
    (tmp_path / "f.txt").write_text("a file, not a folder")
    fifo = str(tmp_path / "fifo.png")
    if not os.path.exists(fifo):
        os.mkfifo(fifo)

    made = []

    def sidecar(**kw):
        doc = {"params": {}, "scene_name": "basic", **kw}
        made.append(kw)
        return write(tmp_path, f"p_{'_'.join(kw)}{len(made)}.json", json.dumps(doc))
    return {
        "unknown scene name": (["shot", "no_such_scene", "--out", out], "built-in scenes"),
        "missing file": (["shot", str(tmp_path / "missing.toml"), "--out", out], "file not found"),
        "TOML syntax error": (["shot", write(tmp_path, "syn.toml", "[camera\nx = 1\n"), "--out", out], "syn.toml"),
        "unknown key": (["shot", write(tmp_path, "uk.toml", GOOD + "colour = 1\n"), "--out", out], "colour"),
        "wrong type": (["shot", write(tmp_path, "wt.toml", GOOD.replace("fov_y = 45.0", 'fov_y = "wide"')), "--out", out], "fov_y"),
        "wrong vector length": (["shot", write(tmp_path, "vl.toml", GOOD.replace("[0.0, 0.0, 3.0]", "[0.0, 3.0]")), "--out", out], "camera.position"),
        "NaN": (["shot", write(tmp_path, "nan.toml", GOOD.replace("fov_y = 45.0", "fov_y = nan")), "--out", out], "fov_y"),
        "bad --size": (["shot", BASIC, "--size", "12xab", "--out", out], "--size"),
        "zero --size": (["shot", BASIC, "--size", "0x10", "--out", out], "--size"),
        "size beyond the frame limit": (["shot", BASIC, "--size", "100000x10", "--out", out], "too large"),
        "unknown --set key": (["shot", BASIC, "--set", "mcguire.nope=3", "--out", out], "nope"),
        "unknown --set group": (["shot", BASIC, "--set", "nope.x=3", "--out", out], "nope"),
        "--set value out of range": (["shot", BASIC, "--set", "reference.samples=0", "--out", out], "at least"),
        "--set wrong type": (["shot", BASIC, "--set", "reference.samples=many", "--out", out], "expected int"),
        "unknown mode": (["shot", BASIC, "--mode", "fancy", "--out", out], "--mode"),
        "zero samples": (["shot", BASIC, "--mode", "reference", "--samples", "0", "--out", out], "--samples"),
        "NaN time": (["shot", BASIC, "--time", "nan", "--out", out], "--time"),
        "output folder under a file": (["shot", BASIC, "--out", str(tmp_path / "f.txt" / "o.png")],
                                       "is not a folder"),
        "--out not a PNG": (["shot", BASIC, "--out", str(tmp_path / "e.jpg")],
                            "--out " + str(tmp_path / "e.jpg") + ": expected a path ending in .png"),
        "--set for a group the mode does not use": (
            ["shot", BASIC, "--mode", "off", "--set", "blur.max_radius=0.1", "--out", out],
            "mode off does not use the blur parameters (used by mcguire, ue4, guertin, hybrid)"),
        "--set for a group compare does not render": (
            ["compare", BASIC, "--modes", "off,ue4", "--set", "mcguire.samples=9", "--out",
             str(tmp_path / "c")], "modes off, ue4, reference does not use the mcguire"),
        "--samples without the reference": (["shot", BASIC, "--mode", "mcguire", "--samples", "8",
                                             "--out", out], "only the reference mode"),
        "no SCENE and no --params": (["shot", "--out", out], "SCENE: expected a scene file"),
        "--params without a scene, SCENE left out": (
            ["shot", "--params", write(tmp_path, "ns.json", '{"params": {}}'), "--out", out],
            "names no scene"),
        "unknown mode for params": (["params", "fancy"], "params fancy: expected one of"),
        "a conformance scene by name": (["shot", "basic", "--out", out],
                                        "'basic' is the scene file tests/conformance/basic.toml"),
        "a bench scene by name": (["shot", "crowd", "--out", out],
                                  "'crowd' is the scene file scenes/bench/crowd.toml"),
        "a bad value in a viewer script": (
            ["view", BASIC, "--frames", "1", "--script", write(tmp_path, "bad.script",
                                                               "2 mode hybird\n")],
            "--script bad.script:1: mode: expected one of off, reference, mcguire"),
        "--screenshot not a PNG": (["view", BASIC, "--frames", "1", "--screenshot",
                                    str(tmp_path / "w.jpg")], "expected a path ending in .png"),
        "output is a folder": (["shot", BASIC, "--out", str(tmp_path)], "is a directory"),
        "--params not JSON": (["shot", BASIC, "--params", write(tmp_path, "p.json", "{oops"), "--out", out], "not JSON"),
        "unknown subcommand": (["paint", BASIC], "invalid choice"),
        "missing --out": (["shot", BASIC], "shot: the following arguments are required: --out"),
        "--out where its sidecar goes": (["shot", BASIC, "--out", str(tmp_path / "o.json")],
                                         "expected a path ending in .png"),
        "a folder where the sidecar goes": (["shot", BASIC, "--out", str(tmp_path / "s.png")],
                                            "s.json"),
        "--out a FIFO": (["shot", BASIC, "--out", fifo], "not a regular file"),
        "--out ending in /": (["shot", BASIC, "--out", out + "/"], "is a directory"),
        "time past the transforms' range": (["shot", BASIC, "--time", "1e300", "--out", out],
                                            "--time"),
        "--params not a sidecar": (["shot", BASIC, "--params",
                                    write(tmp_path, "foo.json", '{"foo": 1}'), "--out", out],
                                   "params"),
        "--params size not a list": (["shot", BASIC, "--params", sidecar(size=5), "--out", out],
                                     "size"),
        "--params of another scene": (["shot", BASIC, "--params", sidecar(scene_name="pan"),
                                       "--out", out], "made for scene 'pan'"),
        "--params camera fov 0": (["shot", BASIC, "--params", sidecar(camera={"fov_y": 0}),
                                   "--out", out], "camera.fov_y"),
        "--params camera up along the view": (
            ["shot", BASIC, "--params", sidecar(camera={"up": [0.0, 0.0, 1.0],
                                                        "position": [0.0, 0.0, 3.0],
                                                        "look_at": [0.0, 0.0, 0.0]}),
             "--out", out], "camera.up"),
        "--params bad parameter": (["shot", BASIC, "--params",
                                    sidecar(params={"hybrid": {"seeds": 100}}), "--out", out],
                                   ".json: hybrid.seeds: expected at most"),
        "bad --inset": (["compare", BASIC, "--inset", "abc", "--out", str(tmp_path / "c")],
                        "--inset"),
        "no --modes": (["compare", BASIC, "--modes", ",", "--out", str(tmp_path / "c")],
                       "--modes"),
        "a mode twice": (["bench", BASIC, "--modes", "mcguire,mcguire"], "listed twice"),
        "--animate too slow": (["bench", BASIC, "--animate", "1e-300"], "--animate"),
        "--speeds too fast": (["bench", BASIC, "--speeds", "1e308"], "--speeds"),
        "empty --json": (["bench", BASIC, "--json", ""], "--json '': expected a file path"),
        "empty --buffers": (["shot", BASIC, "--buffers", "", "--out", out],
                            "--buffers '': expected a folder path"),
    }


def test_every_user_mistake_is_one_line_and_exit_2(tmp_path, capsys):
    for name, (argv, needle) in bad_cases(tmp_path).items():
        code = main(argv)
        err = capsys.readouterr().err
        assert code == 2, name
        lines = err.strip().splitlines()
        assert len(lines) == 1, (name, err)
        assert lines[0].startswith("hmblur: error: "), (name, err)
        assert not lines[0].startswith(("hmblur: error: hmblur", "hmblur: error: error")), err
        assert needle in lines[0], (name, lines[0])
        assert "Traceback" not in err
        assert not (tmp_path / "o.png").exists(), name
        assert not (tmp_path / "s.png").exists(), name
        assert not (tmp_path / "c").exists(), name         # no folder made for nothing
    assert stat.S_ISFIFO(os.stat(tmp_path / "fifo.png").st_mode)    # not replaced


def test_an_error_after_a_progress_bar_starts_on_its_own_line():
    import io
    from viewer.io.progress import Progress, end_line

    class Tty(io.StringIO):
        def isatty(self):
            return True
    err = Tty()
    bar = Progress("reference", err)
    bar(0, 4)                                   # cut short: the line stays open
    end_line()
    end_line()                                  # (once only)
    err.write("hmblur: error: x\n")
    assert err.getvalue().splitlines()[-1] == "hmblur: error: x"
    assert err.getvalue().count("\n") == 2
    done = Tty()
    Progress("reference", done)(0, 1)           # finished: its line is closed
    end_line()
    assert done.getvalue().count("\n") == 1
    # The sweep's line follows the same rule: open while cells are left, closed at the end.
    from viewer.sweep.run import Bar
    sweep = Tty()
    cells = Bar(2, 0, sweep)
    cells.update(False)
    assert sweep.getvalue().startswith("\rsweep: 1/2 cells done") and "\n" not in sweep.getvalue()
    end_line()
    assert sweep.getvalue().endswith("\n")
    cells.update(True)
    end_line()
    assert sweep.getvalue().count("\n") == 2 and "1 failed, 0 left" in sweep.getvalue()


def test_unwritable_output_folder(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(os, "access", lambda path, mode: False)
    assert main(["shot", BASIC, "--out", str(tmp_path / "o.png")]) == 2
    assert "not writable" in capsys.readouterr().err


def test_a_real_process_exits_2_without_traceback(tmp_path):
    p = subprocess.run([sys.executable, "-m", "viewer", "shot", "no_such_scene", "--out",
                        str(tmp_path / "x.png")], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "Traceback" not in p.stderr


def test_shot_is_deterministic_and_writes_a_sidecar(tmp_path, capsys):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    for out in (a, b):
        assert main(["shot", BASIC, "--mode", "reference", "--samples", "8",
                     "--size", "96x54", "--out", str(out)]) == 0
    assert a.read_bytes() == b.read_bytes()
    side = json.loads((tmp_path / "a.json").read_text())
    assert side["mode"] == "reference" and side["size"] == [96, 54]
    assert side["params"]["reference"]["samples"] == 8
    img = np.asarray(Image.open(a))
    assert img.shape == (54, 96, 3) and img.dtype == np.uint8
    assert [f.name for f in tmp_path.iterdir() if f.name.startswith(".")] == []


def test_params_sidecar_reproduces_the_image(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert main(["shot", BASIC, "--mode", "reference", "--samples", "4", "--size", "64x40",
                 "--time", "0.01", "--out", str(a)]) == 0
    assert main(["shot", BASIC, "--mode", "reference", "--params", str(tmp_path / "a.json"),
                 "--out", str(b)]) == 0
    assert a.read_bytes() == b.read_bytes()


def test_compare_writes_images_regions_and_metrics_recomputable_from_them(tmp_path, capsys):
    """`hmblur compare`: every mode's PNG and sidecar, the reference, the region map, the
    strip, metrics.md and metrics.json (with the space the numbers are in); the same
    outputs twice over, and the metrics those of the written PNGs and region map."""
    from viewer.eval.metrics import image_metrics
    from viewer.render.modes.regions import INNER, OUTER
    runs = [tmp_path / "a", tmp_path / "b"]
    for out in runs:
        assert main(["compare", BASIC, "--size", "64x40", "--samples", "4",
                     "--modes", "mcguire,hybrid", "--out", str(out)]) == 0
    names = {"mcguire.png", "mcguire.json", "hybrid.png", "hybrid.json", "reference.png",
             "reference.json", "regions.png", "strip.png", "flip.png", "metrics.md",
             "metrics.json"}
    # (and hmblur's list of the files it wrote there)
    assert {f.name for f in runs[0].iterdir()} == names | {".hmblur-outputs.json"}
    for name in names - {"metrics.json", "metrics.md"}:
        if name.endswith(".png"):
            assert (runs[0] / name).read_bytes() == (runs[1] / name).read_bytes(), name
    m = json.loads((runs[0] / "metrics.json").read_text())
    assert "8-bit codes / 255" in m["space"] and "Space: sRGB" in (runs[0] / "metrics.md").read_text()
    pic = np.asarray(Image.open(runs[0] / "regions.png"))[:40]     # the map; its key below
    region = np.zeros(pic.shape[:2], np.uint8)
    region[(pic == (230, 60, 40)).all(-1)] = INNER
    region[(pic == (40, 110, 230)).all(-1)] = OUTER
    assert m["regions"] == {"all": 64 * 40, "static": int((region == 0).sum()),
                            "inner": int((region == INNER).sum()),
                            "outer": int((region == OUTER).sum())}
    assert m["regions"]["inner"] > 20 and m["regions"]["outer"] > 20
    ref = np.asarray(Image.open(runs[0] / "reference.png"))
    for mode in ("mcguire", "hybrid"):
        got = image_metrics(np.asarray(Image.open(runs[0] / f"{mode}.png")), ref, region)
        for part, row in got.items():
            for key in ("psnr", "ssim", "flip"):
                assert m["metrics"][mode][part][key] == pytest.approx(row[key], abs=1e-9)
    assert m["metrics"]["hybrid"]["inner"]["flip"] < m["metrics"]["mcguire"]["inner"]["flip"]


def test_params_gives_mode_and_seed_unless_flags_say_otherwise(tmp_path):
    side = tmp_path / "side.json"
    side.write_text(json.dumps({"params": {}, "scene_name": "basic", "mode": "mcguire",
                                "seed": 5, "size": [48, 30]}))
    assert main(["shot", BASIC, "--params", str(side), "--out", str(tmp_path / "a.png")]) == 0
    a = json.loads((tmp_path / "a.json").read_text())
    assert a["mode"] == "mcguire" and a["seed"] == 5 and a["size"] == [48, 30]
    assert main(["shot", BASIC, "--params", str(side), "--seed", "0", "--mode", "off",
                 "--out", str(tmp_path / "b.png")]) == 0
    b = json.loads((tmp_path / "b.json").read_text())
    assert b["mode"] == "off" and b["seed"] == 0


def test_compare_of_an_image_smaller_than_the_ssim_window(tmp_path):
    assert main(["compare", BASIC, "--size", "6x5", "--samples", "2", "--modes", "hybrid",
                 "--out", str(tmp_path / "c")]) == 0
    m = json.loads((tmp_path / "c" / "metrics.json").read_text())
    assert m["metrics"]["hybrid"]["all"]["ssim"] is None
    # FLIP has no window: its mean over the written PNGs, from the evaluator itself.
    import flip_evaluator
    png = [np.asarray(Image.open(tmp_path / "c" / f"{n}.png"), np.float32) / 255
           for n in ("reference", "hybrid")]
    want = float(np.mean(flip_evaluator.evaluate(*png, "LDR", applyMagma=False)[0]))
    assert m["metrics"]["hybrid"]["all"]["flip"] == pytest.approx(want, rel=1e-6, abs=1e-9)


def test_a_write_that_fails_is_one_line_and_leaves_no_output(tmp_path, capsys, monkeypatch):
    # A full disk (ENOSPC) while compare writes its files: none of them appears.
    import viewer.io.imageio as io
    real = io._write_temp
    calls = []

    def failing(path, write, made=None):
        calls.append(path)
        if len(calls) == 3:
            raise OSError(28, "No space left on device", str(path))
        return real(path, write, made)
    monkeypatch.setattr(io, "_write_temp", failing)
    out = tmp_path / "c" / "d"                   # two missing folders: both made, both undone
    assert main(["compare", BASIC, "--size", "32x20", "--samples", "2", "--modes", "mcguire",
                 "--out", str(out)]) == 2
    err = [x for x in capsys.readouterr().err.splitlines() if x.startswith("hmblur")]
    assert len(err) == 1 and err[0].endswith("reference.png: No space left on device")
    assert not (tmp_path / "c").exists()


def test_buffers_are_dumped(tmp_path):
    d = tmp_path / "bufs"
    assert main(["shot", BASIC, "--mode", "off", "--size", "64x40", "--out",
                 str(tmp_path / "o.png"), "--buffers", str(d)]) == 0
    for name in ("color", "depth", "normal", "id", "velocity"):
        assert (d / f"{name}.npy").exists() and (d / f"{name}.png").exists()
    ids = np.load(d / "id.npy")
    assert ids.shape == (40, 64) and ids.dtype == np.uint32 and set(np.unique(ids)) >= {0, 1}


def test_no_gl_driver_names_what_to_install(tmp_path):
    env = dict(os.environ, __EGL_VENDOR_LIBRARY_FILENAMES=str(tmp_path / "none.json"))
    p = subprocess.run([sys.executable, "-m", "viewer", "shot", BASIC, "--out",
                        str(tmp_path / "x.png")], capture_output=True, text=True, cwd=ROOT, env=env)
    assert p.returncode == 2
    assert p.stderr.count("\n") == 1 and "apt-get install libegl1" in p.stderr
    assert not (tmp_path / "x.png").exists()


def test_bench_reports_every_mode_pass_ratio_and_the_reveal(tmp_path, capsys, ctx):
    out = tmp_path / "bench.json"
    assert main(["bench", BASIC, "--size", "96x54", "--frames", "2", "--warmup", "0",
                 "--json", str(out), "--speeds", "0.5,1",
                 "--set", "hybrid.range_check=true"]) == 0
    rep = json.loads(out.read_text())
    assert rep["size"] == [96, 54] and rep["device"]
    # The settings measured, readable back by --params.
    assert rep["params"]["hybrid"]["range_check"] is True and rep["seed"] == 0
    from argparse import Namespace

    from viewer.cli.args import setup
    back = setup(Namespace(params=str(out), scene=BASIC, size=None, time=None, seed="0",
                           set=[]))
    assert back.params["hybrid"].range_check is True and back.size == (96, 54)
    # The driver's own method (CPU clock on software GL, timer queries on a GPU); times are
    # the bench's to report, not the tests' to judge: only their bookkeeping is checked.
    from viewer.render.graph.registry import build
    from viewer.render.timing import PassClock, describe
    assert rep["pass_timing"] == describe(PassClock(ctx).method)
    assert set(rep["modes"]) == {"off", "mcguire", "ue4", "guertin", "hybrid"}
    for mode, r in rep["modes"].items():
        assert r["frame"]["n"] == 2 and r["frame_ms"] == r["frame"]["median"]
        assert r["frame"]["p10"] <= r["frame"]["median"] <= r["frame"]["p90"]
        # Every pass of the mode timed, in wall and in host CPU time; the bend measure
        # where the mode's curve steps can start (the hybrid's default).
        bend = {"motion_bend"} if mode == "hybrid" else set()
        # (the passes of the configuration measured: the range check's)
        assert set(r["passes"]) == {p.name for p in build(mode, back.params).passes} | bend
        assert set(r["passes_cpu"]) == set(r["passes"]) and "frame_cpu_ms" in r
    hyb = rep["modes"]["hybrid"]
    assert {"select_tiles", "ray_mask", "reveal", "reveal_shade", "hybrid_composite"} <= set(hyb["passes"])
    for m in ("hybrid", "ue4"):
        assert rep["ratios"][f"{m}/mcguire"] == pytest.approx(
            rep["modes"][m]["frame_ms"] / rep["modes"]["mcguire"]["frame_ms"])
    rv = rep["reveal"]
    assert rv["rays"] >= rv["masked_pixels"] > 0
    assert rv["rays_per_s"] == pytest.approx(rv["rays"] / (rv["reveal_ms"] / 1e3))
    assert rv["fraction_of_embree"] == pytest.approx(rv["rays_per_s"] / rv["embree_rays_per_s"])
    # The fraction a reveal would reach that traced at bare Embree's speed and did nothing
    # else but read the mask back.
    bare_ms = 1e3 * rv["masked_pixels"] / rv["embree_rays_per_s"]
    assert {"readback_ms", "reveal_ms", "records_ms"} <= set(rv)
    assert rv["fraction_with_bare_tracing"] == pytest.approx(
        1e3 * rv["rays"] / (bare_ms + rv["readback_ms"]) / rv["embree_rays_per_s"])
    # Slower objects mask fewer pixels.
    scaling = rep["scaling"]
    assert [row["speed"] for row in scaling] == [0.5, 1.0]
    assert 0 < scaling[0]["masked_pixels"] < scaling[1]["masked_pixels"]
    text = capsys.readouterr().out
    assert "hybrid/mcguire" in text and "bare Embree" in text


def test_bench_animates_frame_after_frame(tmp_path, capsys, monkeypatch):
    from viewer.render.renderer import Renderer
    from viewer.render.timing import PassClock
    times = []
    render, timed = Renderer.render, PassClock.render
    monkeypatch.setattr(Renderer, "render", lambda self, mode, t, *a, **k: (
        times.append((mode, t)), render(self, mode, t, *a, **k))[1])
    monkeypatch.setattr(PassClock, "render", lambda self, r, mode, t, *a, **k: (
        times.append((mode, t)), timed(self, r, mode, t, *a, **k))[1])
    out = tmp_path / "bench.json"
    assert main(["bench", BASIC, "--size", "96x54", "--frames", "2", "--warmup", "0",
                 "--modes", "mcguire,hybrid", "--animate", "50", "--json", str(out)]) == 0
    rep = json.loads(out.read_text())
    assert rep["animate_fps"] == 50 and rep["modes"]["hybrid"]["frame"]["n"] == 2
    # Per mode: (previous frame, timed frame, timed passes) at t - dt, t, t + dt, t advancing.
    hybrid = [t for mode, t in times if mode == "hybrid"]
    assert hybrid == pytest.approx([0.0, 0.02, 0.04, 0.02, 0.04, 0.06])
    assert main(["bench", BASIC, "--animate", "0"]) == 2
    assert "--animate 0" in capsys.readouterr().err


def test_bench_pass_times_by_gpu_timer_queries_on_request(tmp_path):
    # The path a GPU driver takes by default; on llvmpipe the queries see submission
    # only, but every pass still gets a time.
    out = tmp_path / "bench.json"
    assert main(["bench", BASIC, "--size", "96x54", "--frames", "1", "--warmup", "0",
                 "--modes", "hybrid", "--pass-timers", "gpu", "--json", str(out)]) == 0
    rep = json.loads(out.read_text())
    assert rep["pass_timing"] == "GPU timer queries"
    passes = rep["modes"]["hybrid"]["passes"]
    assert {"gbuffer", "reveal", "hybrid_composite"} <= set(passes)
    from viewer.render.modes import MODES
    assert set(passes) == {p.name for p in MODES["hybrid"]().passes} | {"motion_bend"}


def test_bench_rejects_an_unknown_mode(capsys):
    assert main(["bench", BASIC, "--modes", "mcguire,fancy"]) == 2
    assert "fancy" in capsys.readouterr().err


# --- a newcomer's first hour -------------------------------------------------------------

def test_version_bare_command_and_one_error_prefix(capsys):
    import tomllib
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert capsys.readouterr().out.strip() == f"hmblur {version}"
    assert main([]) == 2                           # bare: the usage and commands, on stderr
    err = capsys.readouterr().err
    assert err.startswith("usage: hmblur") and all(c in err for c in
                                                   ("shot", "compare", "bench", "view", "params"))
    assert main(["shot", BASIC]) == 2
    assert capsys.readouterr().err == ("hmblur: error: shot: the following arguments are "
                                       "required: --out\n")


def test_help_is_complete(capsys):
    # Every flag of every command in its --help, --mode shown as optional with its default.
    flags = {"shot": ["--mode", "--out", "--buffers", "--time", "--size", "--samples", "--seed",
                      "--set", "--params"],
             "compare": ["--out", "--modes", "--inset"],
             "bench": ["--frames", "--warmup", "--modes", "--json", "--animate", "--pass-timers",
                       "--speeds"],
             "view": ["--mode", "--frames", "--screenshot", "--script", "--stats-json",
                      "--shot-dir", "O ", "overlay", "resize"]}
    for command, names in flags.items():
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        for name in names:
            assert name in text, (command, name)
        if "--mode" in names:
            assert "[--mode MODE]" in text and "(default: hybrid" in text


# Every command's flags. The render commands share SCENE_FLAGS (viewer/cli/args.py), bench
# without --samples (it draws no reference); README's "Commands" says so.
SHARED = {"--time", "--size", "--samples", "--seed", "--shutter", "--set", "--params"}
COMMAND_FLAGS = {
    "shot": SHARED | {"--mode", "--out", "--buffers"},
    "compare": SHARED | {"--out", "--modes", "--variant", "--inset"},
    "bench": SHARED - {"--samples"} | {"--frames", "--warmup", "--modes", "--json", "--animate",
                                       "--pass-timers", "--speeds", "--variant"},
    "video": SHARED | {"--start", "--out", "--modes", "--frames", "--fps", "--metrics", "--variant"},
    "view": SHARED | {"--mode", "--frames", "--screenshot", "--script", "--stats-json",
                      "--record", "--record-fps", "--shot-dir"},
    "params": set(),
    "graph": {"--set", "--params", "--variant"},
    "scene": {"--out"},
    "sweep": {"--out", "--workers", "--scheduler", "--images", "--timing"},
}


def test_every_commands_flags_against_the_table():
    from viewer.cli.args import SCENE_FLAGS
    from viewer.commands.main import COMMANDS, build_parser
    assert set(SCENE_FLAGS) == SHARED
    parser = build_parser()
    (sub,) = [a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction"]
    assert set(sub.choices) == set(COMMANDS) == set(COMMAND_FLAGS)
    for name, p in sub.choices.items():
        flags = {o for a in p._actions for o in a.option_strings} - {"-h", "--help"}
        assert flags == COMMAND_FLAGS[name], name
    video = sub.choices["video"]
    assert video.parse_args(["--start", "0.5", "--out", "v"]).time == "0.5"
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert ("`shot`, `compare`, `bench`, `video`, `view` also take `--time T`" in readme
            and "all but `bench` `--samples N`" in readme)
    for flag in sorted(SHARED - {"--samples"}):
        assert f"`{flag} " in readme, flag


def test_shared_flags_act_or_are_refused(tmp_path, capsys):
    out = tmp_path / "a.png"
    assert main(["shot", BASIC, "--size", "32x18", "--shutter", "0.125", "--out", str(out)]) == 0
    side = json.loads(out.with_suffix(".json").read_text())
    assert side["camera"]["shutter"] == 0.125
    again = tmp_path / "b.png"
    assert main(["shot", "--params", str(out.with_suffix(".json")), "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()
    plain = tmp_path / "c.png"
    assert main(["shot", BASIC, "--size", "32x18", "--out", str(plain)]) == 0
    assert plain.read_bytes() != out.read_bytes()
    capsys.readouterr()
    refused = [
        (["shot", BASIC, "--mode", "off", "--shutter", "0.1"], "--shutter 0.1: mode off"),
        (["shot", BASIC, "--shutter", "-1"], "--shutter '-1': expected an exposure time from 0"),
        (["shot", BASIC, "--shutter", "1e8"], "--shutter '1e8': expected an exposure time from 0"),
        (["compare", BASIC, "--shutter", "inf"], "--shutter 'inf': expected a finite number"),
        (["video", BASIC, "--modes", "off", "--shutter", "0.1"], "--shutter 0.1: mode off"),
        (["video", BASIC, "--modes", "off,hybrid", "--samples", "4"],
         "--samples 4: only the reference mode takes sub-frames, not modes off, hybrid"),
        (["video", BASIC, "--start", "soon"], "--time 'soon': expected a number"),
        (["bench", BASIC, "--modes", "off", "--shutter", "0.1"], "--shutter 0.1: mode off"),
        (["bench", BASIC, "--samples", "4"], "unrecognized arguments: --samples 4"),
    ]
    for args, words in refused:
        target = "v" if args[0] == "video" else "o"
        extra = ["--out", str(tmp_path / (target + (".png" if args[0] == "shot" else "")))]
        if args[0] == "bench":
            extra = []
        assert main(args + extra) == 2, args
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and words in err, (args, err)
    assert not any(p.name in ("o.png", "o", "v") for p in tmp_path.iterdir())


def test_a_closed_stdout_ends_quietly(tmp_path):
    # `hmblur graph | head`: the reader gone, no message and no traceback, the status a
    # SIGPIPE's (141), whichever command was writing; outputs to files are still whole.
    for args in (["graph", "hybrid"], ["params"], ["scene", str(ROOT / "scenes" / "assets" /
                                                             "rover.glb")],
                 ["shot", BASIC, "--size", "16x9", "--mode", "off", "--out",
                  str(tmp_path / "p.png")]):
        r, w = os.pipe()
        os.close(r)
        try:
            p = subprocess.run([sys.executable, "-m", "viewer", *args], cwd=ROOT, stdout=w,
                               stderr=subprocess.PIPE, text=True, timeout=240)
        finally:
            os.close(w)
        assert (p.returncode, p.stderr) == (141, ""), (args, p.stderr)
    assert (tmp_path / "p.png").is_file() and (tmp_path / "p.json").is_file()


def test_params_lists_every_parameter_from_the_dataclasses(capsys):
    from viewer.render.graph.params import GROUPS
    from viewer.render.modes import MODE_GROUPS
    assert main(["params"]) == 0
    text = capsys.readouterr().out
    for name, cls in GROUPS.items():
        for f in __import__("dataclasses").fields(cls):
            line = next(x for x in text.splitlines() if x.strip().startswith(f"{name}.{f.name} = "))
            assert repr(f.default) in line, line
            if f.metadata.get("unit"):
                assert f"[{f.metadata['unit']}]" in line
    assert "blur.max_radius = 0.08  (float: 0.002 .. 0.25)  [fraction of the image width]" in text
    assert main(["params", "ue4"]) == 0
    import re
    listed = set(re.findall(r"^  (\w+)\.\w+ = ", capsys.readouterr().out, re.M))
    assert listed == set(MODE_GROUPS["ue4"])
    assert main(["params", "off"]) == 0 and "no parameters" in capsys.readouterr().out


def test_shot_makes_missing_folders_and_png_sidecars_never_collide(tmp_path):
    out = tmp_path / "new" / "deeper" / "e.png"
    assert main(["shot", BASIC, "--size", "32x18", "--out", str(out)]) == 0
    assert out.is_file() and (out.parent / "e.json").is_file()
    # compare agrees: a folder under missing folders is made
    assert main(["compare", BASIC, "--size", "16x10", "--samples", "2", "--modes", "off",
                 "--out", str(tmp_path / "x" / "y")]) == 0
    assert (tmp_path / "x" / "y" / "strip.png").is_file()
    # Only .png is written, so e.png -> e.json is the one image that sidecar can belong to.
    for bad in ("e.jpg", "e.PNG", "e", "e.png.json"):
        assert main(["shot", BASIC, "--out", str(tmp_path / bad)]) == 2
    assert sorted(f.name for f in tmp_path.iterdir() if f.is_file()) == []


def test_sidecar_brings_the_scene_back_from_another_folder(tmp_path, monkeypatch, capsys):
    """The sidecar stores the scene's absolute path (and a built-in's name); --params
    without SCENE renders the same image from any folder."""
    scene = tmp_path / "scenes" / "mine.toml"
    scene.parent.mkdir()
    scene.write_text((CONFORMANCE / "basic.toml").read_text().replace(
        'path = "', f'path = "{CONFORMANCE}/'))
    here = tmp_path / "work"
    here.mkdir()
    monkeypatch.chdir(tmp_path / "scenes")
    assert main(["shot", "mine.toml", "--mode", "mcguire", "--size", "40x24",
                 "--out", str(here / "a.png")]) == 0
    side = json.loads((here / "a.json").read_text())
    assert side["scene"] == str(scene) and "scene_builtin" not in side
    assert side["timing"]["first_frame"] is True and "first frame" in side["timing"]["note"]
    monkeypatch.chdir(here)
    assert main(["shot", "--params", "a.json", "--out", "b.png"]) == 0
    assert (here / "b.png").read_bytes() == (here / "a.png").read_bytes()
    assert "first frame" in capsys.readouterr().out
    assert main(["shot", "spinner", "--size", "16x10", "--out", "c.png"]) == 0
    c = json.loads((here / "c.json").read_text())
    assert c["scene_builtin"] == "spinner" and c["scene"] == str(ROOT / "scenes" / "spinner.toml")
    assert main(["shot", "--params", "c.json", "--out", "d.png"]) == 0
    assert (here / "d.png").read_bytes() == (here / "c.png").read_bytes()


def test_first_scene_example_renders(tmp_path):
    assert main(["shot", str(ROOT / "scenes" / "examples" / "first_scene.toml"), "--mode",
                 "hybrid", "--size", "64x36", "--out", str(tmp_path / "f.png")]) == 0
    side = json.loads((tmp_path / "f.json").read_text())
    assert side["scene_name"] == "first_scene" and side["stats"]["masked_pixels"] > 0


def test_buffers_readme_describes_every_file(tmp_path):
    from viewer.io.buffer_docs import describe
    d = tmp_path / "bufs"
    for mode in ("mcguire", "ue4", "hybrid", "reference"):
        samples = ["--samples", "2"] if mode == "reference" else []
        assert main(["shot", BASIC, "--mode", mode, "--size", "32x18", *samples, "--out",
                     str(tmp_path / f"{mode}.png"), "--buffers", str(d / mode)]) == 0
        readme = (d / mode / "README.txt").read_text()
        for npy in sorted((d / mode).glob("*.npy")):
            a = np.load(npy)
            assert describe(npy.stem), f"{npy.stem} is not in viewer.io.buffer_docs.BUFFERS"
            entry = readme.split(f"\n{npy.name}  ", 1)[1].split("\n", 3)
            assert entry[0] == f"{a.dtype}  {'x'.join(map(str, a.shape))}"
            assert entry[1].strip() == describe(npy.stem)
    ray = np.load(d / "hybrid" / "ray_mask.npy")
    assert "ray_mask.npy  uint32" in (d / "hybrid" / "README.txt").read_text()
    assert f"values here: {ray.min()}..{ray.max()}" in (d / "hybrid" / "README.txt").read_text()


def test_compare_writes_keyed_regions_flip_maps_and_region_definitions(tmp_path):
    from viewer.eval.metrics import flip_map, to_srgb
    from viewer.eval.strip import REGION_COLOURS, heat
    out = tmp_path / "c"
    assert main(["compare", BASIC, "--size", "64x40", "--samples", "4", "--modes",
                 "off,hybrid", "--out", str(out)]) == 0
    md = (out / "metrics.md").read_text()
    assert "static: the same object is seen for the whole exposure" in md
    assert "surface of a spinning object is static" in md
    m = json.loads((out / "metrics.json").read_text())
    assert set(m["region_definitions"]) == {"static", "inner", "outer"}
    pic = np.asarray(Image.open(out / "regions.png"))
    assert pic.shape[0] > 40 and pic.shape[1] == 64                 # the key below the map
    key = pic[40:]
    for colour in REGION_COLOURS.values():                          # a swatch of each
        assert (key == colour).all(-1).sum() >= 25
    assert ((key == 0).all(-1)).sum() > 20                          # and text
    # flip.png: each mode's FLIP map as heat colours, somewhere in its column (but for
    # the outline of the strip's inset, which it also has, zoomed, below)
    flip = np.asarray(Image.open(out / "flip.png"))
    ref = np.asarray(Image.open(out / "reference.png"))
    hyb = heat(flip_map(to_srgb(ref), to_srgb(np.asarray(Image.open(out / "hybrid.png")))))
    col = flip[:, 64 + 4:64 + 4 + 64]
    rows = [y for y in range(col.shape[0] - 39) if (col[y:y + 40] == hyb).all(-1).mean() > 0.9]
    assert len(rows) == 1
    x0, y0, x1, y1 = m["inset"]
    zoom = 64 // (x1 - x0)
    crop = np.repeat(np.repeat(hyb[y0:y1, x0:x1], zoom, 0), zoom, 1)
    ih, iw = crop.shape[:2]
    zx = (64 - iw) // 2                                   # centred in the column
    assert any(np.array_equal(col[y:y + ih, zx:zx + iw], crop) for y in range(col.shape[0] - ih))
    bar = flip[-40:]
    assert tuple(heat(np.array([[0.0]]))[0, 0]) in {tuple(c) for c in bar.reshape(-1, 3)}


def test_bench_header_says_animated_and_explains_the_medians():
    from viewer.commands.bench import format_report
    rv = {"masked_pixels": 10, "rays": 12, "reveal_ms": 2.0, "rays_per_s": 6e3,
          "fraction_of_embree": 0.5, "trace_ms": 1.0, "trace_rays_per_s": 1.2e4,
          "trace_fraction_of_embree": 1.0, "embree_rays_per_s": 1.2e4,
          "embree_front_rays_per_s": 2e4, "readback_ms": 0.5, "fraction_with_bare_tracing": 0.8}
    mode = {"frame_ms": 20.0, "frame": {"p10": 19.0, "p90": 21.0}, "passes": {"gbuffer": 21.0}}
    rep = {"scene": "s", "size": [8, 4], "device": "d", "pass_timing": "t", "frames": 3,
           "time": 0.5, "animate_fps": 30.0, "modes": {"off": mode}, "ratios": {}, "reveal": rv}
    text = format_report(rep)
    assert "animated at 30 fps" in text.splitlines()[1]
    assert "a pass's median can exceed its frame's median" in " ".join(text.split())
    reveal = text[text.index("reveal (hybrid"):].splitlines()
    assert len(reveal) == 6 and all(len(x) < 100 for x in reveal)
    rep["animate_fps"] = None
    assert "one frame time, t = 0.5 s" in format_report(rep).splitlines()[1]


def test_graph_prints_the_modes_passes_and_host_resources(capsys):
    from viewer.commands.main import main
    assert main(["graph", "hybrid"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("mode hybrid -> hybrid\n")
    assert "  reveal (cpu): ray_mask -> host:masked_pixels, host:reveal_hits, host:reveal_batch\n" in out
    assert "  masked_pixels (ndarray): reveal -> hybrid_composite\n" in out
    assert main(["graph", "fancy"]) == 2
    assert "graph fancy: expected one of" in capsys.readouterr().err
