"""The API's renderer: it owns its GL context (headless EGL unless given one), renders any
scene at any size, a mode or a registered user pass at a time, to arrays; a context
manager, reusable across scenes, released with release() or at the end of `with`.

    with hm.Renderer(size=(320, 180)) as r:
        r.register("mine", hm.glsl_pass("docs/examples/naive_gather.frag"))
        ref = r.reference(scene)
        img = r.render(scene, "mine")

Inside, one viewer.render.renderer.Renderer (the render core `hmblur` runs) is kept for the
scene rendered last; another scene replaces it (its GPU buffers and ray tracer released)."""
from __future__ import annotations

from os import PathLike
from typing import Callable, Mapping

import moderngl

from world import jit_notice
from world.scene import Scene
from viewer.eval.comparison import Comparison, Variant, check_variant, compare_frame
from viewer.glcontext import create_headless, device_name
from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODES
from viewer.render.modes.reference import REGIONS
from viewer.render.modes.user import UserPass
from viewer.render.renderer import Renderer as CoreRenderer
from .methods import as_method
from .results import Reference, Render
from .scenes import load_scene

__all__ = ["Renderer", "param_set"]

Params = ParamSet | Mapping[str, object] | None


def param_set(params: Params = None) -> ParamSet:
    """A ParamSet from None (the defaults), a ParamSet (copied) or {"group.field": value}
    (`hmblur params` lists them); a wrong key or value raises UserError."""
    p = ParamSet()
    if isinstance(params, ParamSet):
        p.update(params.to_dict(), source="params")
    elif params is not None:
        for key, value in params.items():
            p.set(key, value, label="params")
    return p


class Renderer:
    """Renders scenes to arrays: `render`, `reference`, `compare_frame`; user passes are
    registered by name with `register` and render like modes."""

    def __init__(self, size: tuple[int, int] | None = None,
                 context: moderngl.Context | None = None):
        """`size`: (W, H) of every render (None: each scene's [render] size); `context`: a
        moderngl context of the caller's (kept, not released), else a headless EGL one."""
        jit_notice.install()          # (a cold kernel cache: one line before the wait)
        self._owns = context is None
        self.context = create_headless() if context is None else context
        self.size = None if size is None else (int(size[0]), int(size[1]))
        self.methods: dict[str, UserPass] = {}
        self._core: CoreRenderer | None = None
        self._scene: Scene | None = None
        self._source: str | None = None      # what the kept scene was loaded from, if named

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()

    @property
    def device(self) -> str:
        """The GL renderer and version, as sidecars name them."""
        return device_name(self.context)

    @property
    def modes(self) -> list[str]:
        """What render() takes: the built-in modes, then the registered user passes."""
        return [*MODES, *self.methods]

    def register(self, name: str, method: UserPass | str | Callable) -> UserPass:
        """A user pass (glsl_pass, py_pass, a `glsl:PATH` / `py:PATH:FUNCTION` text or a
        callable) to render as `name`; a shader is compiled now."""
        m = as_method(method)
        check_variant(Variant(name, m.kind, {}, m), f"register({name!r})", values=False)
        self.methods[name] = m
        if self._core is not None:
            self._core.add_method(name, m)
        return m

    def core(self, scene: Scene | str | PathLike, size: tuple[int, int] | None = None
             ) -> CoreRenderer:
        """The render core for `scene` at `size` (else the renderer's, else the scene's):
        kept while the same scene (object, or file or name) is rendered, made anew for
        another."""
        source = None
        if not isinstance(scene, Scene):
            source = str(scene)
            scene = self._scene if source == self._source else load_scene(source)
        want = size or self.size or (scene.render.width, scene.render.height)
        want = (int(want[0]), int(want[1]))
        if self._core is None or self._scene is not scene:
            self._release_core()
            self.context.__enter__()          # (current again, if another one was made)
            self._core, self._scene = CoreRenderer(self.context, scene, want), scene
            self._source = source
            for name, m in self.methods.items():
                self._core.add_method(name, m)
        elif self._core.size != want:
            self._core.resize(want)
        return self._core

    def render(self, scene: Scene | str | PathLike, mode: str, time: float | None = None,
               params: Params = None, seed: int = 0, buffers: bool = False,
               size: tuple[int, int] | None = None) -> Render:
        """`mode` (or a registered user pass) at `time` (None: the scene's [render] time)
        with `params` and `seed`; with `buffers`, every texture the frame made."""
        r = self.core(scene, size)
        t = self._scene.render.time if time is None else float(time)
        res = r.render(mode, t, param_set(params), seed=seed)
        return Render(mode, res.image, t, seed, r.buffers() if buffers else {},
                      res.stats, res.pass_ms)

    def reference(self, scene: Scene | str | PathLike, time: float | None = None,
                  params: Params = None, seed: int = 0, samples: int | None = None,
                  size: tuple[int, int] | None = None) -> Reference:
        """The ground truth at `time` (reference.samples sub-frames, or `samples`) with its
        blur regions from its own visibility."""
        r = self.core(scene, size)
        t = self._scene.render.time if time is None else float(time)
        p = param_set(params)
        if samples is not None:
            p.set("reference.samples", int(samples), label="samples")
        res = r.render("reference", t, p, seed=seed, record_visibility=True)
        return Reference("reference", res.image, t, seed, {}, res.stats, res.pass_ms,
                         regions=res.host[REGIONS])

    def compare_frame(self, scene: Scene | str | PathLike, variants: list[Variant],
                      time: float | None = None, params: Params = None, seed: int = 0,
                      size: tuple[int, int] | None = None, progress=None,
                      log=None) -> Comparison:
        """`hmblur compare`'s frame (viewer/eval/comparison.py): the reference once, then
        every variant, each scored per region against it."""
        r = self.core(scene, size)
        t = self._scene.render.time if time is None else float(time)
        return compare_frame(r, t, param_set(params), variants, seed, progress=progress,
                             log=log)

    def _release_core(self):
        if self._core is not None:
            self._core.release()
        self._core = self._scene = self._source = None

    def release(self) -> None:
        """Free the GL resources (and the context, if the renderer made it)."""
        self._release_core()
        if self._owns and self.context is not None:
            self.context.release()
        self.context = None
