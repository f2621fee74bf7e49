"""Pass and pipeline: a pass names its inputs and its outputs (with formats), takes its
parameters from the frame, and executes; a pipeline is the passes of one mode, in order,
checked when built so every input is produced earlier."""
from __future__ import annotations

import moderngl

from world.conventions import glsl_defines
from .frame import Frame, PassTimer
from .gpu_scene import set_uniform
from .pool import TexSpec


class Pass:
    name: str = "pass"
    inputs: tuple[str, ...] = ()
    produces: tuple[str, ...] = ()        # output names; `outputs` gives their formats

    def outputs(self, frame: Frame) -> dict[str, TexSpec]:
        return {}

    def execute(self, frame: Frame) -> None:
        raise NotImplementedError

    def allocate(self, frame: Frame):
        return {n: frame.pool.texture(n, spec) for n, spec in self.outputs(frame).items()}


class FullscreenPass(Pass):
    """A fragment pass over a full-screen triangle (no vertex buffer)."""
    fragment: str = ""

    def defines(self, frame: Frame) -> dict:
        return {}

    def program(self, frame: Frame, vertex: str = "fullscreen.vert") -> moderngl.Program:
        return frame.programs.get(vertex, self.fragment,
                                  {**glsl_defines(), **self.defines(frame)})

    def draw(self, frame: Frame, outputs: tuple[str, ...], textures: dict[str, str],
             uniforms: dict | None = None, blend: bool = False, tiles=None,
             clear: bool = True):
        """Bind pool textures to sampler uniforms, set uniforms, draw into `outputs`.

        tiles: a TileList (viewer/render/tile_lists.py) to draw only its tiles, every
        texel of which the pass writes; the targets are zero elsewhere (what they held
        outside the tiles is cleared first: TileList.clear_outside) unless `clear` is
        False (the caller filled them). None: the full-screen triangle."""
        ctx = frame.ctx
        if tiles is not None and not tiles.count:
            # No tiles: nothing to bind or draw (a program, its textures and uniforms cost
            # ~0.1 ms of host time); only last frame's tiles go where the pass clears.
            if clear:
                tiles.clear_outside(frame, tuple(outputs))
                frame.pool.mark_tiles(tuple(outputs), tiles)
            return
        prog = self.program(frame, "fullscreen.vert" if tiles is None else tiles.vertex_shader)
        for unit, (uniform, tex_name) in enumerate(textures.items()):
            frame.pool.get(tex_name).use(unit)
            set_uniform(prog, uniform, unit)
        set_uniform(prog, "u_seed", int(frame.seed) & 0xFFFFFFFF)   # glsl/noise.glsl
        set_uniform(prog, "u_viewport", tuple(float(x) for x in frame.size))
        for k, v in (uniforms or {}).items():
            set_uniform(prog, k, v)
        fbo = frame.pool.framebuffer(tuple(outputs))
        fbo.use()
        fbo.viewport = (0, 0) + fbo.size
        ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        if tiles is not None and clear:
            tiles.clear_outside(frame, tuple(outputs))
        frame.pool.mark_written(outputs, None if tiles is None else tiles.box)
        if blend:
            ctx.enable(moderngl.BLEND)
            ctx.blend_func = moderngl.ONE, moderngl.ONE
        if tiles is None:
            frame.programs.empty_vao(prog).render(moderngl.TRIANGLES, vertices=3)
        else:
            tiles.render(prog)
            if clear:
                frame.pool.mark_tiles(tuple(outputs), tiles)
        if blend:
            ctx.disable(moderngl.BLEND)


class Pipeline:
    def __init__(self, mode: str, passes: list[Pass], output: str, produced=()):
        self.mode, self.passes, self.output = mode, passes, output
        have = set(produced)
        for p in passes:
            missing = [n for n in p.inputs if n not in have]
            if missing:
                raise ValueError(f"pipeline {mode}: pass {p.name} needs {missing}, not produced before it")
            have |= set(p.produces)
        if output not in have:
            raise ValueError(f"pipeline {mode}: output {output} is not produced")

    def run(self, frame: Frame, measure=PassTimer, start: int = 0, stop: int | None = None):
        """The one executor: allocate each pass's outputs, then run it inside
        `measure(frame, name)` (a context manager that times it: PassTimer by default,
        timing.PassClock.measure for GL timer queries), passes [start, stop) only."""
        for p in self.passes[start:stop]:
            p.allocate(frame)
            with measure(frame, p.name):
                p.execute(frame)

    def describe(self) -> str:
        lines = [f"mode {self.mode} -> {self.output}"]
        for p in self.passes:
            lines.append(f"  {p.name}: {', '.join(p.inputs) or '-'} -> {', '.join(p.produces)}")
        return "\n".join(lines)
