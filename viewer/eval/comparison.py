"""One frame compared: the reference (with its visibility, hence the blur regions) rendered
once, then each variant (a named mode with its own parameters), with PSNR / SSIM / FLIP per
region against the reference. `hmblur compare` and every cell of `hmblur sweep` run this
one function, so that their numbers are the same by construction."""
from __future__ import annotations

import re
import time
from dataclasses import dataclass, field

import numpy as np

from world import limits
from world.errors import UserError
from .metrics import metric_maps, region_metrics
from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODE_GROUPS
from viewer.render.modes.reference import REGIONS
from viewer.render.modes.user import USER_GROUPS, UserPass, parse_method
from viewer.render.modes.user.method import KINDS
from viewer.render.renderer import Renderer, RenderResult

REALTIME = ("off", "mcguire", "ue4", "guertin", "hybrid")
# Names an image or table of compare's folder already uses: no variant may take them.
RESERVED = ("reference", "regions", "strip", "flip", "metrics")
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]*")
MAX_NAME = 100                 # a variant's name is a file name (NAME.png, NAME.json)


@dataclass
class Variant:
    """A real-time mode or a user's blur pass under a name, with parameter assignments on
    top of the common ones ("group.field" -> value as text or a value). For a user pass,
    `mode` is its kind ("glsl", "py") and `method` the pass (viewer/render/modes/user/)."""
    name: str
    mode: str
    sets: dict = field(default_factory=dict)
    method: UserPass | None = None

    @property
    def groups(self) -> tuple[str, ...]:
        """The parameter groups the variant reads."""
        return USER_GROUPS if self.method is not None else MODE_GROUPS.get(self.mode, ())

    @property
    def runs_as(self) -> str:
        """What the renderer renders: the mode, or the name the user pass is registered as."""
        return self.name if self.method is not None else self.mode

    def describe(self) -> str:
        """`mode` or the user pass's spec, and the assignments (tables' notes)."""
        what = self.method.spec if self.method is not None else self.mode
        return what + "".join(f", {k}={val}" for k, val in self.sets.items())

    def params(self, base: ParamSet, label: str) -> ParamSet:
        """`base` with this variant's assignments applied (a copy; `base` is untouched)."""
        p = ParamSet()
        p.update(base.to_dict(), source=label)
        for key, value in self.sets.items():
            p.set(key, value, label=label)
        return p


def check_variant(v: Variant, label: str, available=REALTIME, values: bool = True):
    """One line naming `label` for a bad name, mode, a group the mode does not read or
    (with `values`) a value of the wrong type or out of range."""
    if not NAME.fullmatch(v.name) or len(v.name) > MAX_NAME:
        shown = repr(v.name) if len(v.name) <= MAX_NAME else f"{v.name[:20]!r}... ({len(v.name)} characters)"
        raise UserError(f"{label}: variant name {shown}: expected letters, digits and "
                        f"_ . + - (a file name), starting with a letter or digit, at most "
                        f"{MAX_NAME} characters")
    if v.name in RESERVED:
        raise UserError(f"{label}: variant name {v.name!r} is taken by compare's own "
                        f"outputs ({', '.join(RESERVED)})")
    if v.method is not None and v.name in MODE_GROUPS:
        raise UserError(f"{label}: variant name {v.name!r} is a built-in mode's; a user "
                        "pass takes a name of its own")
    if v.method is None and v.mode not in available:
        raise UserError(f"{label}: mode {v.mode!r} is not one of {', '.join(available)} "
                        "(or a user pass: glsl:PATH, py:PATH:FUNCTION)")
    for key in v.sets:
        group = key.partition(".")[0]
        if group not in v.groups:
            readers = [m for m, gs in MODE_GROUPS.items() if group in gs]
            what = f"user pass {v.mode}" if v.method is not None else f"mode {v.mode}"
            raise UserError(f"{label}: {key}: {what} does not use the {group} "
                            f"parameters (used by {', '.join(readers) or 'no mode'})")
    if values:                           # every value's type and range, before any render
        v.params(ParamSet(), label)


def check_capacity(n_variants: int, size, where: str):
    """A comparison of `n_variants` at `size` holds every variant's image and the
    reference's at once: both counts within world/limits.py, checked before any render."""
    if n_variants > limits.MAX_VARIANTS:
        raise UserError(f"{where}: {n_variants} variants, more than the "
                        f"{limits.MAX_VARIANTS} a comparison may show")
    w, h = size
    pixels = (n_variants + 1) * w * h
    if pixels > limits.MAX_COMPARE_PIXELS:
        raise UserError(f"{where}: {n_variants} variants and the reference at {w}x{h} are "
                        f"{pixels:,} pixels, more than the {limits.MAX_COMPARE_PIXELS:,} a "
                        "comparison may hold: show fewer variants or give a smaller size")


def parse_variant(text: str, available=REALTIME) -> Variant:
    """`NAME=MODE[:group.field=value,...]`, `NAME=glsl:PATH` or `NAME=py:PATH:FUNCTION`
    (the --variant flag; a user pass's file is read and checked now)."""
    label = f"--variant {text}"
    name, eq, rest = text.partition("=")
    mode, _, sets_text = rest.partition(":")
    if not eq or not name.strip() or not mode.strip():
        raise UserError(f"{label}: expected NAME=MODE[:group.field=value,...], e.g. "
                        "fast=hybrid:hybrid.curve_steps=1, or NAME=glsl:PATH, "
                        "NAME=py:PATH:FUNCTION (a user pass)")
    if mode.strip() in KINDS:
        v = Variant(name.strip(), mode.strip(), {}, parse_method(rest.strip(), label=label))
        check_variant(v, label, available)
        return v
    sets = {}
    for item in filter(None, (s.strip() for s in sets_text.split(","))):
        key, eq, value = item.partition("=")
        if not eq or "." not in key:
            raise UserError(f"{label}: {item!r}: expected group.field=value")
        if key.strip() in sets:
            raise UserError(f"{label}: {key.strip()} is set twice")
        sets[key.strip()] = value.strip()
    v = Variant(name.strip(), mode.strip(), sets)
    check_variant(v, label, available)
    return v


def parse_variants(texts, available, shown, verb: str) -> list[Variant]:
    """Each --variant text in order (parse_variant), none under a name of `shown` (the
    --modes rendered beside them) or an earlier variant's; `verb` says what the command
    does with them ("shown", "timed", "drawn") in the one line."""
    out: list[Variant] = []
    for text in texts:
        v = parse_variant(text, available)
        if v.name in shown or any(v.name == u.name for u in out):
            raise UserError(f"--variant {text}: the name {v.name!r} is already {verb} (by "
                            "--modes or an earlier --variant); give it another")
        out.append(v)
    return out


def prepare_variants(r: Renderer, variants: list[Variant], base: ParamSet
                     ) -> dict[str, tuple[str, ParamSet]]:
    """The variants' user passes registered with `r` (a shader that does not compile
    stops here, before any frame), and what each renders: name -> (what `r` renders, the
    parameters: `base` with the variant's assignments)."""
    for v in variants:
        if v.method is not None:
            r.add_method(v.name, v.method)
    return {v.name: (v.runs_as, v.params(base, f"variant {v.name}")) for v in variants}


@dataclass
class Comparison:
    reference: RenderResult
    region: np.ndarray                    # (H, W) uint8, viewer.render.modes.regions codes
    params: dict                          # variant name -> its ParamSet
    results: dict                         # variant name -> RenderResult
    table: dict                           # variant name -> region_metrics(...)
    flips: dict                           # variant name -> (H, W) FLIP map
    ms: dict                              # "reference" and each name -> wall ms, first frame


def compare_frame(r: Renderer, t: float, base: ParamSet, variants: list[Variant], seed: int,
                  progress=None, log=None) -> Comparison:
    """The reference at `t` with `base` parameters, then every variant on the same
    renderer, each measured against the reference per region. `log(variant, line)` is
    told each variant's headline numbers. User passes are registered with the renderer
    first (a shader that does not compile stops here, before the reference)."""
    plan = prepare_variants(r, variants, base)
    t0 = time.perf_counter()
    ref = r.render("reference", t, base, seed=seed, record_visibility=True, progress=progress)
    ms = {"reference": (time.perf_counter() - t0) * 1e3}
    region = ref.host[REGIONS]
    out = Comparison(ref, region, {}, {}, {}, {}, ms)
    for v in variants:
        runs_as, params = plan[v.name]
        t0 = time.perf_counter()
        res = r.render(runs_as, t, params, seed=seed)
        ms[v.name] = (time.perf_counter() - t0) * 1e3
        maps = metric_maps(res.image, ref.image)
        out.params[v.name], out.results[v.name] = params, res
        out.table[v.name], out.flips[v.name] = region_metrics(maps, region), maps["flip"]
        if log is not None:
            tab = out.table[v.name]
            inner = tab["inner"]["flip"]
            log(v, f"{v.name}: FLIP {tab['all']['flip']:.4f} (inner "
                   f"{'n/a' if inner is None else f'{inner:.4f}'}), first frame {ms[v.name]:.0f} ms")
    return out
