import json
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from viewer.io import imageio
from conftest import srgb8_to_linear
from viewer.io.imageio import OutputSet, json_safe, linear_to_srgb8, srgb_float, write_json_atomic, write_png_atomic

CONF = Path(__file__).parent / "conformance"


# --- encoding --------------------------------------------------------------------------

@pytest.mark.parametrize("linear, code", [
    (0.0, 0),
    (1.0, 255),
    (0.001, 3),          # linear segment: 12.92 * 0.001 * 255 = 3.29
    (0.002, 7),          # 6.59 rounds up
    (0.0031308, 10),     # breakpoint: both branches give 0.04045 -> 10.31
    (0.18, 118),         # 1.055 * 0.18^(1/2.4) - 0.055 = 0.46137 -> 117.65
    (0.5, 188),          # 0.735357 * 255 = 187.52
    (1.5, 255), (1e30, 255),    # clamp above
    (-0.2, 0), (-1e30, 0),      # clamp below
])
def test_encoding_hand_values(linear, code):
    assert linear_to_srgb8(np.array([linear]))[0] == code


def test_non_finite_policy():
    out = linear_to_srgb8(np.array([np.nan, np.inf, -np.inf]))
    assert out.tolist() == [0, 255, 0]
    assert srgb_float(np.array([np.nan, np.inf])).tolist() == [0.0, 1.0]


def test_encoding_keeps_shape_and_dtype():
    x = np.full((2, 3, 3), 0.5, np.float32)
    out = linear_to_srgb8(x)
    assert out.dtype == np.uint8 and out.shape == (2, 3, 3) and (out == 188).all()


def test_srgb_float_is_unquantised_encoding():
    s = srgb_float(np.array([0.0, 0.0031308, 0.5, 1.0, 2.0]))
    assert s.dtype == np.float32
    np.testing.assert_allclose(s, [0.0, 0.04044994, 0.735357, 1.0, 1.0], atol=1e-6)
    # Both forms against the transfer function written here from the contract (sRGB of
    # the clamped linear value; 8 bits: floor(255 srgb + 0.5)).
    x = np.linspace(-0.1, 1.1, 5001)
    c = np.clip(x, 0.0, 1.0)
    want = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    np.testing.assert_allclose(srgb_float(x), want, rtol=0, atol=1e-6)
    assert np.array_equal(linear_to_srgb8(x), np.floor(255.0 * want + 0.5).astype(np.uint8))


def test_decode_round_trips_every_code():
    codes = np.arange(256, dtype=np.uint8)
    lin = srgb8_to_linear(codes)
    assert lin.dtype == np.float32
    assert lin[0] == 0.0 and lin[255] == 1.0
    assert np.all(np.diff(lin) > 0)
    np.testing.assert_allclose(lin[10], 10 / 255 / 12.92, rtol=1e-6)        # linear segment
    np.testing.assert_allclose(lin[128], ((128 / 255 + 0.055) / 1.055) ** 2.4, rtol=1e-6)
    assert np.array_equal(linear_to_srgb8(lin), codes)


@pytest.mark.parametrize("name", ["basic", "vase_pan"])
@pytest.mark.parametrize("key, suffix", [("sharp", "off"), ("linear", "reference")])
def test_encoding_matches_conformance_pngs(name, key, suffix):
    # The PNGs were written by an independent implementation: exact pixel equality pins
    # the clamp, the transfer function and the floor(255*s + 0.5) rounding.
    data = np.load(CONF / f"{name}.npz")
    png = np.asarray(Image.open(CONF / f"{name}_{suffix}.png").convert("RGB"))
    ours = linear_to_srgb8(data[key])
    assert ours.shape == png.shape
    assert np.array_equal(ours, png)


# --- atomic writers --------------------------------------------------------------------

def _leftovers(d: Path):
    return sorted(p.name for p in d.iterdir() if p.name.endswith(".tmp"))


def test_png_round_trip_rgb_and_grey(tmp_path):
    rgb = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3)
    grey = np.arange(20, dtype=np.uint8).reshape(4, 5) * 10
    write_png_atomic(tmp_path / "a.png", rgb)
    write_png_atomic(tmp_path / "g.png", grey)
    a, g = Image.open(tmp_path / "a.png"), Image.open(tmp_path / "g.png")
    assert a.mode == "RGB" and np.array_equal(np.asarray(a), rgb)
    assert g.mode == "L" and np.array_equal(np.asarray(g), grey)
    assert a.info == {}          # no metadata chunks
    assert _leftovers(tmp_path) == []


def test_png_bytes_are_deterministic(tmp_path):
    img = np.random.default_rng(1).integers(0, 256, (7, 9, 3), dtype=np.uint8)
    write_png_atomic(tmp_path / "x.png", img)
    first = (tmp_path / "x.png").read_bytes()
    write_png_atomic(tmp_path / "x.png", img)      # overwrite
    write_png_atomic(tmp_path / "y.png", img)
    assert (tmp_path / "x.png").read_bytes() == first == (tmp_path / "y.png").read_bytes()
    assert b"tIME" not in first and b"tEXt" not in first


@pytest.mark.parametrize("bad", [np.zeros((4, 4, 3), np.float32), np.zeros((4, 4, 4), np.uint8),
                                 np.zeros(5, np.uint8)])
def test_png_rejects_bad_input_without_writing(tmp_path, bad):
    with pytest.raises(ValueError):
        write_png_atomic(tmp_path / "bad.png", bad)
    assert list(tmp_path.iterdir()) == []


def test_failing_png_write_leaves_no_file(tmp_path, monkeypatch):
    def boom(self, fp, *a, **k):
        fp.write(b"\x89PNG half")              # partial output, then failure
        raise OSError("disk full")
    monkeypatch.setattr(Image.Image, "save", boom)
    with pytest.raises(OSError, match="disk full"):
        write_png_atomic(tmp_path / "out.png", np.zeros((2, 2, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_failing_overwrite_keeps_previous_file(tmp_path, monkeypatch):
    target = tmp_path / "out.npy"

    def write_npy(array):
        files = OutputSet()
        files.npy(target, array)
        files.commit()
    write_npy(np.arange(3))
    before = target.read_bytes()

    def boom(f, *a, **k):
        f.write(b"garbage")
        raise RuntimeError("interrupted")
    monkeypatch.setattr(imageio.np, "save", boom)
    with pytest.raises(RuntimeError):
        write_npy(np.arange(10))
    assert target.read_bytes() == before
    assert _leftovers(tmp_path) == []


def test_written_file_mode_follows_umask(tmp_path):
    old = os.umask(0o022)
    try:
        p = write_json_atomic(tmp_path / "m.json", {})
    finally:
        os.umask(old)
    assert (p.stat().st_mode & 0o777) == 0o644


def test_json_sorted_indented_and_non_finite(tmp_path):
    obj = {"b": 1, "a": {"psnr": float("inf"), "x": np.float32(0.5), "n": np.int64(3),
                         "arr": np.array([1, 2]), "t": (1.0, float("-inf"), float("nan"))}}
    p = write_json_atomic(tmp_path / "m.json", obj)
    text = p.read_text()
    assert text == (
        '{\n  "a": {\n    "arr": [\n      1,\n      2\n    ],\n    "n": 3,\n'
        '    "psnr": "inf",\n    "t": [\n      1.0,\n      "-inf",\n      "nan"\n    ],\n'
        '    "x": 0.5\n  },\n  "b": 1\n}\n')
    assert json.loads(text)["a"]["psnr"] == "inf"
    write_json_atomic(tmp_path / "m2.json", obj)
    assert (tmp_path / "m2.json").read_bytes() == p.read_bytes()


def test_json_unserialisable_leaves_nothing(tmp_path):
    with pytest.raises(TypeError):
        write_json_atomic(tmp_path / "bad.json", {"x": object()})
    assert list(tmp_path.iterdir()) == []


def test_json_safe_leaves_finite_values():
    assert json_safe({"a": [1, 2.5, "s", None, True]}) == {"a": [1, 2.5, "s", None, True]}


def test_npy_round_trip(tmp_path):
    a = np.arange(12, dtype=np.float32).reshape(3, 4)
    files = OutputSet()
    files.npy(tmp_path / "a.npy", a)
    files.commit()
    b = np.load(tmp_path / "a.npy", allow_pickle=False)
    assert b.dtype == a.dtype and np.array_equal(a, b)
    assert _leftovers(tmp_path) == []


def test_output_set_writes_all_or_nothing(tmp_path):
    files = OutputSet()
    files.png(tmp_path / "new" / "a.png", np.zeros((2, 3, 3), np.uint8))
    files.json(tmp_path / "new" / "a.json", {"x": 1})
    (tmp_path / "new").mkdir()
    (tmp_path / "new" / "a.json").mkdir()          # a folder where a file goes
    with pytest.raises(IsADirectoryError):
        files.commit()
    assert [p.name for p in (tmp_path / "new").iterdir()] == ["a.json"]
    (tmp_path / "new" / "a.json").rmdir()
    files.commit()                                  # the folder made if missing
    assert sorted(p.name for p in (tmp_path / "new").iterdir()) == ["a.json", "a.png"]

    def broken(f):
        raise RuntimeError("encoder failed")
    files = OutputSet()
    files.png(tmp_path / "b.png", np.zeros((2, 3, 3), np.uint8))
    files.add(tmp_path / "b.bin", broken)
    with pytest.raises(RuntimeError):
        files.commit()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new"]      # no temps either
