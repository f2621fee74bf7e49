"""`hmblur video`: a sequence of frames, frame k at time start + k / fps, the chosen modes
side by side (labelled as in `compare`'s strip; one mode alone is its bare image, the
pixels `hmblur shot` writes), written as MP4, GIF or a folder of PNGs, with a JSON sidecar
that `--params` reproduces it from; `--metrics` adds per-frame FLIP/PSNR/SSIM against the
reference per region, the flicker of each mode (viewer/eval/temporal.py) and a plot."""
from __future__ import annotations

import argparse
import csv
import io
import time
from pathlib import Path

from world import limits
from viewer.cli import args as cliargs
from viewer.commands.compare import LABELS
from viewer.io.sidecar import camera_dict
from world.errors import UserError
from viewer.io.imageio import OutputSet, linear_to_srgb8
from viewer.eval.metrics import SPACE, image_metrics
from viewer.eval.plot import PALETTE, line_plots
from viewer.io.progress import Progress
from viewer.eval.comparison import parse_variants, prepare_variants
from viewer.render.modes import MODE_GROUPS, MODES
from viewer.render.modes.reference import REGIONS
from viewer.eval.strip import REGION_ORDER, make_strip
from viewer.eval.temporal import FlickerAccumulator
from viewer.io.video_writer import OUT_HELP, VideoPaths, VideoWriter, check_folder_collisions, video_paths

DEFAULT_FRAMES = 24
DEFAULT_FPS = 24.0
METRIC_FILES = (("metrics", ".csv"), ("flicker", ".csv"), ("flip", ".png"))
CSV_FIELDS = ("frame", "time", "mode", "region", "pixels", "flip", "psnr", "ssim")
MODE_COLOURS = {"off": (127, 127, 127), "mcguire": PALETTE[0], "ue4": PALETTE[1],
                "hybrid": PALETTE[2]}


def register(sub):
    p = sub.add_parser(
        "video", help="a sequence of frames, modes side by side, as MP4, GIF or PNGs",
        description="Frame k at time START + k / FPS (objects, keys and camera advance); two "
                    "or more modes side by side with labels, one mode as its bare image (a PNG "
                    "frame is then byte-identical to `hmblur shot` at that time).")
    cliargs.add_scene_args(
        p, scene_help="scene file (.toml), glTF asset (.gltf, .glb) or built-in scene name "
                      "(default: the --params file's)",
        time_help="time of the first frame in seconds (--start is the same flag; default: "
                  "the scene's [render] time)", time_aliases=("--start",))
    p.add_argument("--modes", default=None,
                   help=f"comma-separated, any of {', '.join(MODES)} (default: the --params "
                        "file's, else every mode but reference)")
    p.add_argument("--variant", action="append", default=[], metavar="NAME=MODE[:G.F=V,...]",
                   help="also draw a mode under a name with its own parameters, or a user's "
                        "blur pass NAME=glsl:PATH / NAME=py:PATH:FUNCTION (as compare's "
                        "--variant; repeatable; --modes then defaults to none)")
    p.add_argument("--frames", type=str, default=None,
                   help=f"number of frames (default {DEFAULT_FRAMES})")
    p.add_argument("--fps", type=str, default=None,
                   help=f"frames per second: frame k is at time + k / fps (default {DEFAULT_FPS:g})")
    p.add_argument("--out", required=True, help=OUT_HELP)
    p.add_argument("--metrics", action="store_true",
                   help="also render the reference of every frame and write per-frame "
                        "FLIP/PSNR/SSIM against it per region (PATH_metrics.csv), each mode's "
                        "flicker (PATH_flicker.csv) and a plot of FLIP over time "
                        "(PATH_flip.png); in a folder metrics.csv, flicker.csv, flip.png")
    p.set_defaults(run=run)


def mode_colours(modes) -> dict:
    spare = iter(c for c in PALETTE[3:] if c not in MODE_COLOURS.values())
    return {m: MODE_COLOURS.get(m) or next(spare, (90, 90, 90)) for m in modes}


def frame_times(start: float, frames: int, fps: float):
    """Frame k's time, k = 0 .. frames - 1, made as it is asked for."""
    return (start + k / fps for k in range(frames))


def compose(images: dict) -> "np.ndarray":
    """One mode: its sRGB image as shot writes it; more: the labelled strip."""
    if len(images) == 1:
        (img,) = images.values()
        return linear_to_srgb8(img)
    return make_strip([(LABELS.get(m, m), img) for m, img in images.items()])


def run(args) -> int:
    side = cliargs.read_sidecar(args.params) if args.params else {}
    if args.scene is not None:
        scene = args.scene
    elif args.params:
        scene = cliargs.sidecar_scene(side, args.params)
    else:
        raise UserError("video: expected a SCENE (a file or built-in name), or --params "
                        "with the sidecar of an earlier video")
    setup_args = argparse.Namespace(scene=scene, time=args.time, size=args.size,
                                    samples=args.samples, seed=args.seed, shutter=args.shutter,
                                    set=args.set, params=args.params)
    s = cliargs.setup(setup_args)
    src = f"--params {args.params}"
    modes_text = args.modes
    if modes_text is None and isinstance(side.get("modes"), list):
        modes_text = ",".join(map(str, side["modes"]))
    elif modes_text is None and isinstance(side.get("mode"), str):   # a shot's sidecar
        modes_text = side["mode"]
    variant_texts = args.variant or [str(v) for v in side.get("variants", [])
                                     if args.modes is None]
    if modes_text is None or (not modes_text and variant_texts):
        modes = [] if variant_texts else [m for m in MODES if m != "reference"]
    else:
        flag = "--modes" if args.modes is not None else f"{src}: modes"
        modes = cliargs.parse_modes(flag, modes_text, list(MODES))
    variants = parse_variants(variant_texts, [m for m in MODES if m != "reference"], modes,
                              "drawn")
    cliargs.check_set_groups(args.set, modes + [v.name for v in variants] + ["reference"],
                             {**MODE_GROUPS, **{v.name: v.groups for v in variants}})
    modes = modes + [v.name for v in variants]
    frames = (cliargs.parse_int("--frames", args.frames, 1, limits.MAX_FRAMES)
              if args.frames is not None else
              cliargs.parse_int(f"{src}: frames", str(side["frames"]), 1, limits.MAX_FRAMES)
              if "frames" in side else DEFAULT_FRAMES)
    fps = (parse_fps("--fps", args.fps) if args.fps is not None else
           parse_fps(f"{src}: fps", str(side["fps"])) if "fps" in side else DEFAULT_FPS)
    if args.metrics and modes == ["reference"]:
        raise UserError("--metrics: measures modes against the reference: expected --modes "
                        "with a mode other than reference")
    rendered = modes + (["reference"] if args.metrics else [])
    cliargs.check_samples_read(args.samples, rendered, " (the reference is rendered with --metrics)")
    cliargs.check_shutter_read(args.shutter, rendered)
    cliargs.parse_time("last frame time", repr(s.time + (frames - 1) / fps))
    out = video_paths(args.out, "--out", METRIC_FILES if args.metrics else ())
    check_gif_memory(out, frames, s.size, len(modes))
    check_folder_collisions(out, frames, METRIC_FILES if args.metrics else ())
    times = frame_times(s.time, frames, fps)
    from viewer.glcontext import create_headless, device_name
    from viewer.render.renderer import Renderer
    ctx = create_headless()
    r = Renderer(ctx, s.scene, s.size)
    own = prepare_variants(r, variants, s.params)
    metrics = VideoMetrics(modes) if args.metrics else None
    progress = Progress(f"{s.scene.name}: {frames} frames of {', '.join(modes)}"
                        + (" + metrics" if metrics and "reference" not in modes else ""))
    t0 = time.perf_counter()
    try:
        with VideoWriter(out, fps) as writer:
            for k, t in enumerate(times):
                images, ref = {}, None
                for m in modes:
                    runs_as, params = own.get(m, (m, s.params))
                    res = r.render(runs_as, t, params, seed=s.seed,
                                   record_visibility=metrics is not None and m == "reference")
                    images[m] = res.image
                    if m == "reference":
                        ref = res
                if metrics is not None:
                    if ref is None:
                        ref = r.render("reference", t, s.params, seed=s.seed, record_visibility=True)
                    metrics.add(k, t, images, ref.image, ref.host[REGIONS])
                writer.add(compose(images))
                progress(k, frames)
            seconds = time.perf_counter() - t0
            files = out.output_set()
            doc = sidecar(s, scene, [m for m in modes if m not in own], frames, fps, out,
                          device_name(ctx), seconds)
            if variants:
                doc["variants"] = [t for t in variant_texts]
            if metrics is not None:
                doc["flicker"] = metrics.flicker()
                doc["metrics_space"] = SPACE
                metrics.write(files, out)
            files.json(out.beside("", ".json"), doc)
            writer.commit(files)
    finally:
        r.release()
    w, h = writer.file_size
    print(f"{out.video}: {frames} frames {w}x{h} ({', '.join(modes)}) at {fps:g} fps, "
          f"{out.kind}, in {seconds:.1f} s ({1e3 * seconds / frames:.0f} ms/frame)")
    if metrics is not None:
        print(metrics.flicker_table())
    return 0


parse_fps = cliargs.parse_fps
# A GIF is written in one piece (one palette for the clip): its frames are held in memory.
MAX_GIF_BYTES = 1 << 30


def check_gif_memory(out: VideoPaths, frames: int, size, n_modes: int):
    """A GIF's frames, all held until it is written, must fit MAX_GIF_BYTES (an estimate:
    the modes side by side, 3 bytes a pixel)."""
    need = frames * size[0] * size[1] * n_modes * 3
    if out.kind == "gif" and need > MAX_GIF_BYTES:
        raise UserError(f"{out.flag} {out.video}: a GIF holds every frame in memory until it "
                        f"is written: {frames} frames of {n_modes} x {size[0]}x{size[1]} are "
                        f"~{need >> 20} MB, more than {MAX_GIF_BYTES >> 20} MB: write .mp4 or "
                        "a folder, or fewer frames")


def sidecar(s: cliargs.Setup, scene: str, modes, frames: int, fps: float, out: VideoPaths,
            device: str, seconds: float) -> dict:
    return {
        **cliargs.scene_source(scene),
        **({"animations": dict(s.animations)} if s.animations else {}),
        "scene_name": s.scene.name,
        "modes": list(modes),
        "time": s.time,                # of frame 0; frame k is at time + k / fps
        "frames": frames,
        "fps": fps,
        "size": list(s.size),          # of each mode's image
        "seed": s.seed,
        "params": s.params.to_dict(),
        "camera": camera_dict(s.scene.camera),
        "format": out.kind,
        "device": device,
        "seconds": seconds,
    }


class VideoMetrics:
    """Per frame: every listed mode but the reference against that frame's reference."""

    def __init__(self, modes):
        self.modes = [m for m in modes if m != "reference"]
        self.rows: list[dict] = []
        self.acc = {m: FlickerAccumulator() for m in self.modes}

    def add(self, k: int, t: float, images: dict, ref_image, region):
        ref8 = linear_to_srgb8(ref_image)
        for m in self.modes:
            table = image_metrics(images[m], ref_image, region)
            for name in REGION_ORDER:
                v = table[name]
                self.rows.append({"frame": k, "time": t, "mode": m, "region": name,
                                  "pixels": v["pixels"], "flip": v["flip"], "psnr": v["psnr"],
                                  "ssim": v["ssim"]})
            self.acc[m].add(linear_to_srgb8(images[m]), ref8, region)

    def flicker(self) -> dict:
        return {m: self.acc[m].result() for m in self.modes}

    def flicker_table(self) -> str:
        lines = ["| mode | " + " | ".join(f"flicker {r}" for r in REGION_ORDER) + " |",
                 "| --- |" + " ---: |" * len(REGION_ORDER)]
        for m, per in self.flicker().items():
            lines.append(f"| {m} | " + " | ".join(_fmt(per[r]["flicker"]) for r in REGION_ORDER) + " |")
        return "\n".join(lines) + "\n(flicker: mean |frame-to-frame change - the reference's|, 8-bit sRGB codes)"

    def csv_text(self) -> str:
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=CSV_FIELDS, lineterminator="\n")
        w.writeheader()
        for row in self.rows:
            w.writerow({k: _cell(row[k]) for k in CSV_FIELDS})
        return buf.getvalue()

    def flicker_csv(self) -> str:
        buf = io.StringIO()
        fields = ("mode", "region", "pairs", "flicker", "change", "reference_change")
        w = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        for m, per in self.flicker().items():
            for region in REGION_ORDER:
                v = per[region]
                w.writerow({"mode": m, "region": region, **{k: _cell(v[k]) for k in fields[2:]}})
        return buf.getvalue()

    def plot(self):
        colours = mode_colours(self.modes)
        panels = []
        for region in REGION_ORDER:
            series = {}
            for m in self.modes:
                rows = [r for r in self.rows if r["mode"] == m and r["region"] == region]
                series[m] = ([r["time"] for r in rows], [r["flip"] for r in rows])
            panels.append(("all (whole image)" if region == "all" else region, series))
        return line_plots(panels, colours, "time (s)", "FLIP", title="FLIP against the reference")

    def write(self, files: OutputSet, out: VideoPaths):
        for (name, suffix), data in zip(METRIC_FILES[:2], (self.csv_text(), self.flicker_csv())):
            payload = data.encode("utf-8")
            files.add(out.beside(name, suffix), lambda f, b=payload: f.write(b))
        files.png(out.beside(*METRIC_FILES[2]), self.plot())


def _cell(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "inf" if v == float("inf") else repr(v)
    return v


def _fmt(v) -> str:
    return "-" if v is None else f"{v:.3f}"
