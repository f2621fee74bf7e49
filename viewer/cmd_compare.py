"""`hmblur compare`: every real-time mode and the reference of one frame, a labelled strip
with a zoomed inset where the inner blur is largest, and PSNR / SSIM / FLIP against the
reference per region (whole image, inner blur, outer blur, static)."""
from __future__ import annotations

import time

import numpy as np

from . import cliargs
from .cmd_shot import sidecar
from .glcontext import create_headless, device_name
from .imageio import OutputSet, linear_to_srgb8
from .metrics import SPACE, image_metrics
from .progress import Progress
from .regions import INNER, OUTER, region_counts
from .render.modes import MODES
from .render.renderer import Renderer
from .strip import choose_inset, make_strip, metrics_markdown

REALTIME = ("off", "mcguire", "ue4", "guertin", "hybrid")
LABELS = {"off": "off (sharp)", "mcguire": "McGuire 2012", "ue4": "UE4-style",
          "guertin": "Guertin 2014",
          "hybrid": "hybrid", "reference": "reference"}


def register(sub):
    p = sub.add_parser("compare", help="all modes side by side, with metrics against the reference")
    cliargs.add_scene_args(p)
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--modes", default=None,
                   help=f"comma-separated real-time modes (default: every one of {', '.join(REALTIME)} that exists)")
    p.add_argument("--inset", type=str, default=None, metavar="WxH",
                   help="inset size in pixels (default: a quarter of the image height, square)")
    p.set_defaults(run=run)


def region_picture(region: np.ndarray) -> np.ndarray:
    pic = np.zeros(region.shape + (3,), np.uint8)
    pic[region == INNER] = (230, 60, 40)
    pic[region == OUTER] = (40, 110, 230)
    pic[region == 0] = (40, 40, 40)
    return pic


def choose_modes(text: str | None) -> list[str]:
    available = [m for m in REALTIME if m in MODES]
    return available if text is None else cliargs.parse_modes("--modes", text, available)


def run(args) -> int:
    s = cliargs.setup(args)
    modes = choose_modes(args.modes)
    out = cliargs.check_output_dir(args.out, "--out")
    w, h = s.size
    inset = cliargs.parse_size(args.inset, "--inset") if args.inset else (max(8, h // 4),) * 2
    ctx = create_headless()
    r = Renderer(ctx, s.scene, s.size)
    images, results, table, timings = {}, {}, {}, {}
    try:
        t0 = time.perf_counter()
        ref = r.render("reference", s.time, s.params, seed=s.seed, record_visibility=True,
                       progress=Progress(f"reference ({s.params['reference'].samples} sub-frames)"))
        timings["reference"] = (time.perf_counter() - t0) * 1e3
        region = ref.host["regions"]
        for mode in modes:
            t0 = time.perf_counter()
            res = r.render(mode, s.time, s.params, seed=s.seed)
            timings[mode] = (time.perf_counter() - t0) * 1e3
            images[mode], results[mode] = res.image, res
            table[mode] = image_metrics(res.image, ref.image, region)
            print(f"{mode}: FLIP {table[mode]['all']['flip']:.4f} "
                  f"(inner {fmt(table[mode]['inner']['flip'])}) in {timings[mode]:.0f} ms")
        images["reference"], results["reference"] = ref.image, ref
    finally:
        r.release()

    box = choose_inset(region, inset)
    panels = [(LABELS[m], images[m]) for m in modes] + [(LABELS["reference"], ref.image)]
    lines = [[f"FLIP {table[m]['all']['flip']:.3f} all",
              f"FLIP {fmt(table[m]['inner']['flip'])} inner"] for m in modes]
    lines.append([f"{s.params['reference'].samples} sub-frames", "ground truth"])
    strip = make_strip(panels, inset_box=box, metrics=lines)

    files = OutputSet()                  # all of them, or none
    for mode, img in images.items():
        files.png(out / f"{mode}.png", linear_to_srgb8(img))
        files.json(out / f"{mode}.json", sidecar(s, mode, results[mode], ctx, args.scene))
    files.png(out / "regions.png", region_picture(region))
    files.png(out / "strip.png", strip)
    md = metrics_markdown(table)
    header = (f"# {s.scene.name}: {w}x{h}, t = {s.time:g} s, shutter {s.scene.camera.shutter:g} s, "
              f"reference {s.params['reference'].samples} sub-frames\n\nSpace: {SPACE}.\n\n")
    text = (header + md).encode("utf-8")
    files.add(out / "metrics.md", lambda f: f.write(text))
    files.json(out / "metrics.json", {
        "scene": args.scene, "scene_name": s.scene.name, "size": [w, h], "time": s.time,
        "seed": s.seed, "device": device_name(ctx), "params": s.params.to_dict(),
        "regions": region_counts(region), "inset": list(box), "metrics": table, "space": SPACE,
        "ms": timings, "stats": {m: results[m].stats for m in results},
    })
    files.commit()
    print(md)
    print(f"{out}: strip.png, metrics.md, metrics.json, {len(images)} images")
    return 0


def fmt(v) -> str:
    return "n/a" if v is None else f"{v:.4f}"
