"""Pass and pipeline: a pass names its inputs and its outputs (with formats), the
host-side resources it reads and makes (viewer/render/graph/host.py) and the textures it reads
back to the host (ResourcePool.read_back), takes its parameters from the frame, and
executes; a pipeline is the passes of one mode's configuration (viewer/render/graph/registry.py),
in order, checked when built so every input, texture or host resource, is produced
earlier, and checked as it runs so each pass touches only what it declares."""
from __future__ import annotations

import moderngl

from world.conventions import glsl_defines
from .frame import Frame, PassTimer
from viewer.render.graph.gpu_scene import set_uniform
from .host import HostResource
from .pool import ReadBack, TexSpec


class Pass:
    name: str = "pass"
    inputs: tuple[str, ...] = ()
    produces: tuple[str, ...] = ()        # output names; `outputs` gives their formats
    host_inputs: tuple[HostResource, ...] = ()
    host_outputs: tuple[HostResource, ...] = ()
    runs_on: str = "gpu"                  # "cpu": host work (read-backs, rays), no draw
    reads_back: tuple[ReadBack, ...] = ()  # textures read to the host (pool.read_back)

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
        """The defines every draw of this pass compiles with (from the frame's settings);
        a draw's own variant comes as draw(defines=...)."""
        return {}

    def program(self, frame: Frame, vertex: str = "graph/fullscreen.vert", defines: dict | None = None,
                fragment: str | None = None) -> moderngl.Program:
        return frame.programs.get(vertex, fragment or self.fragment,
                                  {**glsl_defines(), **self.defines(frame), **(defines or {})})

    def draw(self, frame: Frame, outputs: tuple[str, ...], textures: dict[str, str],
             uniforms: dict | None = None, blend: bool | tuple = False, tiles=None,
             clear: bool = True, defines: dict | None = None, fragment: str | None = None):
        """Bind pool textures to sampler uniforms, set uniforms, draw into `outputs`.

        blend: True adds the output to the target (ONE, ONE); a tuple gives the blend
        factors (moderngl's blend_func: 2 or 4 of them).

        defines, fragment: this draw's shader variant (added to defines(frame); instead of
        the pass's fragment): program() with the same arguments gives the program drawn
        (the cache's), for a caller that sets uniforms of its own first.

        tiles: a TileList (viewer/render/passes/tile_runs.py) to draw only its tiles, every
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
        prog = self.program(frame, "graph/fullscreen.vert" if tiles is None else tiles.vertex_shader,
                            defines, fragment)
        for unit, (uniform, tex_name) in enumerate(textures.items()):
            frame.pool.get(tex_name).use(unit)
            set_uniform(prog, uniform, unit)
        set_uniform(prog, "u_seed", int(frame.seed) & 0xFFFFFFFF)   # glsl/graph/noise.glsl
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
            ctx.blend_func = blend if isinstance(blend, tuple) else (moderngl.ONE, moderngl.ONE)
        if tiles is None:
            frame.programs.empty_vao(prog).render(moderngl.TRIANGLES, vertices=3)
        else:
            tiles.render(prog)
            if clear:
                frame.pool.mark_tiles(tuple(outputs), tiles)
        if blend:
            ctx.disable(moderngl.BLEND)


class Pipeline:
    def __init__(self, mode: str, passes: list[Pass], output: str, produced=(),
                 config=None):
        """`config`: the mode's configuration this pipeline was built for (registry.py)."""
        self.mode, self.passes, self.output, self.config = mode, passes, output, config
        have = set(produced)
        host: dict[str, Pass] = {}          # host resource name -> its producer
        for p in passes:
            both = [n for n in p.inputs if n in p.produces]
            if both:
                raise ValueError(f"pipeline {mode}: pass {p.name} both reads and writes "
                                 f"{both} (a texture drawn into while it is sampled is "
                                 "undefined in GL)")
            missing = [n for n in p.inputs if n not in have]
            if missing:
                raise ValueError(f"pipeline {mode}: pass {p.name} needs {missing}, not produced before it")
            missing = [r.name for r in p.reads_back
                       if not r.kept and r.name not in (*p.inputs, *p.produces)]
            if missing:
                raise ValueError(f"pipeline {mode}: pass {p.name} reads back {missing}, "
                                 f"not among its inputs or outputs")
            missing = [r.name for r in p.host_inputs if host_producer(host, r) is None]
            if missing:
                raise ValueError(f"pipeline {mode}: pass {p.name} needs host resources "
                                 f"{missing}, not produced before it")
            have |= set(p.produces)
            for r in p.host_outputs:
                if r.name in host:
                    raise ValueError(f"pipeline {mode}: host resource {r.name} is made by "
                                     f"both {host[r.name].name} and {p.name}")
                host[r.name] = p
        if output not in have:
            raise ValueError(f"pipeline {mode}: output {output} is not produced")

    def run(self, frame: Frame, measure=PassTimer, start: int = 0, stop: int | None = None):
        """The one executor: allocate each pass's outputs, then run it inside
        `measure(frame, name)` (a context manager that times it: PassTimer by default,
        timing.PassClock.measure for GL timer queries), passes [start, stop) only. The
        frame's parameters must make the configuration the pipeline was built for."""
        if self.config is not None and type(self.config).of(frame.params) != self.config:
            raise RuntimeError(f"pipeline {self.mode} built for {self.config} run with the "
                               f"parameters of {type(self.config).of(frame.params)}")
        for p in self.passes[start:stop]:
            p.allocate(frame)
            with measure(frame, p.name), frame.host.opened_to(p), frame.pool.opened_to(p):
                p.execute(frame)

    def textures(self) -> list[str]:
        """Every texture the passes make, in the order made: this pipeline's names (the
        pool may hold other pipelines' textures too; nothing reads those)."""
        return list(dict.fromkeys(n for p in self.passes for n in p.produces))

    def host_resources(self) -> list[tuple[HostResource, Pass, list[Pass]]]:
        """(resource, producer, readers) of every host resource, in the order made."""
        return [(r, p, [q for q in self.passes if r in q.host_inputs])
                for p in self.passes for r in p.host_outputs]

    def unread(self) -> list[str]:
        """Textures made that no later pass reads and that are not the output: a pass's
        own intermediates (a reduction's first stage) and buffers kept for `--buffers`."""
        later: set[str] = set()
        out = []
        for p in reversed(self.passes):
            out += [n for n in reversed(p.produces) if n not in later and n != self.output]
            later |= set(p.inputs)
        return out[::-1]

    def read_backs(self) -> list[tuple[ReadBack, Pass]]:
        """(read-back, pass) of every GPU-to-host read the passes declare, in order."""
        return [(r, p) for p in self.passes for r in p.reads_back]

    def describe(self) -> str:
        """The whole graph: the configuration it was built for and a count of its passes
        and read-backs, each pass (GPU or CPU) with what it reads and makes, textures and
        host resources (marked `host:`), the textures no later pass reads, then every
        read-back with its pass, then every
        host resource with its type, its producer and its readers ("the caller": read
        after the frame, e.g. by compare)."""
        cpu = sum(p.runs_on == "cpu" for p in self.passes)
        backs = self.read_backs()
        every = sum(not r.when for r, _ in backs)
        lines = [f"mode {self.mode} -> {self.output}"]
        if self.config is not None:
            lines.append(f"config {self.config}")
        n = len(self.passes)
        lines.append(f"{n} pass{'es' if n != 1 else ''} ({n - cpu} gpu, {cpu} cpu); "
                     f"read-backs: {every} every frame, {len(backs) - every} at times")
        for p in self.passes:
            ins = [*p.inputs, *(f"host:{r.name}" for r in p.host_inputs)]
            outs = [*p.produces, *(f"host:{r.name}" for r in p.host_outputs)]
            kind = " (cpu)" if p.runs_on == "cpu" else ""
            lines.append(f"  {p.name}{kind}: {', '.join(ins) or '-'} -> {', '.join(outs) or '-'}")
        unread = self.unread()
        if unread:
            lines.append(f"  (not read by a later pass: {', '.join(unread)})")
        if backs:
            lines.append("read-backs:")
            for r, p in backs:
                lines.append(f"  {r.name}{' (kept)' if r.kept else ''}: {p.name}"
                             + (f" ({r.when})" if r.when else ""))
        rows = self.host_resources()
        if rows:
            lines.append("host resources:")
            for r, p, readers in rows:
                lines.append(f"  {r.name} ({r.type_name()}): {p.name} -> "
                             f"{', '.join(q.name for q in readers) or 'the caller'}")
        return "\n".join(lines)


def host_producer(made: dict[str, Pass], res: HostResource) -> Pass | None:
    """The pass of `made` (name -> producer) that makes `res`, or None."""
    p = made.get(res.name)
    return p if p is not None and res in p.host_outputs else None
