"""`hmblur compare`: every real-time mode and the reference of one frame, a labelled strip
with a zoomed inset where the inner blur is largest, and PSNR / SSIM / FLIP against the
reference per region (whole image, inner blur, outer blur, static)."""
from __future__ import annotations

import time

from . import cliargs
from .cmd_shot import FIRST_FRAME_NOTE, sidecar
from .glcontext import create_headless, device_name
from .imageio import OutputSet, linear_to_srgb8
from .metrics import SPACE, metric_maps, region_metrics
from .progress import Progress
from .regions import DEFINITIONS, region_counts
from .render.modes import MODE_GROUPS, MODES
from .render.reference import REGIONS
from .render.renderer import Renderer
from .strip import choose_inset, error_strip, make_strip, metrics_markdown, region_picture

REALTIME = ("off", "mcguire", "ue4", "guertin", "hybrid")
LABELS = {"off": "off (sharp)", "mcguire": "McGuire 2012", "ue4": "UE4-style",
          "guertin": "Guertin 2014",
          "hybrid": "hybrid", "reference": "reference"}


def register(sub):
    p = sub.add_parser("compare", help="all modes side by side, with metrics against the reference",
                       description="Render the reference and every real-time mode of one "
                       "frame; write each mode's PNG and sidecar, strip.png (labelled, with a "
                       "zoomed inset where the inner blur is densest), flip.png (each mode's "
                       "FLIP error map, with the same inset and a colour key), regions.png (the blur regions, "
                       "with a key) and metrics.md / metrics.json (PSNR, SSIM, FLIP per "
                       "region, with pixel counts and the space they are computed in).")
    cliargs.add_scene_args(p)
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder (made, with missing parents, if missing)")
    p.add_argument("--modes", default=None, metavar="M1,M2",
                   help=f"comma-separated real-time modes (default: every one of {', '.join(REALTIME)} that exists)")
    p.add_argument("--inset", type=str, default=None, metavar="WxH",
                   help="inset size in pixels (default: a quarter of the image height, square)")
    p.set_defaults(run=run)


def choose_modes(text: str | None) -> list[str]:
    available = [m for m in REALTIME if m in MODES]
    return available if text is None else cliargs.parse_modes("--modes", text, available)


def run(args) -> int:
    s = cliargs.setup(args)
    modes = choose_modes(args.modes)
    cliargs.check_set_groups(args.set, modes + ["reference"], MODE_GROUPS)
    out = cliargs.check_output_dir(args.out, "--out")
    w, h = s.size
    inset = cliargs.parse_size(args.inset, "--inset") if args.inset else (max(8, h // 4),) * 2
    ctx = create_headless()
    r = Renderer(ctx, s.scene, s.size)
    images, results, table, timings, flips = {}, {}, {}, {}, {}
    try:
        t0 = time.perf_counter()
        ref = r.render("reference", s.time, s.params, seed=s.seed, record_visibility=True,
                       progress=Progress(f"reference ({s.params['reference'].samples} sub-frames)"))
        timings["reference"] = (time.perf_counter() - t0) * 1e3
        region = ref.host[REGIONS]
        for mode in modes:
            t0 = time.perf_counter()
            res = r.render(mode, s.time, s.params, seed=s.seed)
            timings[mode] = (time.perf_counter() - t0) * 1e3
            images[mode], results[mode] = res.image, res
            maps = metric_maps(res.image, ref.image)
            table[mode], flips[mode] = region_metrics(maps, region), maps["flip"]
            print(f"{mode}: FLIP {table[mode]['all']['flip']:.4f} "
                  f"(inner {fmt(table[mode]['inner']['flip'])}), first frame {timings[mode]:.0f} ms")
        images["reference"], results["reference"] = ref.image, ref
    finally:
        r.release()

    box = choose_inset(region, inset)
    panels = [(LABELS[m], images[m]) for m in modes] + [(LABELS["reference"], ref.image)]
    lines = [[f"FLIP {table[m]['all']['flip']:.3f} all",
              f"FLIP {fmt(table[m]['inner']['flip'])} inner"] for m in modes]
    lines.append([f"{s.params['reference'].samples} sub-frames", "ground truth"])
    strip = make_strip(panels, inset_box=box, metrics=lines)
    errors = error_strip([(f"{LABELS[m]}: FLIP", flips[m]) for m in modes],
                         metrics=[[f"mean {table[m]['all']['flip']:.4f}"] for m in modes],
                         inset_box=box)

    files = OutputSet()                  # all of them, or none
    for mode, img in images.items():
        files.png(out / f"{mode}.png", linear_to_srgb8(img))
        files.json(out / f"{mode}.json", sidecar(s, mode, results[mode], ctx, args.scene,
                                                 first_frame=True, ms=timings[mode]))
    files.png(out / "regions.png", region_picture(region))
    files.png(out / "strip.png", strip)
    files.png(out / "flip.png", errors)
    md = metrics_markdown(table)
    steps = s.params["motion"].steps
    header = (f"# {s.scene.name}: {w}x{h}, t = {s.time:g} s, shutter {s.scene.camera.shutter:g} s, "
              + (f"motion.steps={steps} (the blurring modes), " if steps > 1 else "")
              + f"reference {s.params['reference'].samples} sub-frames\n\nSpace: {SPACE}.\n\n"
              "Regions (regions.png), from the reference's own visibility at each of its "
              "sub-frames:\n\n" + "".join(f"- {d}\n" for d in DEFINITIONS.values()) + "\n")
    text = (header + md).encode("utf-8")
    files.add(out / "metrics.md", lambda f: f.write(text))
    files.json(out / "metrics.json", {
        **cliargs.scene_source(args.scene), "scene_name": s.scene.name, "size": [w, h],
        "time": s.time,
        "seed": s.seed, "device": device_name(ctx), "params": s.params.to_dict(),
        "regions": region_counts(region), "region_definitions": DEFINITIONS,
        "inset": list(box), "metrics": table, "space": SPACE,
        "ms": timings, "ms_note": FIRST_FRAME_NOTE,
        "stats": {m: results[m].stats for m in results},
    })
    files.commit()
    print(md)
    print(f"{out}: strip.png, flip.png, regions.png, metrics.md, metrics.json, "
          f"{len(images)} images (first-frame times include shader compiles and set-up; "
          "'hmblur bench' times warm frames)")
    return 0


def fmt(v) -> str:
    return "n/a" if v is None else f"{v:.4f}"
