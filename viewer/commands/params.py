"""`hmblur params [MODE]`: every parameter `--set` takes (default, range, unit, help), from
the same dataclasses that drive `--set`, the viewer's panel and the sidecars."""
from __future__ import annotations

import textwrap

from world.errors import UserError
from viewer.render.graph.params import GROUPS, describe_params
from viewer.render.modes import MODE_GROUPS, MODES

EFFECTS = {"uniform": "", "recompile": "a change recompiles shaders",
           "realloc": "a change reallocates textures"}


def register(sub):
    p = sub.add_parser("params", help="list the parameters --set takes",
                       description="List every parameter (GROUP.FIELD) with its default, "
                       "accepted values, unit and meaning: those of MODE's groups, or of "
                       "every group. Set one with --set GROUP.FIELD=VALUE on shot, compare, "
                       "bench or view.")
    p.add_argument("mode", nargs="?", default=None, metavar="MODE",
                   help=f"one of: {', '.join(MODES)} (default: every group)")
    p.set_defaults(run=run)


def format_params(names=None) -> str:
    lines = []
    rows = describe_params(names)
    for group in GROUPS:
        mine = [r for r in rows if r["key"].startswith(group + ".")]
        if not mine:
            continue
        users = [m for m, gs in MODE_GROUPS.items() if group in gs]
        lines.append(f"{group}  (used by {', '.join(users) or 'no mode'})")
        for r in mine:
            unit = f"  [{r['unit']}]" if r["unit"] else ""
            lines.append(f"  {r['key']} = {r['default']!r}  ({r['type']}: {r['range']}){unit}")
            text = r["help"] + (f"; {EFFECTS[r['effect']]}" if EFFECTS.get(r["effect"]) else "")
            lines += textwrap.wrap(text, 88, initial_indent="      ", subsequent_indent="      ")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def run(args) -> int:
    if args.mode is None:
        print(format_params(), end="")
        return 0
    if args.mode not in MODES:
        raise UserError(f"params {args.mode}: expected one of {', '.join(MODES)}")
    groups = MODE_GROUPS.get(args.mode, ())
    if not groups:
        print(f"mode {args.mode} has no parameters")
        return 0
    print(format_params(groups), end="")
    return 0
