"""Comparison figures and tables: a labelled side-by-side strip with zoomed insets (in the
spirit of Figure 1 of Tan et al., Hybrid MBlur) and the metrics table as Markdown.

Strip layout, one column per image, on a white background:

    label            (text scaled with the image height: font_size)
    image            (sRGB; the inset box outlined just outside its pixels)
    inset            (the box, nearest-neighbour zoom by an integer factor)
    metric lines     (optional, one text line each)

Boxes are half-open pixel rectangles (x0, y0, x1, y1): columns x0..x1-1, rows y0..y1-1.
"""
from __future__ import annotations

import math

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from viewer.io.imageio import linear_to_srgb8
from viewer.render.modes.regions import INNER, NAMES, OUTER, STATIC

GAP = 4                    # pixels between columns and between stacked parts
PAD = 2                    # around text
BACKGROUND = (255, 255, 255)
TEXT = (0, 0, 0)
BOX = (255, 40, 0)
REGION_ORDER = ("all",) + tuple(NAMES[c] for c in sorted(NAMES))


MIN_FONT = 11              # px: the smallest text, for tiny images
FONT_FRACTION = 1 / 16     # of the image height: labels stay readable on a scaled-down strip


def font_size(image_height: int) -> int:
    """Text height in pixels for panels `image_height` tall."""
    return max(MIN_FONT, round(image_height * FONT_FRACTION))


def _font(image_height: int):
    # Pillow's own FreeType font (Aileron, shipped with Pillow >= 10.1) at a size that
    # follows the image, drawn without anti-aliasing (fontmode "1"): the same pixels for
    # the same Pillow and FreeType. Without FreeType, the fixed 11 px bitmap font.
    try:
        return ImageFont.load_default(size=font_size(image_height))
    except (TypeError, ImportError, OSError):
        if hasattr(ImageFont, "load_default_imagefont"):
            return ImageFont.load_default_imagefont()
        return ImageFont.load_default()


def _line_height(font) -> int:
    return font.getbbox("Ag")[3] + 2 * PAD


def _as_srgb8(image) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"expected an (H,W,3) image, got shape {a.shape}")
    return a if a.dtype == np.uint8 else linear_to_srgb8(a)


def _check_box(box, w: int, h: int) -> tuple[int, int, int, int]:
    x0, y0, x1, y1 = (int(v) for v in box)
    if not (0 <= x0 < x1 <= w and 0 <= y0 < y1 <= h):
        raise ValueError(f"inset box {box} is empty or outside the {w}x{h} image")
    return x0, y0, x1, y1


def _text(lines, width: int, font) -> np.ndarray:
    """Lines of text on a (len*line height, width) block: text is clipped to its own
    column instead of running into the next panel."""
    lh = _line_height(font)
    block = Image.new("RGB", (width, max(1, len(lines)) * lh), BACKGROUND)
    draw = ImageDraw.Draw(block)
    draw.fontmode = "1"     # no anti-aliasing, should a FreeType font ever be used
    for i, line in enumerate(lines):
        draw.text((PAD, i * lh + PAD), str(line), font=font, fill=TEXT)
    return np.asarray(block)[:len(lines) * lh]


def _outline(panel: np.ndarray, box) -> None:
    """1-px rectangle just outside the box, so the box's own pixels stay intact; the
    sides that would fall off the image are left out."""
    h, w = panel.shape[:2]
    x0, y0, x1, y1 = box
    xa, xb, ya, yb = max(x0 - 1, 0), min(x1, w - 1), max(y0 - 1, 0), min(y1, h - 1)
    if y0 > 0:
        panel[y0 - 1, xa:xb + 1] = BOX
    if y1 < h:
        panel[y1, xa:xb + 1] = BOX
    if x0 > 0:
        panel[ya:yb + 1, x0 - 1] = BOX
    if x1 < w:
        panel[ya:yb + 1, x1] = BOX


def make_strip(images, inset_box=None, metrics=None, zoom: int | None = None) -> np.ndarray:
    """[(label, image)] -> uint8 (H,W,3) strip. Images: float = linear colour, uint8 = sRGB;
    all the same size. `metrics`: per image, a list of text lines (or None). `zoom`:
    inset magnification, by default the largest integer that fits the image width."""
    if not images:
        raise ValueError("make_strip needs at least one image")
    panels = [(str(label), _as_srgb8(img)) for label, img in images]
    h, w = panels[0][1].shape[:2]
    if any(p.shape[:2] != (h, w) for _, p in panels):
        raise ValueError("make_strip: all images must have the same size")
    lines = [list(m or []) for m in (metrics or [[]] * len(panels))]
    if len(lines) != len(panels):
        raise ValueError("make_strip: one metrics entry per image")

    font = _font(h)
    lh = _line_height(font)
    box = None if inset_box is None else _check_box(inset_box, w, h)
    iw = ih = 0
    if box is not None:
        bw, bh = box[2] - box[0], box[3] - box[1]
        zoom = max(1, w // bw) if zoom is None else int(zoom)
        iw, ih = bw * zoom, bh * zoom
    col = max(w, iw)
    n_text = max(len(m) for m in lines)
    inset_y = lh + h + GAP
    text_y = lh + h + (GAP + ih if box else 0) + GAP
    height = text_y + n_text * lh if n_text else text_y - GAP
    width = len(panels) * col + (len(panels) - 1) * GAP

    canvas = np.empty((height, width, 3), np.uint8)
    canvas[:] = BACKGROUND
    for k, (label, img) in enumerate(panels):
        x = k * (col + GAP)
        canvas[:lh, x:x + col] = _text([label], col, font)
        ix = x + (col - w) // 2
        panel = img.copy()
        if box is not None:
            crop = img[box[1]:box[3], box[0]:box[2]]
            zx = x + (col - iw) // 2
            canvas[inset_y:inset_y + ih, zx:zx + iw] = np.repeat(
                np.repeat(crop, zoom, axis=0), zoom, axis=1)
            _outline(panel, box)
        canvas[lh:lh + h, ix:ix + w] = panel
        if lines[k]:
            block = _text(lines[k], col, font)
            canvas[text_y:text_y + len(block), x:x + col] = block
    return canvas


def choose_inset(region, size) -> tuple[int, int, int, int]:
    """Box of `size` ((w, h) or a side) over the densest INNER blur: the window holding the
    most INNER pixels (integral image); among equal windows the one nearest their middle,
    so a blob smaller than the window ends up centred. Without INNER pixels it uses any
    blur, and without blur it centres the box."""
    r = np.asarray(region)
    h, w = r.shape
    bw, bh = (size, size) if np.isscalar(size) else size
    bw, bh = min(int(bw), w), min(int(bh), h)
    if bw < 1 or bh < 1:
        raise ValueError(f"inset size {size} must be positive")
    mask = r == INNER
    if not mask.any():
        mask = r != STATIC
    sat = np.zeros((h + 1, w + 1), np.int64)
    sat[1:, 1:] = mask.cumsum(0).cumsum(1)
    # counts[y, x] = pixels in rows y..y+bh-1, columns x..x+bw-1
    counts = sat[bh:, bw:] - sat[:-bh, bw:] - sat[bh:, :-bw] + sat[:-bh, :-bw]
    ys, xs = np.nonzero(counts == counts.max())
    k = np.argmin((ys - ys.mean()) ** 2 + (xs - xs.mean()) ** 2)
    x0, y0 = int(xs[k]), int(ys[k])
    return x0, y0, x0 + bw, y0 + bh


# --- region map and error maps ----------------------------------------------------------

REGION_COLOURS = {INNER: (230, 60, 40), OUTER: (40, 110, 230), STATIC: (40, 40, 40)}
REGION_KEY = {INNER: "inner blur: uncovers something farther",
              OUTER: "outer blur: something nearer passes over",
              STATIC: "static: the same object all exposure"}
# FLIP's error in [0, 1] as colour: a ramp through magma-like control points (dark purple
# for no error to pale yellow for the largest), linear between them.
HEAT_STOPS = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
HEAT_RGB = np.array([(0, 0, 4), (81, 18, 124), (183, 55, 121), (252, 137, 97),
                     (252, 253, 191)], np.float64)


def _key_rows(entries, width: int, font) -> np.ndarray:
    """A colour key: one row per (colour, text), a square swatch then the text."""
    lh = _line_height(font)
    sw = lh - 2 * PAD
    block = Image.new("RGB", (width, lh * len(entries)), BACKGROUND)
    draw = ImageDraw.Draw(block)
    draw.fontmode = "1"
    for i, (colour, text) in enumerate(entries):
        y = i * lh
        draw.rectangle((PAD, y + PAD, PAD + sw - 1, y + PAD + sw - 1), fill=tuple(colour))
        draw.text((sw + 3 * PAD, y + PAD), text, font=font, fill=TEXT)
    return np.asarray(block)


def region_picture(region) -> np.ndarray:
    """The region map as colours (REGION_COLOURS), top row first, with its key drawn in
    rows below the map (the map's pixels are the first H rows)."""
    r = np.asarray(region)
    h, w = r.shape
    pic = np.zeros((h, w, 3), np.uint8)
    for code, colour in REGION_COLOURS.items():
        pic[r == code] = colour
    font = _font(h)
    key = _key_rows([(REGION_COLOURS[c], REGION_KEY[c]) for c in (INNER, OUTER, STATIC)],
                    w, font)
    gap = np.full((GAP, w, 3), BACKGROUND, np.uint8)
    return np.concatenate([pic, gap, key])


def heat(error) -> np.ndarray:
    """(H,W) error in [0, 1] (clamped) -> uint8 (H,W,3) heat colours (HEAT_RGB)."""
    e = np.clip(np.nan_to_num(np.asarray(error, np.float64)), 0.0, 1.0)
    rgb = np.stack([np.interp(e, HEAT_STOPS, HEAT_RGB[:, c]) for c in range(3)], -1)
    return np.floor(rgb + 0.5).astype(np.uint8)


def _colour_bar(width: int, font) -> np.ndarray:
    """A horizontal key of the heat colours from 0 to 1, with its values written below."""
    lh = _line_height(font)
    bar = heat(np.broadcast_to(np.linspace(0.0, 1.0, width), (lh, width)))
    label = Image.new("RGB", (width, lh), BACKGROUND)
    draw = ImageDraw.Draw(label)
    draw.fontmode = "1"
    draw.text((PAD, PAD), "0 (no error)", font=font, fill=TEXT)
    end = "1 (FLIP error)"
    draw.text((width - PAD - draw.textlength(end, font=font), PAD), end, font=font, fill=TEXT)
    mid = "0.5"
    draw.text(((width - draw.textlength(mid, font=font)) / 2, PAD), mid, font=font, fill=TEXT)
    return np.concatenate([bar, np.asarray(label)])


def error_strip(maps, metrics=None, inset_box=None) -> np.ndarray:
    """[(label, (H,W) FLIP error map)] -> the maps side by side as heat colours, labelled,
    with optional metric lines, the zoomed inset of `inset_box` as make_strip draws it
    (compare gives the strip's, so small errors there show), and a colour key from 0 to 1
    along the bottom."""
    strip = make_strip([(label, heat(m)) for label, m in maps], inset_box=inset_box,
                       metrics=metrics)
    h = np.asarray(maps[0][1]).shape[0]
    bar = _colour_bar(strip.shape[1], _font(h))
    gap = np.full((GAP, strip.shape[1], 3), BACKGROUND, np.uint8)
    return np.concatenate([strip, gap, bar])


# --- metrics table -------------------------------------------------------------------------

def metrics_rows(table) -> list[dict]:
    """{mode: image_metrics(...)} -> rows {mode, region, pixels, psnr, ssim, flip}, modes in
    table order, regions in the order all, static, inner, outer (those present)."""
    rows = []
    for mode, per_region in table.items():
        for region in REGION_ORDER:
            if region in per_region:
                m = per_region[region]
                rows.append({"mode": str(mode), "region": region, "pixels": int(m["pixels"]),
                             "psnr": m["psnr"], "ssim": m["ssim"], "flip": m["flip"]})
    return rows


def _fmt(value, digits: int) -> str:
    if value is None:
        return "-"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.{digits}f}"


def metrics_markdown(table, key: str = "mode") -> str:
    """The rows as a Markdown table: PSNR in dB (2 decimals), SSIM and FLIP (4 decimals);
    `key` heads the first column ("variant" where names are not bare modes)."""
    out = [f"| {key} | region | pixels | PSNR (dB) | SSIM | FLIP |",
           "| --- | --- | ---: | ---: | ---: | ---: |"]
    for r in metrics_rows(table):
        out.append(f"| {r['mode']} | {r['region']} | {r['pixels']} | {_fmt(r['psnr'], 2)} "
                   f"| {_fmt(r['ssim'], 4)} | {_fmt(r['flip'], 4)} |")
    return "\n".join(out) + "\n"
