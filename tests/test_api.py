"""The Python API (hybrid_mblur, docs/api.md): arrays equal to the CLI's PNG bytes, a
renderer that owns its context and serves several scenes, scores and tables equal to
compare's metrics.json, the reference's region masks, and the notebook-style example."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import hybrid_mblur as hm
from viewer.commands.main import main
from viewer.eval.metrics import image_metrics
from viewer.io.imageio import png_bytes

from conftest import CONFORMANCE, ROOT

BASIC = str(CONFORMANCE / "basic.toml")
GLSL = str(ROOT / "docs/examples/naive_gather.frag")
NUMPY = str(ROOT / "docs/examples/numpy_gather.py")


@pytest.mark.parametrize("mode", ["mcguire", "hybrid"])
def test_the_api_arrays_are_the_shot_png(tmp_path, ctx, mode):
    out = tmp_path / "a.png"
    assert main(["shot", BASIC, "--size", "48x27", "--mode", mode, "--seed", "3",
                 "--set", "blur.max_radius=0.1", "--out", str(out)]) == 0
    with hm.Renderer(size=(48, 27), context=ctx) as r:
        res = r.render(hm.load_scene(BASIC), mode, params={"blur.max_radius": 0.1}, seed=3)
    assert res.image.dtype == np.float32 and res.image.shape == (27, 48, 3)
    assert np.array_equal(res.srgb, np.asarray(Image.open(out).convert("RGB")))
    assert png_bytes(res.srgb) == out.read_bytes()
    assert ctx.error == "GL_NO_ERROR"          # (the caller's context: used, not released)


def test_a_renderer_owns_its_context_and_serves_several_scenes():
    a, b = hm.load_scene(BASIC), hm.load_scene("living_room")
    with hm.Renderer(size=(40, 24)) as r:
        assert r.context is not None and "off" in r.modes
        first = r.render(a, "mcguire", buffers=True)
        other = r.render(b, "mcguire")
        again = r.render(a, "mcguire")
        off = r.render(a, "off", buffers=True)
        resized = r.render(a, "off", size=(20, 12))
        kept = r.core(BASIC)                    # a scene named by its file: loaded once
        assert r.core(BASIC) is kept and r.core(a) is not kept
    assert r.context is None                    # released with the `with`
    assert np.array_equal(first.image, again.image)
    assert not np.array_equal(first.image, other.image)
    # `buffers`: the textures the frame made; off's output is its G-buffer colour.
    assert {"color", "depth", "velocity", "mcguire_neighbormax"} <= set(first.buffers)
    assert np.array_equal(off.image, off.buffers["color"][..., :3])
    assert first.buffers["velocity"].shape == (24, 40, 2)
    assert resized.image.shape == (12, 20, 3)


def test_reference_masks_partition_the_image_and_scores_are_compares(ctx):
    scene = hm.load_scene(BASIC)
    with hm.Renderer(size=(48, 27), context=ctx) as r:
        ref = r.reference(scene, samples=4)
        img = r.render(scene, "mcguire")
    m = ref.masks()
    assert m["all"].all()
    parts = m["static"].astype(int) + m["inner"] + m["outer"]
    assert (parts == 1).all() and m["inner"].any() and m["outer"].any()
    table = hm.scores(img, ref)
    want = image_metrics(img.image, ref.image, ref.regions)
    assert list(table.index) == ["all", "static", "inner", "outer"]
    for region, row in table.iterrows():
        assert row["pixels"] == want[region]["pixels"] == m[region].sum()
        for c in ("psnr", "ssim", "flip"):
            assert row[c] == pytest.approx(want[region][c], rel=0, abs=0)
    # uint8 sRGB codes are taken as they are: the PNG's numbers are the same.
    assert hm.scores(img.srgb, ref).equals(table)


def test_compare_dataframe_equals_compare_metrics_json(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", BASIC, "--size", "48x27", "--samples", "4", "--modes", "mcguire",
                 "--variant", f"mine=glsl:{GLSL}", "--out", str(out)]) == 0
    doc = json.loads((out / "metrics.json").read_text())
    df = hm.compare(hm.load_scene(BASIC), ["mcguire", ("mine", f"glsl:{GLSL}")],
                    size=(48, 27), params={"reference.samples": 4})
    assert list(df.columns) == ["variant", "mode", "region", "pixels", "flip", "psnr", "ssim"]
    assert list(df["variant"].unique()) == ["mcguire", "mine"]
    assert list(df[df.variant == "mine"]["mode"].unique()) == ["glsl"]
    assert len(df) == 8
    for _, row in df.iterrows():
        want = doc["metrics"][row["variant"]][row["region"]]
        assert row["pixels"] == want["pixels"]
        for c in ("flip", "psnr", "ssim"):
            w = want[c]
            w = float(w) if isinstance(w, str) else w     # ("inf" in JSON)
            assert (math.isnan(row[c]) and w is None) or row[c] == w, (row["variant"], c)
    method = doc["variants"]["mine"]["method"]
    assert method["path"] == GLSL and method["sha256"] == hm.glsl_pass(GLSL).digest
    assert "- mine: glsl:" in (out / "metrics.md").read_text()


def test_the_notebook_example_renders_three_modes_and_a_user_pass():
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.run([sys.executable, str(ROOT / "docs/examples/compare_methods.py"),
                        "living_room", "64x36"], capture_output=True, text=True, env=env,
                       timeout=600)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert lines[0].startswith("living_room 64x36, reference of 16 sub-frames")
    assert lines[1].split() == ["method", "region", "pixels", "psnr", "ssim", "flip"]
    rows = [line.split() for line in lines[2:]]
    assert [(r[0], r[1]) for r in rows] == [(m, g) for m in ("mcguire", "ue4", "hybrid",
                                                             "naive_numpy")
                                            for g in ("all", "static", "inner", "outer")]
    assert all(int(r[2]) > 0 for r in rows) and {r[2] for r in rows if r[1] == "all"} == {"2304"}
    flip = {r[0]: float(r[5]) for r in rows if r[1] == "inner"}
    assert flip["hybrid"] < flip["mcguire"]     # the reveal's inner blur, as in the README


def test_api_mistakes_are_user_errors(ctx):
    with hm.Renderer(size=(16, 9), context=ctx) as r:
        with pytest.raises(hm.UserError, match="no_such_mode"):
            r.render(hm.load_scene(BASIC), "no_such_mode")
        with pytest.raises(hm.UserError, match="built-in mode"):
            r.register("mcguire", hm.glsl_pass(GLSL))
        with pytest.raises(hm.UserError, match="params: blur.max_radius: expected float"):
            r.render(hm.load_scene(BASIC), "off", params={"blur.max_radius": "wide"})
    with pytest.raises(hm.UserError, match="no_scene_here"):
        hm.load_scene("no_scene_here")
