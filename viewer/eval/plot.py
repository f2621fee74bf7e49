"""Line plots drawn with Pillow (no plotting library needed): a grid of panels, each with
axes, ticks at round numbers, a title, and one line per series; one legend below them.
Text is Pillow's bitmap font magnified by an integer factor, so a plot's pixels are the
same on every machine."""
from __future__ import annotations

import math

import numpy as np
from PIL import Image, ImageDraw, ImageFont

BACKGROUND = (255, 255, 255)
INK = (0, 0, 0)
GRID = (225, 225, 225)
TEXT_SCALE = 2
PANEL = (440, 240)            # plot area of one panel, pixels
MARGIN = (110, 36, 34, 56)    # left, top, right, bottom around a plot area
PALETTE = [(31, 119, 180), (255, 127, 14), (44, 160, 44), (214, 39, 40), (148, 103, 189),
           (140, 86, 75), (227, 119, 194), (127, 127, 127), (188, 189, 34), (23, 190, 207)]


def _font():
    if hasattr(ImageFont, "load_default_imagefont"):
        return ImageFont.load_default_imagefont()
    return ImageFont.load_default()


def text_image(text: str, colour=INK) -> Image.Image:
    font = _font()
    x0, y0, x1, y1 = font.getbbox(text or " ")
    img = Image.new("RGB", (max(1, x1) + 2, max(1, y1) + 2), BACKGROUND)
    ImageDraw.Draw(img).text((1, 1), text, font=font, fill=colour)
    return img.resize((img.width * TEXT_SCALE, img.height * TEXT_SCALE), Image.NEAREST)


def _paste(canvas: Image.Image, img: Image.Image, x: float, y: float, anchor: str = "lt"):
    """anchor: horizontal l/m/r, vertical t/m/b."""
    dx = {"l": 0, "m": img.width // 2, "r": img.width}[anchor[0]]
    dy = {"t": 0, "m": img.height // 2, "b": img.height}[anchor[1]]
    canvas.paste(img, (int(round(x)) - dx, int(round(y)) - dy))


def nice_ticks(lo: float, hi: float, target: int = 5) -> list[float]:
    """Ticks at multiples of 1, 2 or 5 x 10^k covering [lo, hi], about `target` of them."""
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi <= lo:
        hi = lo + 1.0
    raw = (hi - lo) / max(1, target)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = math.floor(lo / step + 1e-9) * step
    ticks, v = [], first
    while v < hi + step * 0.999:
        ticks.append(round(v, 12))
        v += step
    return ticks


def tick_label(v: float, ticks: list[float]) -> str:
    step = ticks[1] - ticks[0] if len(ticks) > 1 else 1.0
    digits = max(0, -int(math.floor(math.log10(step) + 1e-9)))
    if abs(v) < 1e-6 * step:          # no "-0.0" from a tick summed up to a hair below 0
        v = 0.0
    return f"{v:.{digits}f}"


def line_plots(panels, colours: dict, x_label: str, y_label: str, title: str = "",
               columns: int = 2) -> np.ndarray:
    """panels: [(title, {series label: (xs, ys)})], ys may hold None (a gap). colours:
    {series label: RGB}. Returns a uint8 (H,W,3) image."""
    labels = list(dict.fromkeys(k for _, series in panels for k in series))
    rows = math.ceil(len(panels) / columns)
    cols = min(columns, len(panels))
    cell_w = MARGIN[0] + PANEL[0] + MARGIN[2]
    cell_h = MARGIN[1] + PANEL[1] + MARGIN[3]
    head = text_image(title).height + 10 if title else 0
    legend_h = text_image("Ag").height + 16
    canvas = Image.new("RGB", (cols * cell_w, head + rows * cell_h + legend_h), BACKGROUND)
    draw = ImageDraw.Draw(canvas)
    if title:
        _paste(canvas, text_image(title), canvas.width / 2, 6, "mt")
    for i, (name, series) in enumerate(panels):
        ox = (i % columns) * cell_w + MARGIN[0]
        oy = head + (i // columns) * cell_h + MARGIN[1]
        _panel(canvas, draw, (ox, oy), name, series, colours, x_label, y_label)
    # legend: a short thick line and the label, series after series, centred
    items = [(text_image(k), colours[k]) for k in labels]
    width = sum(30 + img.width + 24 for img, _ in items)
    x = (canvas.width - width) / 2
    y = canvas.height - legend_h / 2
    for img, colour in items:
        draw.line([(x, y), (x + 24, y)], fill=colour, width=4)
        _paste(canvas, img, x + 30, y, "lm")
        x += 30 + img.width + 24
    return np.asarray(canvas)


def _panel(canvas, draw, origin, name, series, colours, x_label, y_label):
    ox, oy = origin
    pw, ph = PANEL
    xs_all = [x for xs, _ in series.values() for x in xs]
    ys_all = [y for _, ys in series.values() for y in ys if y is not None and math.isfinite(y)]
    x_lo, x_hi = (min(xs_all), max(xs_all)) if xs_all else (0.0, 1.0)
    if x_hi <= x_lo:
        x_hi = x_lo + 1.0
    y_hi = max(ys_all) if ys_all else 1.0
    xt = nice_ticks(x_lo, x_hi)
    yt = nice_ticks(0.0, y_hi if y_hi > 0 else 1.0)
    x_lo, x_hi = min(x_lo, xt[0]), max(x_hi, xt[-1])
    y_lo, y_top = 0.0, yt[-1]

    def px(x):
        return ox + (x - x_lo) / (x_hi - x_lo) * pw

    def py(y):
        return oy + ph - (y - y_lo) / (y_top - y_lo) * ph

    for v in yt:
        draw.line([(ox, py(v)), (ox + pw, py(v))], fill=GRID)
        draw.line([(ox - 5, py(v)), (ox, py(v))], fill=INK)
        _paste(canvas, text_image(tick_label(v, yt)), ox - 8, py(v), "rm")
    for v in xt:
        if x_lo - 1e-9 <= v <= x_hi + 1e-9:
            draw.line([(px(v), oy + ph), (px(v), oy + ph + 5)], fill=INK)
            _paste(canvas, text_image(tick_label(v, xt)), px(v), oy + ph + 8, "mt")
    draw.rectangle([ox, oy, ox + pw, oy + ph], outline=INK)
    _paste(canvas, text_image(name), ox + pw / 2, oy - 6, "mb")
    _paste(canvas, text_image(x_label), ox + pw / 2, oy + ph + 32, "mt")
    ylab = text_image(y_label).rotate(90, expand=True)
    _paste(canvas, ylab, ox - MARGIN[0] + 4, oy + ph / 2, "lm")
    for label, (xs, ys) in series.items():
        colour = colours[label]
        run = []
        for x, y in list(zip(xs, ys)) + [(None, None)]:
            if y is None or not math.isfinite(y):
                if len(run) > 1:
                    draw.line(run, fill=colour, width=2)
                for p in run:
                    draw.rectangle([p[0] - 2, p[1] - 2, p[0] + 2, p[1] + 2], fill=colour)
                run = []
            else:
                run.append((px(x), py(y)))
