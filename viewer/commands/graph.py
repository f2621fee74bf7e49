"""`hmblur graph [MODE]`: a mode's pipeline as it runs under the given parameters (its
configuration: viewer/render/graph/registry.py), GPU and CPU passes with the textures and host
resources each reads and makes, the read-backs to the host, then every host resource
with its type, producer and readers (Pipeline.describe; no scene or GL context needed),
and the renderer's own work around the pipeline (steps.around)."""
from __future__ import annotations

from world.errors import UserError
from viewer.cli.args import check_set_groups, read_sidecar
from viewer.render.graph.params import ParamSet
from viewer.render.modes import MODE_GROUPS, MODES
from viewer.render.graph.registry import build
from viewer.render.modes.user import user_pipeline
from viewer.eval.comparison import parse_variant
from viewer.render.steps import around


def around_text(mode: str, params: ParamSet) -> str:
    """The renderer's own work around the pipeline, which `hmblur bench` times too."""
    rows = around(mode, params)
    return "\naround the pipeline (the renderer's own):\n" + "\n".join(
        f"  {name}{' (cpu)' if where == 'cpu' else ''}: {when}" for name, where, when in rows)


def register(sub):
    p = sub.add_parser("graph", help="print a mode's passes and resources",
                       description="Print MODE's pipeline (every mode's without MODE) as "
                       "built for the parameters (--set, --params): its configuration, "
                       "each pass in order with the textures and host-side resources "
                       "(host:NAME) it reads and makes, '(cpu)' for host work, the "
                       "textures read back to the host, then each host resource with "
                       "its type, its producer and its readers.")
    p.add_argument("mode", nargs="?", default=None, metavar="MODE",
                   help=f"one of: {', '.join(MODES)} (default: the --params file's, "
                        f"else every mode)")
    p.add_argument("--set", action="append", default=[], metavar="GROUP.FIELD=VALUE",
                   help="set a parameter (repeatable; 'hmblur params' lists them)")
    p.add_argument("--variant", action="append", default=[], metavar="NAME=MODE[:G.F=V,...]",
                   help="also (without MODE: only) the pipeline of a mode under a name with "
                        "its own parameters, or of a blur pass of your own: "
                        "NAME=glsl:PATH.frag, NAME=py:PATH.py:FUNCTION (as compare's "
                        "--variant; repeatable)")
    p.add_argument("--params", type=str, default=None, metavar="FILE.json",
                   help="JSON sidecar of an earlier output: its parameters (and its mode "
                        "where MODE is left out); --set given beside it wins")
    p.set_defaults(run=run)


def run(args) -> int:
    params = ParamSet()
    mode = args.mode
    if args.params is not None:
        side = read_sidecar(args.params)
        params.update(side["params"], source=f"--params {args.params}")
        if mode is None and side.get("mode") is not None:
            mode = str(side["mode"])
    if mode is not None and mode not in MODES:
        raise UserError(f"graph {mode}: expected one of {', '.join(MODES)}")
    variants = [parse_variant(text, list(MODES)) for text in args.variant]
    modes = [mode] if mode else ([] if variants else list(MODES))
    check_set_groups(args.set, modes + [v.name for v in variants],
                     {**MODE_GROUPS, **{v.name: v.groups for v in variants}})
    params.apply(args.set)
    graphs = [(build(m, params).describe(), m, params) for m in modes]
    for v in variants:
        if v.method is not None:
            graphs.append((user_pipeline(v.name, v.method).describe(), None, params))
        else:
            own = v.params(params, f"variant {v.name}")
            graphs.append((build(v.mode, own).describe(), v.mode, own))
    print("\n\n".join(text + (around_text(m, p) if m else "") for text, m, p in graphs))
    return 0
