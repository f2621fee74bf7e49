"""`hmblur compare`: every real-time mode and the reference of one frame, a labelled strip
with a zoomed inset where the inner blur is largest, and PSNR / SSIM / FLIP against the
reference per region (whole image, inner blur, outer blur, static)."""
from __future__ import annotations

from dataclasses import replace

from viewer.cli import args as cliargs
from viewer.io.sidecar import FIRST_FRAME_NOTE, sidecar
from viewer.glcontext import create_headless, device_name
from viewer.io.imageio import OutputSet, linear_to_srgb8
import hybrid_mblur as hm
from viewer.io.outdir import OutputFolder
from viewer.eval.comparison import REALTIME, Variant, check_capacity, parse_variants
from viewer.eval.metrics import SPACE
from viewer.io.progress import Progress
from viewer.render.modes.regions import DEFINITIONS, region_counts
from viewer.render.modes import MODE_GROUPS, MODES
from viewer.eval.strip import choose_inset, error_strip, make_strip, metrics_markdown, region_picture

FILES = ("regions.png", "strip.png", "flip.png", "metrics.md", "metrics.json")
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
                   help="output folder (made, with missing parents, if missing; a file of "
                        "yours there is never replaced: only the files hmblur wrote there)")
    p.add_argument("--modes", default=None, metavar="M1,M2",
                   help=f"comma-separated real-time modes (default: every one of {', '.join(REALTIME)} that exists)")
    p.add_argument("--variant", action="append", default=[], metavar="NAME=MODE[:G.F=V,...]",
                   help="a mode under a name with its own parameters, e.g. "
                        "fast=hybrid:hybrid.curve_steps=1, or a blur pass of your own: "
                        "NAME=glsl:PATH.frag, NAME=py:PATH.py:FUNCTION (docs/api.md; a "
                        "method file is code that runs) (repeatable; shown beside --modes, "
                        "which then defaults to none; the same mode may appear many times)")
    p.add_argument("--inset", type=str, default=None, metavar="WxH",
                   help="inset size in pixels (default: a quarter of the image height, square)")
    p.set_defaults(run=run)


def choose_modes(text: str | None, variants: bool = False) -> list[str]:
    """The --modes list; by default every real-time mode, or none when --variant names
    what to show."""
    available = [m for m in REALTIME if m in MODES]
    if text is None:
        return [] if variants else available
    return cliargs.parse_modes("--modes", text, available)


def choose_variants(args) -> list[Variant]:
    """--modes (each mode under its own name) then each --variant, no name twice."""
    modes = choose_modes(args.modes, bool(args.variant))
    return ([Variant(m, m) for m in modes]
            + parse_variants(args.variant, [m for m in REALTIME if m in MODES], modes, "shown"))


def label(v: Variant) -> str:
    """A column's label: the mode's own words when the variant is the bare mode."""
    return v.name if named(v) else LABELS[v.mode]


def run(args) -> int:
    s = cliargs.setup(args)
    variants = choose_variants(args)
    check_capacity(len(variants), s.size, "--modes/--variant")
    cliargs.check_set_groups(args.set, [v.runs_as for v in variants] + ["reference"],
                             {**MODE_GROUPS, **{v.runs_as: v.groups for v in variants}})
    folder = OutputFolder(cliargs.check_output_dir(args.out, "--out"), "--out")
    out = folder.path
    folder.check([f"{n}{suffix}" for n in [v.name for v in variants] + ["reference"]
                  for suffix in (".png", ".json")] + list(FILES))
    w, h = s.size
    inset = cliargs.parse_size(args.inset, "--inset") if args.inset else (max(8, h // 4),) * 2
    ctx = create_headless()
    with hm.Renderer(s.size, context=ctx) as r:     # (the context outlives it: sidecars)
        c = r.compare_frame(s.scene, variants, s.time, s.params, s.seed,
                            progress=Progress(f"reference ({s.params['reference'].samples} "
                                              "sub-frames)"),
                            log=lambda v, line: print(line))
    names = [v.name for v in variants]
    table, ref = c.table, c.reference

    box = choose_inset(c.region, inset)
    panels = [(label(v), c.results[v.name].image) for v in variants] + [(LABELS["reference"], ref.image)]
    lines = [[f"FLIP {table[n]['all']['flip']:.3f} all",
              f"FLIP {fmt(table[n]['inner']['flip'])} inner"] for n in names]
    lines.append([f"{s.params['reference'].samples} sub-frames", "ground truth"])
    strip = make_strip(panels, inset_box=box, metrics=lines)
    errors = error_strip([(f"{label(v)}: FLIP", c.flips[v.name]) for v in variants],
                         metrics=[[f"mean {table[n]['all']['flip']:.4f}"] for n in names],
                         inset_box=box)

    files = OutputSet(folder)            # all of them, or none
    for v in variants:                   # each image with the sidecar that remakes it
        vs = replace(s, params=c.params[v.name])
        side = sidecar(vs, v.mode, c.results[v.name], ctx, args.scene, first_frame=True,
                       ms=c.ms[v.name], groups=v.groups)
        if named(v):
            side["variant"] = {"name": v.name, **variant_doc(v)}
        files.png(out / f"{v.name}.png", linear_to_srgb8(c.results[v.name].image))
        files.json(out / f"{v.name}.json", side)
    files.png(out / "reference.png", linear_to_srgb8(ref.image))
    files.json(out / "reference.json", sidecar(s, "reference", ref, ctx, args.scene,
                                               first_frame=True, ms=c.ms["reference"]))
    files.png(out / "regions.png", region_picture(c.region))
    files.png(out / "strip.png", strip)
    files.png(out / "flip.png", errors)
    md = metrics_markdown(table, key="mode" if all(v.name == v.mode for v in variants)
                          else "variant")
    steps = s.params["motion"].steps
    header = (f"# {s.scene.name}: {w}x{h}, t = {s.time:g} s, shutter {s.scene.camera.shutter:g} s, "
              + (f"motion.steps={steps} (the blurring modes), " if steps > 1 else "")
              + f"reference {s.params['reference'].samples} sub-frames\n\nSpace: {SPACE}.\n\n"
              + "".join(f"- {v.name}: {v.describe()}\n" for v in variants if named(v))
              + ("\n" if any(named(v) for v in variants) else "")
              + "Regions (regions.png), from the reference's own visibility at each of its "
              "sub-frames:\n\n" + "".join(f"- {d}\n" for d in DEFINITIONS.values()) + "\n")
    text = (header + md).encode("utf-8")
    files.add(out / "metrics.md", lambda f: f.write(text))
    files.json(out / "metrics.json", {
        **cliargs.scene_source(args.scene), "scene_name": s.scene.name, "size": [w, h],
        "time": s.time, "shutter": s.scene.camera.shutter,
        "seed": s.seed, "device": device_name(ctx), "params": s.params.to_dict(),
        "variants": {v.name: variant_doc(v) for v in variants},
        "regions": region_counts(c.region), "region_definitions": DEFINITIONS,
        "inset": list(box), "metrics": table, "space": SPACE,
        "ms": c.ms, "ms_note": FIRST_FRAME_NOTE, "stats": {**{n: c.results[n].stats for n in names},
                              "reference": ref.stats},
    })
    files.commit()
    print(md)
    print(f"{out}: strip.png, flip.png, regions.png, metrics.md, metrics.json, "
          f"{len(variants) + 1} images (first-frame times include shader compiles and set-up; "
          "'hmblur bench' times warm frames)")
    return 0


def named(v: Variant) -> bool:
    """Whether the variant is more than a bare mode under its own name."""
    return v.name != v.mode or bool(v.sets) or v.method is not None


def variant_doc(v: Variant) -> dict:
    """A variant in metrics.json and its image's sidecar: its mode (a user pass: its kind,
    file, function and the sha256 of what ran) and assignments."""
    doc = {"mode": v.mode, "set": v.sets}
    if v.method is not None:
        m = v.method
        doc["method"] = {"spec": m.spec, "path": str(m.path) if m.path else None,
                         "function": m.function or None, "sha256": m.digest}
    return doc


def fmt(v) -> str:
    return "n/a" if v is None else f"{v:.4f}"
