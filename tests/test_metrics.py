import json
import math

import flip_evaluator
import numpy as np
import pytest
from skimage.metrics import structural_similarity

from conftest import srgb8_to_linear
from viewer.io.imageio import linear_to_srgb8, write_json_atomic
from viewer.eval.metrics import flip_map, image_metrics, metric_maps, to_srgb
from viewer.render.modes.regions import INNER, OUTER, STATIC


def _rand8(shape=(16, 20, 3), seed=0):
    return np.random.default_rng(seed).integers(0, 256, shape, dtype=np.uint8)


# --- PSNR ------------------------------------------------------------------------------

def test_psnr_one_channel_full_scale_error():
    ref = np.zeros((8, 8, 3), np.uint8)
    test = ref.copy()
    test[2, 3, 1] = 255                   # MSE = 1 / (8*8*3)
    m = image_metrics(test, ref)["all"]
    assert m["pixels"] == 64
    assert m["psnr"] == pytest.approx(10 * math.log10(192), abs=1e-9)   # 22.833 dB


def test_psnr_one_code_everywhere_is_peak_limited():
    ref = np.full((9, 9, 3), 100, np.uint8)
    m = image_metrics(ref + 1, ref)["all"]
    assert m["psnr"] == pytest.approx(20 * math.log10(255), abs=1e-9)   # 48.13 dB


def test_identical_images_give_inf_and_json_string(tmp_path):
    img = _rand8()
    m = image_metrics(img, img, region=np.zeros(img.shape[:2], np.uint8))
    assert m["all"]["psnr"] == math.inf and m["static"]["psnr"] == math.inf
    assert m["all"]["ssim"] == pytest.approx(1.0) and m["all"]["flip"] == 0.0
    p = write_json_atomic(tmp_path / "m.json", m)
    assert json.loads(p.read_text())["all"]["psnr"] == "inf"


def test_linear_inputs_are_measured_as_8bit_codes_by_default():
    lin = srgb8_to_linear(_rand8(seed=3)).astype(np.float64)
    nudged = lin + 1e-7                    # below half a code step almost everywhere
    assert np.array_equal(linear_to_srgb8(nudged), linear_to_srgb8(lin))
    assert image_metrics(nudged, lin)["all"]["psnr"] == math.inf
    unq = image_metrics(nudged, lin, quantize=False)["all"]["psnr"]
    assert math.isfinite(unq) and unq > 80


def test_to_srgb_conventions():
    assert to_srgb(np.full((1, 1, 3), 255, np.uint8)).tolist() == [[[1.0, 1.0, 1.0]]]
    half = np.full((1, 1, 3), 0.5)
    assert to_srgb(half)[0, 0, 0] == 188 / 255
    assert to_srgb(half, quantize=False)[0, 0, 0] == pytest.approx(0.735357, abs=1e-6)
    with pytest.raises(ValueError):
        to_srgb(np.zeros((4, 4)))


# --- SSIM ------------------------------------------------------------------------------

def test_ssim_all_equals_skimage_scalar():
    ref, test = _rand8(seed=1), _rand8(seed=2)
    expect = structural_similarity(ref / 255.0, test / 255.0, channel_axis=2, data_range=1.0)
    assert image_metrics(test, ref)["all"]["ssim"] == pytest.approx(expect, abs=1e-12)
    # and differs from the plain map mean, which includes the border skimage drops
    assert metric_maps(test, ref)["ssim"].mean() != pytest.approx(expect, abs=1e-6)


# --- FLIP ------------------------------------------------------------------------------

def test_flip_evaluator_call_contract():
    # pins the library's interface that flip_map relies on
    rng = np.random.default_rng(4)
    a = rng.random((10, 12, 3)).astype(np.float32)
    b = np.clip(a + 0.1, 0, 1).astype(np.float32)
    out = flip_evaluator.evaluate(a, b, "LDR", applyMagma=False)
    assert isinstance(out, tuple) and len(out) == 3
    err, mean, params = out
    assert err.shape == (10, 12, 1) and err.dtype == np.float32
    assert mean == pytest.approx(float(err.mean()), rel=1e-5)
    assert isinstance(params, dict) and params["ppd"] == pytest.approx(67.0206, abs=1e-3)
    magma, _, _ = flip_evaluator.evaluate(a, b, "LDR")      # default: a colour picture
    assert magma.shape == (10, 12, 3)
    np.testing.assert_array_equal(flip_map(a, b), err[..., 0].astype(np.float64))


def test_flip_grows_with_error():
    rng = np.random.default_rng(5)
    ref = rng.random((24, 24, 3))
    noise = rng.standard_normal(ref.shape)
    means = [image_metrics(np.clip(ref + s * noise, 0, 1), ref, quantize=False)["all"]["flip"]
             for s in (0.0, 0.01, 0.05, 0.2)]
    assert means[0] == 0.0
    assert means[0] < means[1] < means[2] < means[3] < 1.0


# --- regions ---------------------------------------------------------------------------

def test_region_means_on_synthetic_map():
    h, w = 16, 24
    ref = _rand8((h, w, 3), seed=6)
    test = ref.copy()
    test[:, 12:] = 255 - ref[:, 12:]          # error only in the right half
    region = np.full((h, w), STATIC, np.uint8)
    region[:, 12:] = INNER                   # no OUTER pixels at all
    m = image_metrics(test, ref, region)
    assert list(m) == ["all", "static", "inner", "outer"]
    assert [m[k]["pixels"] for k in ("all", "static", "inner", "outer")] == [384, 192, 192, 0]
    assert m["outer"] == {"pixels": 0, "psnr": None, "ssim": None, "flip": None}
    assert m["static"]["psnr"] == math.inf
    d = (test[:, 12:].astype(np.float64) - ref[:, 12:]) / 255.0
    assert m["inner"]["psnr"] == pytest.approx(-10 * math.log10(np.mean(d * d)), abs=1e-9)
    # the "all" MSE is the pixel-weighted mean of the region MSEs
    assert m["all"]["psnr"] == pytest.approx(-10 * math.log10(np.mean(d * d) / 2), abs=1e-9)

    maps = metric_maps(test, ref)
    fm = maps["flip"]
    assert m["inner"]["flip"] == pytest.approx(fm[:, 12:].mean(), abs=1e-12)
    assert m["static"]["flip"] == pytest.approx(fm[:, :12].mean(), abs=1e-12)
    assert m["inner"]["flip"] > 4 * m["static"]["flip"] > 0   # FLIP's filters bleed across
    _, smap = structural_similarity(ref / 255.0, test / 255.0, channel_axis=2,
                                    data_range=1.0, full=True)
    smap = smap.mean(axis=2)[3:-3, 3:-3]                    # skimage's border crop
    assert m["inner"]["ssim"] == pytest.approx(smap[:, 9:].mean(), abs=1e-12)
    assert m["static"]["ssim"] == pytest.approx(smap[:, :9].mean(), abs=1e-12)


def test_region_only_in_border_has_no_ssim():
    ref = _rand8((12, 12, 3), seed=8)
    region = np.full((12, 12), STATIC, np.uint8)
    region[0, 0] = OUTER
    m = image_metrics(ref, ref, region)["outer"]
    assert m["pixels"] == 1 and m["ssim"] is None and m["psnr"] == math.inf


def test_shape_mismatches_raise():
    a = _rand8((10, 10, 3))
    with pytest.raises(ValueError):
        image_metrics(a, _rand8((10, 11, 3)))
    with pytest.raises(ValueError):
        image_metrics(a, a, region=np.zeros((9, 10), np.uint8))
