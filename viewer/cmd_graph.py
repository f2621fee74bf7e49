"""`hmblur graph [MODE]`: a mode's pipeline as its passes run, GPU and CPU, with the
textures and host resources each reads and makes, then every host resource with its
type, producer and readers (Pipeline.describe; no scene or GL context needed)."""
from __future__ import annotations

from world.errors import UserError
from .render.modes import MODES


def register(sub):
    p = sub.add_parser("graph", help="print a mode's passes and resources",
                       description="Print MODE's pipeline (every mode's without MODE): each "
                       "pass in order with the textures and host-side resources (host:NAME) "
                       "it reads and makes, '(cpu)' for host work, then each host resource "
                       "with its type, its producer and its readers.")
    p.add_argument("mode", nargs="?", default=None, metavar="MODE",
                   help=f"one of: {', '.join(MODES)} (default: every mode)")
    p.set_defaults(run=run)


def run(args) -> int:
    if args.mode is not None and args.mode not in MODES:
        raise UserError(f"graph {args.mode}: expected one of {', '.join(MODES)}")
    modes = [args.mode] if args.mode else list(MODES)
    print("\n\n".join(MODES[m]().describe() for m in modes))
    return 0
