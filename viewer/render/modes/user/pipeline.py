"""A user's blur pass in the renderer's pipeline:

  gbuffer (layout full: colour, depth, normal, id, displacement)
          -> user_tilemax_x -> user_tilemax -> user_neighbormax (viewer/render/passes/tiles.py)
          -> the user's pass (GLSL: a full-screen fragment pass; Python: a host pass that
             reads the inputs back, calls the function and uploads its image) -> `user`

The tile size is the shared blur limit k (blur.max_radius in pixels), as McGuire's; the
renderer runs sub-exposure steps (motion.steps) around this pipeline as around any blur's."""
from __future__ import annotations

import numpy as np

from world.conventions import glsl_defines
from world.errors import UserError
from viewer.render.graph.frame import Frame
from viewer.render.graph.passes import FullscreenPass, Pass, Pipeline
from viewer.render.graph.pool import ReadBack, TexSpec
from viewer.render.graph.registry import NoConfig
from viewer.render.graph.shaders import ProgramCache, ShaderError
from viewer.render.passes.blur_common import max_radius_px
from viewer.render.passes.gbuffer import GBufferPass
from viewer.render.passes.tiles import tile_passes
from .inputs import INPUT_TEXTURES, OUTPUT, SAMPLERS, TEXTURES, TILE_PREFIX, BlurInputs
from .method import UserPass, user_code_error, user_files

VERTEX = "graph/fullscreen.vert"


def describe(name: str, method: UserPass) -> str:
    """How a message names the method: `method NAME (SPEC)`."""
    return f"method {name} ({method.spec})"


def compile_glsl(programs: ProgramCache, method: UserPass, name: str):
    """The user's fragment shader compiled (cached by the renderer's ProgramCache); a
    compile or link error is one UserError line: the file, the line, the driver's words."""
    try:
        return programs.get(VERTEX, str(method.path), glsl_defines(),
                            fragment_text=method.text)
    except ShaderError as exc:
        lines = str(exc).splitlines()[1:]
        errors = [s for s in lines if "error" in s.lower()] or lines or [str(exc)]
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        first = errors[0]
        if not first.startswith(str(method.path)):
            first = f"{method.path}: {first}"
        raise UserError(f"{describe(name, method)}: {first}{more}") from None


def uniforms(frame: Frame) -> dict:
    """The uniforms every user pass reads beside its samplers (docs/api.md)."""
    return {"u_tile": max_radius_px(frame), "u_exposure": float(frame.shutter),
            "u_time": float(frame.time), "u_size": tuple(float(x) for x in frame.size)}


class GlslBlur(FullscreenPass):
    """The user's fragment shader over the full screen, the inputs bound to its samplers."""

    def __init__(self, name: str, method: UserPass):
        self.variant, self.method = name, method
        self.name = method.label
        self.fragment = str(method.path)
        self.inputs = INPUT_TEXTURES
        self.produces = (OUTPUT,)

    def program(self, frame: Frame, vertex: str = VERTEX, defines: dict | None = None,
                fragment: str | None = None):
        return compile_glsl(frame.programs, self.method, self.variant)

    def outputs(self, frame: Frame):
        return {OUTPUT: TexSpec(4, "f4")}

    def execute(self, frame: Frame):
        self.draw(frame, (OUTPUT,), SAMPLERS, uniforms(frame))


class PythonBlur(Pass):
    """The user's function on the inputs read back to numpy; its image uploaded."""
    runs_on = "cpu"

    def __init__(self, name: str, method: UserPass):
        self.variant, self.method = name, method
        self.name = method.label
        self.inputs = INPUT_TEXTURES
        self.produces = (OUTPUT,)
        self.reads_back = tuple(ReadBack(n) for n in INPUT_TEXTURES)

    def outputs(self, frame: Frame):
        return {OUTPUT: TexSpec(4, "f4")}

    def inputs_of(self, frame: Frame) -> BlurInputs:
        a = {user: frame.read(pool) for pool, user in TEXTURES.items()}
        return BlurInputs(
            color=np.ascontiguousarray(a["color"][..., :3]), depth=a["depth"],
            velocity=a["velocity"], id=a["id"],
            normal=a["normal"][..., :3].astype(np.float32), tilemax=a["tilemax"],
            neighbormax=a["neighbormax"], tile=max_radius_px(frame),
            exposure=float(frame.shutter), time=float(frame.time), seed=int(frame.seed))

    def execute(self, frame: Frame):
        inputs = self.inputs_of(frame)
        fn = self.method.callable()
        try:
            out = fn(inputs)
        except Exception as exc:
            raise user_code_error(describe(self.variant, self.method), exc,
                                  user_files(self.method)) from exc
        image = checked_image(out, inputs.size, describe(self.variant, self.method))
        w, h = inputs.size
        frame.write(OUTPUT, np.concatenate([image, np.ones((h, w, 1), np.float32)], axis=2))


def checked_image(out, size: tuple[int, int], where: str) -> np.ndarray:
    """A Python method's result as (H, W, 3) float32, or one UserError line saying what
    it returned and what was expected."""
    w, h = size
    want = f"expected a numpy array of shape ({h}, {w}, 3), dtype float (linear RGB)"
    if not isinstance(out, np.ndarray):
        raise UserError(f"{where}: returned {type(out).__name__}; {want}")
    if out.shape != (h, w, 3) or out.dtype.kind != "f":
        raise UserError(f"{where}: returned an array of shape {out.shape}, dtype "
                        f"{out.dtype}; {want}")
    image = out.astype(np.float32)
    bad = int(np.count_nonzero(~np.isfinite(image)))
    if bad:
        raise UserError(f"{where}: returned {bad} values that are not finite (NaN or inf, "
                        "as float32); expected finite linear RGB")
    return image


def user_pipeline(name: str, method: UserPass) -> Pipeline:
    """The pipeline of the method registered as `name` (viewer/render/renderer.py)."""
    blur = GlslBlur(name, method) if method.kind == "glsl" else PythonBlur(name, method)
    return Pipeline(name, [GBufferPass(layout="full"), *tile_passes("velocity", TILE_PREFIX),
                           blur], output=OUTPUT, config=NoConfig())
