import math

import numpy as np
import pytest

from conftest import srgb8_to_linear
from viewer.eval import strip as strip_module
from viewer.render.modes.regions import INNER, OUTER, STATIC
from viewer.eval.strip import BACKGROUND, BOX, GAP, HEAT_RGB, REGION_COLOURS, choose_inset, font_size, heat, make_strip, metrics_markdown, metrics_rows, region_picture

def line_height(image_height: int) -> int:
    """Height of one text row (label or metric line) beside panels `image_height` tall."""
    return strip_module._line_height(strip_module._font(image_height))


LH = line_height(20)     # label row height beside 20 px tall images


# --- choose_inset ------------------------------------------------------------------------

def test_inset_centres_a_small_blob():
    region = np.zeros((60, 80), np.uint8)
    region[20:25, 30:35] = INNER                      # 5x5 blob centred on (x=32, y=22)
    assert choose_inset(region, 15) == (25, 15, 40, 30)
    assert choose_inset(region, (21, 11)) == (22, 17, 43, 28)


def test_inset_prefers_the_densest_inner_blur():
    region = np.zeros((50, 100), np.uint8)
    region[5:10, 5:10] = INNER                        # 25 inner pixels
    region[30:40, 70:80] = INNER                      # 100 inner pixels: wins
    region[0:50, 40:60] = OUTER                       # lots of outer blur: ignored
    x0, y0, x1, y1 = choose_inset(region, 10)
    assert (x0, y0, x1, y1) == (70, 30, 80, 40)


def test_inset_matches_brute_force_count():
    rng = np.random.default_rng(0)
    region = rng.choice([STATIC, INNER, OUTER], (23, 31), p=[0.6, 0.2, 0.2]).astype(np.uint8)
    x0, y0, x1, y1 = choose_inset(region, (6, 4))
    assert (x1 - x0, y1 - y0) == (6, 4)
    best = max((region[y:y + 4, x:x + 6] == INNER).sum()
               for y in range(23 - 3) for x in range(31 - 5))
    assert (region[y0:y1, x0:x1] == INNER).sum() == best


def test_inset_fallbacks():
    region = np.zeros((40, 60), np.uint8)
    assert choose_inset(region, 10) == (25, 15, 35, 25)       # nothing blurred: centre
    region[0:4, 0:4] = OUTER                                  # no inner: any blur
    assert choose_inset(region, 4) == (0, 0, 4, 4)
    assert choose_inset(region, (100, 100)) == (0, 0, 60, 40)  # clamped to the image
    with pytest.raises(ValueError):
        choose_inset(region, 0)


# --- make_strip --------------------------------------------------------------------------

def _images():
    rng = np.random.default_rng(1)
    a = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    b = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    return a, b


def test_strip_layout_and_pixels():
    a, b = _images()
    box = (10, 5, 20, 10)                     # 10x5 box -> zoom 30 // 10 = 3 -> 30x15 inset
    strip = make_strip([("reference", srgb8_to_linear(a)), ("hybrid", b)], inset_box=box,
                       metrics=[["PSNR inf"], ["PSNR 31.2", "FLIP 0.05"]])
    assert strip.dtype == np.uint8
    assert strip.shape == (LH + 20 + GAP + 15 + GAP + 2 * LH, 2 * 30 + GAP, 3)

    outline = np.zeros((20, 30), bool)
    outline[4, 9:21] = outline[10, 9:21] = True        # rows just above and below the box
    outline[4:11, 9] = outline[4:11, 20] = True        # columns just left and right of it
    for k, img in enumerate((a, b)):
        x = k * (30 + GAP)
        panel = strip[LH:LH + 20, x:x + 30]
        assert np.array_equal(panel[~outline], img[~outline])    # linear input re-encodes
        assert (panel[outline] == BOX).all()
        inset = strip[LH + 20 + GAP:LH + 20 + GAP + 15, x:x + 30]
        assert np.array_equal(inset, np.kron(img[5:10, 10:20], np.ones((3, 3, 1), np.uint8)))
        assert np.array_equal(inset[::3, ::3], img[5:10, 10:20])
    gap = strip[:, 30:30 + GAP]
    assert (gap == BACKGROUND).all()


def test_strip_text_is_drawn_and_deterministic():
    a, b = _images()
    args = ([("off", a), ("mcguire", b)],)
    kw = dict(inset_box=(0, 0, 30, 20), metrics=[["x"], ["PSNR 20.00 dB"]])
    s1, s2 = make_strip(*args, **kw), make_strip(*args, **kw)
    assert np.array_equal(s1, s2)
    labels = s1[:LH]
    assert (labels != BACKGROUND).any(axis=2).sum() > 20       # ink in the label row
    left, right = labels[:, :30], labels[:, 34:]
    assert not np.array_equal(left, right)                      # different labels
    other = make_strip([("OFF", a), ("mcguire", b)], **kw)
    assert not np.array_equal(other[:LH, :30], left) and np.array_equal(other[LH:], s1[LH:])


def test_strip_text_is_binary_black_on_white():
    a, _ = _images()
    s = make_strip([("label text", a)], metrics=[["line one"]])
    text = np.concatenate([s[:LH].reshape(-1, 3), s[LH + 20:].reshape(-1, 3)])
    colours = {tuple(c) for c in np.unique(text, axis=0)}
    assert colours == {(0, 0, 0), (255, 255, 255)}


def test_strip_without_inset_or_metrics():
    a, b = _images()
    s = make_strip([("a", a), ("b", b), ("c", a)])
    assert s.shape == (LH + 20, 3 * 30 + 2 * GAP, 3)
    assert np.array_equal(s[LH:, 68:98], a)


def test_strip_explicit_zoom_widens_columns():
    a, _ = _images()
    s = make_strip([("a", a)], inset_box=(0, 0, 10, 4), zoom=5)     # 50 px inset > 30 px
    assert s.shape == (LH + 20 + GAP + 20, 50, 3)
    assert np.array_equal(s[LH:LH + 20, 10:40][5:, 11:], a[5:, 11:])  # image centred


def test_strip_input_errors():
    a, _ = _images()
    with pytest.raises(ValueError):
        make_strip([])
    with pytest.raises(ValueError):
        make_strip([("a", a), ("b", a[:10])])
    with pytest.raises(ValueError):
        make_strip([("a", a)], inset_box=(5, 5, 5, 9))
    with pytest.raises(ValueError):
        make_strip([("a", a)], inset_box=(0, 0, 31, 5))
    with pytest.raises(ValueError):
        make_strip([("a", a)], metrics=[["x"], ["y"]])


# --- tables ------------------------------------------------------------------------------

def _entry(pixels, psnr, ssim, flip):
    return {"pixels": pixels, "psnr": psnr, "ssim": ssim, "flip": flip}


TABLE = {
    "off": {"all": _entry(100, 25.123, 0.91234, 0.1), "static": _entry(90, math.inf, 1.0, 0.0),
            "inner": _entry(10, 12.5, 0.5, 0.4), "outer": _entry(0, None, None, None)},
    "hybrid": {"all": _entry(100, 30.0, 0.95, 0.05)},
}


def test_markdown_rows():
    md = metrics_markdown(TABLE)
    lines = md.strip().split("\n")
    assert lines[0] == "| mode | region | pixels | PSNR (dB) | SSIM | FLIP |"
    assert lines[2:] == [
        "| off | all | 100 | 25.12 | 0.9123 | 0.1000 |",
        "| off | static | 90 | inf | 1.0000 | 0.0000 |",
        "| off | inner | 10 | 12.50 | 0.5000 | 0.4000 |",
        "| off | outer | 0 | - | - | - |",
        "| hybrid | all | 100 | 30.00 | 0.9500 | 0.0500 |",
    ]


def test_rows():
    rows = metrics_rows(TABLE)
    assert len(rows) == 5
    assert rows[1] == {"mode": "off", "region": "static", "pixels": 90, "psnr": math.inf,
                       "ssim": 1.0, "flip": 0.0}
    assert rows[3]["psnr"] is None
    assert [(r["mode"], r["region"]) for r in rows][-1] == ("hybrid", "all")


def test_table_from_image_metrics():
    from viewer.eval.metrics import image_metrics
    rng = np.random.default_rng(2)
    ref = rng.random((12, 12, 3))
    region = np.zeros((12, 12), np.uint8)
    region[4:8, 4:8] = INNER
    table = {m: image_metrics(np.clip(ref + s, 0, 1), ref, region)
             for m, s in (("off", 0.1), ("hybrid", 0.0))}
    md = metrics_markdown(table)
    assert md.count("\n") == 2 + 2 * 4
    assert "| hybrid | all | 144 | inf | 1.0000 | 0.0000 |" in md
    assert "| off | outer | 0 | - | - | - |" in md


# --- text size, region key, heat map -------------------------------------------------------

def _ink_rows(block) -> int:
    ink = (block != BACKGROUND).any(axis=2).any(axis=1)
    ys = np.nonzero(ink)[0]
    return int(ys[-1] - ys[0] + 1) if len(ys) else 0


def test_text_grows_with_the_image_so_a_scaled_down_strip_stays_readable():
    assert font_size(20) == font_size(180) == 11 and font_size(360) >= 22
    assert font_size(720) >= 2 * font_size(360) - 1
    for h in (180, 360, 720):
        img = np.full((h, 2 * h, 3), 128, np.uint8)
        s = make_strip([("hybrid", img)])
        lh = line_height(h)
        assert s.shape[0] == lh + h
        # the glyphs of "hybrid" (ascender to descender) span most of the font size
        assert _ink_rows(s[:lh]) >= 0.8 * font_size(h)


def test_region_picture_has_the_map_then_a_key():
    region = np.array([[STATIC, INNER], [OUTER, INNER]], np.uint8).repeat(20, 0).repeat(40, 1)
    pic = region_picture(region)
    h, w = region.shape
    assert pic.shape[1] == w and pic.shape[0] == h + GAP + 3 * line_height(h)
    for code, colour in REGION_COLOURS.items():
        assert (pic[:h][region == code] == colour).all()
    key = pic[h + GAP:]
    for row, code in enumerate((INNER, OUTER, STATIC)):       # one row each: swatch, text
        band = key[row * line_height(h):(row + 1) * line_height(h)]
        assert (band == REGION_COLOURS[code]).all(-1).sum() >= 50
        assert (band == 0).all(-1).sum() > 20


def test_heat_colours_follow_the_ramp():
    e = np.array([[0.0, 0.25, 0.5, 1.0, 2.0, -1.0, np.nan]])
    got = heat(e)
    assert np.array_equal(got[0, :4], HEAT_RGB[[0, 1, 2, 4]].astype(np.uint8))
    assert np.array_equal(got[0, 4], HEAT_RGB[4]) and np.array_equal(got[0, 5], HEAT_RGB[0])
    assert np.array_equal(got[0, 6], HEAT_RGB[0])
    mid = heat(np.array([[0.125]]))[0, 0]
    assert np.array_equal(mid, np.floor((HEAT_RGB[0] + HEAT_RGB[1]) / 2 + 0.5))
