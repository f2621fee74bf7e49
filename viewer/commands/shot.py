"""`hmblur shot`: render one mode of a scene to an sRGB PNG, with a JSON sidecar."""
from __future__ import annotations

import time

from viewer.cli import args as cliargs
from viewer.glcontext import create_headless
import hybrid_mblur as hm
from viewer.io.imageio import OutputSet
from viewer.io.outdir import OutputFolder
from viewer.io.sidecar import sidecar
from viewer.render.modes import MODE_GROUPS, MODES
from viewer.render.modes.user import USER_GROUPS, UserPass, parse_method
from viewer.render.modes.user.method import KINDS
from viewer.io.buffer_docs import buffers_readme
from viewer.io.visualize import visualise


def register(sub):
    p = sub.add_parser("shot", help="render one mode to a PNG (with a JSON sidecar)",
                       description="Render one mode of a scene to an sRGB 8-bit PNG (top row "
                       "first) and write a JSON sidecar beside it (x.png -> x.json) holding "
                       "every parameter, the scene, camera, time, size, seed, device and the "
                       "frame's counters; 'hmblur shot --params x.json --out y.png' "
                       "reproduces it byte for byte.")
    cliargs.add_scene_args(p)
    cliargs.add_mode_arg(p, MODES, user=True)
    p.add_argument("--out", required=True, metavar="PATH.png",
                   help="output PNG path (missing folders are made; the .json sidecar goes "
                        "beside it)")
    p.add_argument("--buffers", default=None, metavar="DIR",
                   help="also write every intermediate texture as .npy (raw) and .png "
                        "(viewable), with README.txt saying what each holds")
    p.set_defaults(run=run)


def user_mode(flag: str | None, sidecar: dict | None) -> UserPass | None:
    """--mode glsl:PATH or py:PATH:FUNCTION (or the --params file's): a user's pass."""
    text = flag if flag is not None else (sidecar or {}).get("mode")
    if isinstance(text, str) and text.partition(":")[0] in KINDS:
        return parse_method(text, label=f"--mode {text}")
    return None


def run(args) -> int:
    s = cliargs.setup(args)
    method = user_mode(args.mode, s.sidecar)
    # (a user's pass renders under its file's name; the sidecar keeps its spec)
    mode = (method.path.stem + (f".{method.function}" if method.function else "")
            if method else cliargs.pick_mode(args.mode, s.sidecar, MODES))
    groups = {**MODE_GROUPS, **({mode: USER_GROUPS} if method else {})}
    cliargs.check_set_groups(args.set, [mode], groups)
    cliargs.check_samples_read(args.samples, [mode])
    if args.buffers is None:          # (the buffers hold the exposure's velocities)
        cliargs.check_shutter_read(args.shutter, [mode], " (only --buffers would show its velocities)")
    out = cliargs.check_output_file(args.out, suffix=".png")
    side = out.with_suffix(".json")
    cliargs.check_output_file(str(side), "--out's sidecar")
    bufdir = (OutputFolder(cliargs.check_output_dir(args.buffers, "--buffers"), "--buffers")
              if args.buffers is not None else None)
    ctx = create_headless()
    files = OutputSet(bufdir)
    with hm.Renderer(s.size, context=ctx) as r:     # (the context outlives it: the sidecar)
        if method is not None:
            r.register(mode, method)
        t0 = time.perf_counter()
        res = r.render(s.scene, mode, s.time, s.params, s.seed, buffers=bufdir is not None)
        ms = (time.perf_counter() - t0) * 1e3
    if bufdir is not None:
        add_buffers(files, res.buffers, bufdir, mode)
    files.png(out, res.srgb)
    files.json(side, sidecar(s, method.spec if method else mode, res, ctx, args.scene,
                             first_frame=True, ms=ms, groups=groups[mode]))
    files.commit()
    print(f"{out}: {mode} {s.size[0]}x{s.size[1]} t={s.time:g} in {ms:.0f} ms "
          "(first frame: set-up included; 'hmblur bench' times warm frames)")
    return 0


def add_buffers(files: OutputSet, bufs: dict, out: OutputFolder, mode: str):
    """Every texture the frame made (name -> array), as .npy and .png, with README.txt,
    into a folder of hmblur's rule (its names are checked once the frame says which they
    are, before any is written)."""
    folder = out.path
    out.check([f"{name}{suffix}" for name in bufs for suffix in (".npy", ".png")]
              + ["README.txt"])
    for name, a in bufs.items():
        files.npy(folder / f"{name}.npy", a)
        files.png(folder / f"{name}.png", visualise(name, a))
    text = buffers_readme(bufs, mode).encode("utf-8")
    files.add(folder / "README.txt", lambda f: f.write(text))
