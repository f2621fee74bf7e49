"""`hmblur shot`: render one mode of a scene to an sRGB PNG, with a JSON sidecar."""
from __future__ import annotations

import time
from pathlib import Path

from . import cliargs
from .glcontext import create_headless, device_name
from .imageio import OutputSet, linear_to_srgb8
from .render.modes import MODE_GROUPS, MODES
from .render.renderer import Renderer
from .visualize import visualise


def register(sub):
    p = sub.add_parser("shot", help="render one mode to a PNG")
    cliargs.add_scene_args(p)
    p.add_argument("--mode", default=None,
                   help=f"one of: {', '.join(MODES)} (default off, or the --params file's)")
    p.add_argument("--out", required=True, help="output PNG path (a .json sidecar goes beside it)")
    p.add_argument("--buffers", default=None, metavar="DIR",
                   help="also write every intermediate texture as .npy (raw) and .png (viewable)")
    p.set_defaults(run=run)


def camera_dict(spec) -> dict:
    return spec.to_dict()


def sidecar(s: cliargs.Setup, mode: str, result, ctx, scene_arg: str) -> dict:
    return {
        "scene": scene_arg,
        "scene_name": s.scene.name,
        "mode": mode,
        "time": s.time,
        "size": list(s.size),
        "seed": s.seed,
        "params": s.params.to_dict(MODE_GROUPS.get(mode, ())),
        "camera": camera_dict(s.scene.camera),
        "device": device_name(ctx),
        "stats": result.stats,
    }


def run(args) -> int:
    s = cliargs.setup(args)
    mode = args.mode or (s.sidecar or {}).get("mode") or "off"
    if mode not in MODES:
        raise cliargs.UserError(f"--mode {mode}: expected one of {', '.join(MODES)}")
    out = cliargs.check_output_file(args.out)
    side = out.with_suffix(".json")
    if side == out:
        raise cliargs.UserError(f"--out {args.out}: the JSON sidecar goes to the same path "
                                "with .json: expected an image path such as x.png")
    cliargs.check_output_file(str(side), "--out's sidecar")
    bufdir = cliargs.check_output_dir(args.buffers, "--buffers") if args.buffers is not None else None
    ctx = create_headless()
    r = Renderer(ctx, s.scene, s.size)
    files = OutputSet()
    try:
        t0 = time.perf_counter()
        res = r.render(mode, s.time, s.params, seed=s.seed)
        ms = (time.perf_counter() - t0) * 1e3
        if bufdir is not None:
            add_buffers(files, r, bufdir)
        files.png(out, linear_to_srgb8(res.image))
        files.json(side, sidecar(s, mode, res, ctx, args.scene))
    finally:
        r.release()
    files.commit()
    print(f"{out}: {mode} {s.size[0]}x{s.size[1]} t={s.time:g} in {ms:.0f} ms")
    return 0


def add_buffers(files: OutputSet, r: Renderer, folder: Path):
    for name, a in r.buffers().items():
        files.npy(folder / f"{name}.npy", a)
        files.png(folder / f"{name}.png", visualise(name, a))
