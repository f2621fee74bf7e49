"""The G-buffer pass: linear colour shaded per docs/scene-format.md, linear view depth, world
normal, object id and the screen-space displacement over the exposure; for the hybrid's
curved motion also each pixel's path over the exposure (glsl/passes/path.glsl). Under a camera
still over the exposure the static objects' pixels come from a raster kept per view
(static_raster.py) and only the movers are drawn; the targets are the full draw's."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import moderngl

from world.conventions import glsl_defines
from viewer.render.graph.params import param
from viewer.render.graph import depth
from viewer.render.passes import static_raster
from viewer.render.graph.frame import Frame
from viewer.render.graph.gpu_scene import set_uniform
from viewer.render.graph.passes import Pass
from viewer.render.graph.pool import ReadBack, TexSpec

GBUFFER = {
    "color": TexSpec(4, "f4"),
    "depth": TexSpec(1, "f4"),
    "normal": TexSpec(4, "f2"),
    "id": TexSpec(1, "u4"),
    "velocity": TexSpec(2, "f4"),
    "hybrid_front": TexSpec(4, "f4"),    # (D, depth, id): the hybrid mode's packed layer
    # The path's offsets from the frame-time position, two points a target (glsl/passes/path.glsl).
    "hybrid_path": TexSpec(4, "f4"),
    "hybrid_path2": TexSpec(4, "f4"),
}

STATIC_RASTER_READ = ReadBack("static_raster", "once per still view", kept=True)

# Segments a path may have (glsl/passes/path.glsl): 1 is the chord alone (no path targets).
SEGMENT_CHOICES = (1, 2, 4)


PATH_SUFFIXES = ("_path", "_path2")       # two path points a target (glsl/passes/path.glsl)


def path_names(base: str, segments: int) -> tuple[str, ...]:
    """BASE's path targets for `segments` path pieces: BASE_path, and BASE_path2 for 4;
    none for one (the chord alone)."""
    return tuple(base + s for s in PATH_SUFFIXES[:segments // 2])


def path_samplers(names) -> dict[str, str]:
    """The sampler bindings u_path0, u_path1 of path targets `names`."""
    return {f"u_path{j}": name for j, name in enumerate(names)}


def path_targets(segments: int) -> tuple[str, ...]:
    """The G-buffer's path targets for `segments` pieces: K stored points, two a target."""
    return path_names("hybrid", segments)


@dataclass(frozen=True)
class PathConfig:
    """A real-time blur's configuration (viewer/render/graph/registry.py): the path segments
    (GROUP.segments), which decide the path targets and the shader variants."""
    segments: int = 1
    group: ClassVar[str] = ""

    @classmethod
    def of(cls, params) -> "PathConfig":
        return cls(int(params[cls.group].segments))


def segments_param(default: int = 1):
    """The `segments` field of a mode's parameters (the same choices and meaning in every
    real-time mode)."""
    return param(default, unit="segments", choices=SEGMENT_CHOICES, effect="recompile",
                 help="linear pieces of each pixel's screen path over the exposure (its "
                      "points projected at evenly spaced times); the gather splits its "
                      "taps over them; 1 = the chord alone (the paper)")


def path_times(t_open: float, t_close: float, segments: int) -> list[float]:
    """t_k = t_open + k (t_close - t_open) / K, k = 0..K: the path's points' times."""
    return [t_open + (t_close - t_open) * k / segments for k in range(segments + 1)]


# Target sets by GBUFFER_LAYOUT (glsl/passes/gbuffer_outputs.glsl), in attachment order. Each
# mode writes only what it reads (every target costs per fragment: docs/architecture.md).
LAYOUTS = {
    "full": (0, ("color", "depth", "normal", "id", "velocity")),
    "visibility": (1, ("color", "depth", "id")),
    "color": (2, ("color",)),
    "hybrid": (3, ("color", "normal", "hybrid_front")),
    "front": (4, ("color", "hybrid_front")),
    "motion": (5, ("color", "depth", "velocity")),
}


def layout_defines(layout: str) -> dict:
    """GBUFFER_LAYOUT, this layout's code, and every layout's code as
    GBUFFER_LAYOUT_<NAME>, so glsl/passes/gbuffer_outputs.glsl compares by name."""
    return {"GBUFFER_LAYOUT": LAYOUTS[layout][0],
            **{f"GBUFFER_LAYOUT_{name.upper()}": code for name, (code, _) in LAYOUTS.items()}}


class GBufferPass(Pass):
    name = "gbuffer"

    def __init__(self, prefix: str = "", layout: str = "full", static_only: bool = False,
                 segments: int | None = None):
        """`prefix` names a second set of targets (the reference's sub-frames use "sub_");
        `layout` writes fewer targets where the rest would be thrown away; `static_only`
        draws the objects that never move alone; `segments`: the path pieces written (the
        mode's configuration; 1 the chord alone), None for a mode without paths."""
        self.prefix = prefix
        self.static_only = static_only
        self.layout = layout
        self.segments = segments or 1
        self.produces = self.targets(layout, self.segments)
        # The kept static raster's depth and ranks, read once a view where movers are
        # drawn over it (static_raster.py); a static-only pass copies it whole.
        self.reads_back = () if static_only else (STATIC_RASTER_READ,)

    def targets(self, layout: str, segments: int = 1) -> tuple[str, ...]:
        return tuple(self.prefix + n for n in LAYOUTS[layout][1] + path_targets(segments))

    def outputs(self, frame: Frame):
        return {p: GBUFFER[p[len(self.prefix):]]
                for p in self.produces}

    def execute(self, frame: Frame, time: float | None = None):
        t = frame.time if time is None else time
        t_open, t_close = frame.exposure_at(t)
        layout, segments, names = self.layout, self.segments, self.produces
        defines = {**glsl_defines(), **frame.gpu.light_defines(), **layout_defines(layout),
                   "SEGMENTS": segments, "PATH_LOCATION": len(LAYOUTS[layout][1]),
                   "PATH_LOCATION1": len(LAYOUTS[layout][1]) + 1}
        times = path_times(t_open, t_close, segments) if segments > 1 else None
        draw = _Draw(frame, defines, t, t_open, t_close, times)
        order = frame.gpu.front_to_back(frame.camera.eye(t), t)
        if self.static_only:
            order = [o for o in order if not o.moving]
        fbo = frame.pool.framebuffer(names, depth=True)
        raster = self._kept_raster(frame, draw, names, order)
        if raster is None:
            draw.objects(draw.begin(fbo), order)
        elif self.static_only:
            frame.ctx.copy_framebuffer(fbo, raster.exact_fbo)
        else:
            self._compose(frame, draw, fbo, raster, order)
        frame.ctx.disable(moderngl.DEPTH_TEST)

    def _kept_raster(self, frame: Frame, draw: "_Draw", names, order):
        """The static objects' kept raster for this frame's view (static_raster.py), drawn
        now where it is wanted and missing; None where there is none."""
        key = static_raster.still_key(frame, draw.t, draw.exposure_times(), draw.defines)
        if key is None:
            return None
        store = static_raster.rasters(frame)
        raster = store.find(frame, key)
        if raster is None and store.wanted(key, now=self.static_only):
            raster = store.make(frame, key, [GBUFFER[n[len(self.prefix):]] for n in names])
            if raster is not None:
                statics = [o for o in order if not o.moving]
                with_rank = _Draw(frame, {**draw.defines, "RANK_LOCATION": len(names)},
                                  draw.t, draw.t_open, draw.t_close, draw.times)
                with_rank.objects(with_rank.begin(raster.draw_fbo), statics, ranks=True)
                raster.drawn(key)
        return raster

    @staticmethod
    def _compose(frame: Frame, draw: "_Draw", fbo, raster, order):
        """The kept raster copied in, the movers drawn over it (static_raster.py: the
        statics a mover comes before at one float farther, their depth given back
        before the next mover after them)."""
        ctx = frame.ctx
        plan = static_raster.draw_plan(order)
        movers = [o for o in plan if not isinstance(o, list)]
        boxes = static_raster.rasters(frame).movers_boxes(frame, movers, draw.t)
        first = next((k for k, slot in enumerate(plan) if not isinstance(slot, list)), 0)
        reach = static_raster.union(boxes)
        if reach is None or not any(isinstance(slot, list) for slot in plan[first:]):
            # Nothing reaches the image, or every static comes before every mover.
            ctx.copy_framebuffer(fbo, raster.exact_fbo)
            if reach is not None:
                draw.objects(draw.program(fbo), movers)
            return
        raster.prepare(frame.pool, len(order) - len(movers))
        ctx.copy_framebuffer(fbo, raster.far_fbo)
        depth_only = frame.pool.framebuffer((), depth=True)
        prog = draw.program(fbo)
        run, k = None, 0
        for slot in plan:
            if isinstance(slot, list):
                run = slot
                continue
            later = static_raster.union(boxes[k:])    # where this mover or a later draws
            b = run and later and raster.box(*run, later)
            if b:
                raster.restore_depth(frame, depth_only, *run, b)
                fbo.use()
            run, k = None, k + 1
            draw.objects(prog, [slot])


class _Draw:
    """One G-buffer draw's shader variant and times: the background, then objects."""

    def __init__(self, frame: Frame, defines: dict, t: float, t_open: float, t_close: float,
                 times: list[float] | None):
        self.frame, self.defines = frame, defines
        self.t, self.t_open, self.t_close, self.times = t, t_open, t_close, times

    def exposure_times(self) -> list[float]:
        """Every time other than t that the draw looks at the camera."""
        return [self.t_open, self.t_close, *(self.times or ())]

    def begin(self, fbo: moderngl.Framebuffer) -> moderngl.Program:
        """Clear `fbo`, fill it with the background (without depth test: every target
        where nothing is hit); returns program()."""
        frame, ctx = self.frame, self.frame.ctx
        fbo.use()
        fbo.viewport = (0, 0) + fbo.size
        fbo.clear(depth=depth.clear_value(ctx))
        bg = frame.programs.get("graph/fullscreen.vert", "passes/background.frag", self.defines)
        set_uniform(bg, "u_background", frame.scene.background)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE | moderngl.BLEND)
        frame.programs.empty_vao(bg).render(moderngl.TRIANGLES, vertices=3)
        return self.program(fbo)

    def program(self, fbo: moderngl.Framebuffer) -> moderngl.Program:
        """The G-buffer program with the camera and lights bound, `fbo` bound, the depth
        test on."""
        frame, ctx = self.frame, self.frame.ctx
        fbo.use()
        fbo.viewport = (0, 0) + fbo.size
        ctx.disable(moderngl.CULL_FACE | moderngl.BLEND)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.depth_func = depth.nearer(ctx)
        prog = frame.programs.get("passes/gbuffer.vert", "passes/gbuffer.frag", self.defines)
        frame.gpu.bind_camera(prog, frame.camera, self.t, frame.size)
        frame.gpu.bind_lights(prog)
        return prog

    def objects(self, prog: moderngl.Program, objects, ranks: bool = False):
        """Draw `objects` in order; `ranks`: each writes 1 + its place as its rank."""
        frame, cam, gpu, t = self.frame, self.frame.camera, self.frame.gpu, self.t
        turn = cam.view(t).copy()
        turn[:3, 3] = 0.0                 # V(t) = turn T(-eye(t)): V M = turn T(-eye) M
        for k, obj in enumerate(objects):
            model_eye = gpu.bind_object(prog, obj, cam, t, self.t_open, self.t_close,
                                        frame.object_matrices)[0]
            if self.times is not None:
                set_uniform(prog, "u_modelview_path",
                            gpu.path_matrices(obj, cam, self.times, frame.object_matrices))
            set_uniform(prog, "u_modelview", turn @ model_eye)
            if ranks:
                set_uniform(prog, "u_rank", k + 1)
            gpu.pose(obj, t, self.t_open, self.t_close, self.times)
            vao = gpu.vao(prog, obj)
            if obj.parts is None:
                vao.render(moderngl.TRIANGLES)
                continue
            for first, count, material in obj.parts:     # (each part its own material)
                gpu.bind_material(prog, obj, material)
                vao.render(moderngl.TRIANGLES, vertices=3 * count, first=3 * first)
