"""`hmblur bench`: frame and per-pass times of every real-time mode (medians and spread),
the hybrid reveal's rays and throughput against bare Embree on the same rays, and the
ratios hybrid/McGuire and UE4/McGuire, all measured in one run. Frame times are
synchronised (ctx.finish() and a CPU clock); pass times too on software GL, whose timer
queries only see submission, and GL timer queries on a GPU driver (render/timing.py)."""
from __future__ import annotations

import platform
import textwrap
import time

import numpy as np

from world import limits
from viewer.cli import args as cliargs
from viewer.eval.comparison import REALTIME, parse_variants, prepare_variants
from viewer.glcontext import create_headless, device_name
from viewer.io.imageio import write_json_atomic
from viewer.io.progress import Progress
from viewer.render.modes import MODE_GROUPS, MODES
from viewer.render.renderer import Renderer
from viewer.render.timing import PassClock, describe, gpu_timers_truthful

# Bounds of --speeds and --animate: beyond them a scene's motion is no longer a frame's.
MAX_SPEED = 1e3
MIN_FPS, MAX_FPS = 1e-3, 1e6
MAX_SPEEDS = 64              # --speeds factors (each a set of timed frames)


def register(sub):
    p = sub.add_parser("bench", help="time every real-time mode and pass",
                       description="Time every real-time mode and each of its passes, "
                       "round-robin (medians and p10-p90), the ratios to McGuire, and the "
                       "hybrid reveal's rays against bare Embree on the same rays.")
    cliargs.add_scene_args(p, samples=False)
    p.add_argument("--frames", default="30", metavar="N", help="timed frames per mode (default 30)")
    p.add_argument("--warmup", default="3", metavar="N", help="untimed frames first (default 3)")
    p.add_argument("--modes", default=None, metavar="M1,M2",
                   help=f"comma-separated subset of the real-time modes (default: all of "
                        f"{', '.join(REALTIME)})")
    p.add_argument("--variant", action="append", default=[], metavar="NAME=MODE[:G.F=V,...]",
                   help="also time a mode under a name with its own parameters, or a blur "
                        "pass of your own: NAME=glsl:PATH.frag, NAME=py:PATH.py:FUNCTION "
                        "(as compare's --variant; repeatable; --modes then defaults to none)")
    p.add_argument("--json", default=None, metavar="PATH", help="write the results as JSON")
    p.add_argument("--animate", default=None, metavar="FPS",
                   help="time an animation: frame k at the scene time + k / FPS (each after "
                        "the frame before it), not one frame time over and over, so that "
                        "nothing kept from the last frame (tiles, clears) is the same")
    p.add_argument("--pass-timers", default="auto", choices=("auto", "cpu", "gpu"),
                   help="per-pass times: cpu = ctx.finish() around each pass and a CPU clock, "
                        "gpu = GL timer queries (truthful on GPU drivers only); auto = gpu "
                        "where truthful (default)")
    p.add_argument("--speeds", default=None, metavar="S1,S2,...",
                   help="also scale every object's velocity by each factor (a keyed path: "
                        "run that many times as fast about the frame time) and tabulate the "
                        "hybrid reveal's ms against the masked pixel count")
    p.set_defaults(run=run)


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def summary(values) -> dict:
    a = np.asarray(values, dtype=np.float64)
    return {"median": float(np.median(a)), "p10": float(np.percentile(a, 10)),
            "p90": float(np.percentile(a, 90)), "n": int(a.size)}


def time_modes(r: Renderer, modes: list[str], s, frames: int, warmup: int, progress,
               fps: float | None = None, clock: PassClock | None = None,
               variants: dict | None = None) -> dict:
    """Every mode timed round-robin, frame by frame, so that a slow spell of a shared
    machine falls on all of them alike and the ratios compare like with like. Each timed
    frame follows an untimed frame of the same mode, as in a real-time loop: the caches
    then hold what that mode uses, not what the mode before it in the round-robin (or the
    bare-Embree timing) left behind, which favoured whichever mode followed a light one.
    With `fps`, frame k is at the scene time + k / fps and follows the frame before it,
    (k - 1) / fps; otherwise every frame is at the scene time. `clock` times the passes
    (default: the CPU clock with ctx.finish() around each). `modes`: the names timed;
    `variants`: name -> (what the renderer renders: a mode or a user pass registered by
    name, its parameters) for a variant, else the mode itself under s.params."""
    ctx = r.ctx
    plan = {m: (variants or {}).get(m, (m, s.params)) for m in modes}
    clock = clock or PassClock(ctx, "cpu")
    dt = 1.0 / fps if fps else 0.0
    for mode in modes:
        what, params = plan[mode]
        for _ in range(warmup):
            r.render(what, s.time, params, seed=s.seed, read_image=False)
    frame_ms = {m: [] for m in modes}
    frame_cpu = {m: [] for m in modes}
    passes = {m: {} for m in modes}
    passes_cpu = {m: {} for m in modes}
    stats = {m: [] for m in modes}
    for k in range(frames):
        t = s.time + (k + 1) * dt
        for mode in modes:
            what, params = plan[mode]
            r.render(what, t - dt, params, seed=s.seed, read_image=False)
            # Frame time: one finish() at the end only, so passes overlap as they would.
            ctx.finish()
            t0, c0 = time.perf_counter(), time.thread_time()
            r.render(what, t, params, seed=s.seed, read_image=False)
            c1 = time.thread_time()
            ctx.finish()
            frame_ms[mode].append((time.perf_counter() - t0) * 1e3)
            # The main thread's CPU time in the frame (host work, not the waits for GL).
            frame_cpu[mode].append((c1 - c0) * 1e3)
            # Pass times: the next frame, each pass timed by `clock`.
            res = clock.render(r, what, t + dt, params, s.seed)
            for name, ms in res.pass_ms.items():
                passes[mode].setdefault(name, []).append(ms)
            for name, ms in res.pass_cpu_ms.items():
                passes_cpu[mode].setdefault(name, []).append(ms)
            if mode == "hybrid" and res.stats.get("rays"):
                # The ceiling on this frame's rays, timed right after it (same conditions).
                from raytrace.bench import bare_embree_rays_per_s
                from viewer.render.modes.hybrid.reveal import REVEAL_BATCH
                batch = res.host.get(REVEAL_BATCH)
                res.stats["embree_rays_per_s"] = bare_embree_rays_per_s(batch, repeats=1)
                # The static part into the whole static scene: rays of a static own
                # object stop at it (a cheaper query than the reveal's own).
                res.stats["embree_front_rays_per_s"] = bare_embree_rays_per_s(
                    batch, repeats=1, front=True)
            stats[mode].append(res.stats)
        progress(k, frames)
    return {m: mode_summary(frame_ms[m], passes[m], stats[m], frame_cpu[m], passes_cpu[m])
            for m in modes}


def mode_summary(frame_ms: list, passes: dict, stats: list, frame_cpu: list | None = None,
                 passes_cpu: dict | None = None) -> dict:
    out = {"frame_ms": float(np.median(frame_ms)), "frame": summary(frame_ms),
           "passes": {n: float(np.median(v)) for n, v in passes.items()},
           "passes_spread": {n: summary(v) for n, v in passes.items()}}
    if frame_cpu:
        # Host CPU (the main thread's) against the frame: on llvmpipe the draws wait for
        # the rasteriser, so host time adds to the frame; on a GPU it may overlap it.
        out["frame_cpu_ms"] = float(np.median(frame_cpu))
    if passes_cpu:
        out["passes_cpu"] = {n: float(np.median(v)) for n, v in passes_cpu.items()}
    keys = set().union(*[st.keys() for st in stats]) if stats else set()
    out["stats"] = {k: float(np.median([st[k] for st in stats if k in st])) for k in sorted(keys)
                    if all(isinstance(st.get(k, 0), (int, float)) for st in stats)}
    return out


def reveal_summary(results: dict) -> dict | None:
    """Reveal throughput next to bare Embree on exactly the rays the reveal traced, both
    medians over the timed hybrid frames (the ceiling timed right after each frame)."""
    hyb = results.get("hybrid")
    if hyb is None:
        return None
    st = hyb["stats"]
    rays = int(st.get("rays", 0))
    reveal_ms = st.get("reveal_ms", 0.0)
    trace_ms = st.get("reveal_trace_ms", 0.0)
    ceiling = st.get("embree_rays_per_s", 0.0)
    front = st.get("embree_front_rays_per_s", 0.0)
    # Throughput over the whole host side of the reveal (mask read-back, tracing,
    # hit records), and over the tracing alone.
    rps = rays / (reveal_ms / 1e3) if reveal_ms > 0 else 0.0
    trace_rps = rays / (trace_ms / 1e3) if trace_ms > 0 else 0.0
    # What the whole would reach against bare Embree if its tracing took bare Embree's
    # time (the ceiling's calls: one ray per masked pixel) and nothing else were left but
    # the mask read-back, which no CPU reveal can skip (the mask is made on the GPU).
    # Where the reveal traces every query (a moving camera) the whole cannot do better;
    # where it looks hits up or culls rays (a still camera, moving objects' boxes) it can.
    readback_ms = st.get("reveal_readback_ms", 0.0)
    masked = int(st.get("masked_pixels", 0))
    bare_ms = 1e3 * masked / ceiling if ceiling else 0.0
    bound = (rays / ((bare_ms + readback_ms) / 1e3) / ceiling) if bare_ms > 0 else None
    return {"rays": rays, "masked_pixels": masked,
            "reveal_ms": reveal_ms, "trace_ms": trace_ms, "readback_ms": readback_ms,
            "records_ms": st.get("reveal_pack_ms", 0.0), "rays_per_s": rps,
            "trace_rays_per_s": trace_rps, "embree_rays_per_s": ceiling,
            "fraction_of_embree": (rps / ceiling) if ceiling else None,
            "trace_fraction_of_embree": (trace_rps / ceiling) if ceiling else None,
            "fraction_with_bare_tracing": bound,
            "embree_front_rays_per_s": front, "skin_ms": st.get("reveal_skin_ms", 0.0),
            "fraction_of_embree_front": (rps / front) if front else None}


def speed_table(r: Renderer, s, speeds: list[float], frames: int) -> list[dict]:
    rows = []
    # Velocities scale by f; keyed paths run f times as fast about the frame time (the pose
    # at the frame time stays, the motion over the exposure scales as a velocity's would).
    # glTF entries: their placements as any object's, their animations retimed the same way.
    nodes = [*s.scene.objects, *(a.root for a in s.scene.assets)]
    base = [(o.velocity.copy(), o.angular_velocity.copy(), o.keys) for o in nodes]
    try:
        for f in speeds:
            for o, (v, w, keys) in zip(nodes, base):
                o.velocity, o.angular_velocity = v * f, w * f
                if keys is not None:
                    o.keys = keys.retimed(s.time, f)
            for a in s.scene.assets:
                a.retime = (s.time, f)
            ms, masked, rays = [], [], []
            for _ in range(frames):
                # timing=True: finish() around every pass, so reveal_ms is the reveal's own
                # time, not also the wait for the mask passes its read-back would include.
                res = r.render("hybrid", s.time, s.params, seed=s.seed, read_image=False,
                               timing=True)
                ms.append(res.stats.get("reveal_ms", 0.0))
                masked.append(res.stats.get("masked_pixels", 0))
                rays.append(res.stats.get("rays", 0))
            rows.append({"speed": f, "masked_pixels": int(np.median(masked)),
                         "rays": int(np.median(rays)), "reveal_ms": float(np.median(ms))})
    finally:
        for o, (v, w, keys) in zip(nodes, base):
            o.velocity, o.angular_velocity, o.keys = v, w, keys
        for a in s.scene.assets:
            a.retime = None
    return rows


def run(args) -> int:
    s = cliargs.setup(args)
    frames = cliargs.parse_int("--frames", args.frames, 1, limits.MAX_FRAMES)
    warmup = cliargs.parse_int("--warmup", args.warmup, 0, limits.MAX_FRAMES)
    available = [m for m in REALTIME if m in MODES]
    if args.modes is None:
        modes = [] if args.variant else available
    else:
        modes = cliargs.parse_modes("--modes", args.modes, available)
    variants = parse_variants(args.variant, available, modes, "timed")
    groups = {**MODE_GROUPS, **{v.name: v.groups for v in variants}}
    cliargs.check_set_groups(args.set, modes + [v.name for v in variants], groups)
    speeds = None
    if args.speeds:
        if "hybrid" not in available:
            raise cliargs.UserError("--speeds: needs the hybrid mode")
        if args.speeds.count(",") >= MAX_SPEEDS:
            raise cliargs.UserError(f"--speeds: expected at most {MAX_SPEEDS} factors")
        speeds = [cliargs.parse_float("--speeds", x) for x in args.speeds.split(",")]
        if any(abs(v) > MAX_SPEED for v in speeds):
            raise cliargs.UserError(f"--speeds {args.speeds}: expected factors within "
                                    f"+-{MAX_SPEED:g}")
    cliargs.check_shutter_read(args.shutter, modes + (["hybrid"] if speeds else []))
    fps = None
    if args.animate is not None:
        fps = cliargs.parse_float("--animate", args.animate)
        if not MIN_FPS <= fps <= MAX_FPS:
            raise cliargs.UserError(f"--animate {args.animate}: expected frames per second "
                                    f"from {MIN_FPS:g} to {MAX_FPS:g}")
        if abs(s.time) + frames / fps > cliargs.MAX_TIME:
            raise cliargs.UserError(f"--animate {args.animate}: {frames} frames run past "
                                    f"+-{cliargs.MAX_TIME:g} s")
    out = cliargs.check_output_file(args.json, "--json") if args.json is not None else None
    ctx = create_headless()
    method = args.pass_timers
    if method == "auto":
        method = "gpu" if gpu_timers_truthful(ctx) else "cpu"
    r = Renderer(ctx, s.scene, s.size)
    try:
        own = prepare_variants(r, variants, s.params)
        names = modes + [v.name for v in variants]
        results = time_modes(r, names, s, frames, warmup, Progress(f"bench {'/'.join(names)}"),
                             fps, PassClock(ctx, method), own)
        reveal = reveal_summary(results)
        table = speed_table(r, s, speeds, max(3, frames // 3)) if speeds else None
    finally:
        r.release()
    device = f"{device_name(ctx)}; CPU {cpu_name()}"
    report = {"device": device, "size": list(s.size), "scene": s.scene.name, "time": s.time,
              "shutter": s.scene.camera.shutter,
              "animate_fps": fps, "frames": frames, "pass_timing": describe(method),
              "modes": results, "reveal": reveal, "ratios": {}, "seed": s.seed,
              "params": s.params.to_dict()}     # (--params of shot/compare reads these back)
    base = results.get("mcguire", {}).get("frame_ms")
    for m in ("hybrid", "ue4", "guertin"):
        if base and m in results:
            report["ratios"][f"{m}/mcguire"] = results[m]["frame_ms"] / base
    if table is not None:
        report["scaling"] = table
    print(format_report(report))
    if out is not None:
        write_json_atomic(out, report)
    return 0


MEDIANS_NOTE = ("Each figure is the median of its own samples. Frame times come from frames "
                "timed whole (one ctx.finish() at the end); pass times from another frame, "
                "timed pass by pass ({timing}). They are different samples, so a pass's "
                "median can exceed its frame's median (on software GL the waits between "
                "timed passes also keep passes from overlapping).")


def format_report(rep: dict) -> str:
    w, h = rep["size"]
    fps = rep.get("animate_fps")
    run = (f"animated at {fps:g} fps (frame k at t = {rep['time']:g} + k / {fps:g} s)" if fps
           else f"one frame time, t = {rep['time']:g} s, over and over")
    lines = [f"{rep['scene']} {w}x{h} on {rep['device']}",
             f"{rep['frames']} timed frames per mode, {run}; passes timed by "
             f"{rep['pass_timing']}", "",
             "| mode | frame ms (median) | p10-p90 | host CPU ms | passes (median ms) |",
             "| --- | ---: | ---: | ---: | --- |"]
    for m, r in rep["modes"].items():
        passes = ", ".join(f"{n} {v:.1f}" for n, v in r["passes"].items())
        cpu = f"{r['frame_cpu_ms']:.1f}" if "frame_cpu_ms" in r else "-"
        lines.append(f"| {m} | {r['frame_ms']:.1f} | {r['frame']['p10']:.1f}-{r['frame']['p90']:.1f}"
                     f" | {cpu} | {passes} |")
    lines += ["", *textwrap.wrap(MEDIANS_NOTE.format(timing=rep["pass_timing"]), 92)]
    stepped = [(m, r.get("stats", {})) for m, r in rep["modes"].items()
               if r.get("stats", {}).get("steps", 1) > 1
               or "bend_px" in r.get("stats", {})]
    if stepped:
        text = ("sub-frames a frame (motion.steps, or curve steps where screen paths bend "
                "more than motion.curve_px): " + ", ".join(
                    f"{m} {st.get('steps', 1):g}" + (f" (bend {st['bend_px']:.1f} px)"
                                                     if "bend_px" in st else "")
                    for m, st in stepped))
        lines += ["", *textwrap.wrap(text, 92)]
    if rep["ratios"]:
        lines += ["", "frame time ratios: " + ", ".join(f"{k} {v:.2f}x"
                                                        for k, v in rep["ratios"].items())]
    rv = rep.get("reveal")
    if rv:
        lines += ["", *reveal_lines(rv)]
    if rep.get("scaling"):
        lines += ["", "| speed x | masked pixels | rays | reveal ms |", "| ---: | ---: | ---: | ---: |"]
        lines += [f"| {r['speed']:g} | {r['masked_pixels']} | {r['rays']} | {r['reveal_ms']:.2f} |"
                  for r in rep["scaling"]]
    return "\n".join(lines)


def reveal_lines(rv: dict) -> list[str]:
    """The hybrid reveal's figures, one thing per line."""
    def pct(x):
        return f" ({100 * x:.0f}% of bare Embree)" if x else ""
    out = [f"reveal (hybrid, medians): {rv['masked_pixels']} masked pixels, {rv['rays']} rays",
           f"  whole reveal:   {rv['reveal_ms']:.1f} ms = {rv['rays_per_s'] / 1e6:.2f} M rays/s"
           + pct(rv["fraction_of_embree"]),
           f"  tracing alone:  {rv['trace_ms']:.1f} ms = {rv['trace_rays_per_s'] / 1e6:.2f} M rays/s"
           + pct(rv["trace_fraction_of_embree"]),
           f"  bare Embree on the same rays: {rv['embree_rays_per_s'] / 1e6:.2f} M rays/s"]
    if rv.get("embree_front_rays_per_s"):
        out.append(f"  bare Embree stopping at each ray's own object: "
                   f"{rv['embree_front_rays_per_s'] / 1e6:.2f} M rays/s")
    if rv.get("skin_ms"):
        out.append(f"  of which skinned meshes' Embree scenes rebuilt at the frame time: "
                   f"{rv['skin_ms']:.2f} ms")
    if rv.get("fraction_with_bare_tracing"):
        out.append(f"  bound, tracing at bare Embree's speed + the mask read-back "
                   f"({rv['readback_ms']:.2f} ms): {100 * rv['fraction_with_bare_tracing']:.0f}%")
    return out
