"""`hmblur`: the command line. Each subcommand lives in its own module and adds itself
through `register(subparsers)`; a user's mistake prints one line and exits 2."""
from __future__ import annotations

import argparse
import sys

from .errors import UserError
from .progress import end_line

COMMANDS = ("shot", "compare", "bench", "view", "video")


class _Parser(argparse.ArgumentParser):
    def error(self, message):              # one line, exit 2, no usage dump
        raise UserError(f"{self.prog}: {message}")


def build_parser() -> argparse.ArgumentParser:
    import importlib
    parser = _Parser(prog="hmblur", description="Motion blur: post-process (McGuire, "
                     "UE4-style), hybrid ray-traced reveal, and a ground-truth reference.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"viewer.cmd_{name}")
        except ModuleNotFoundError as exc:    # a command not written yet does not exist
            if exc.name == f"viewer.cmd_{name}":
                continue
            raise
        module.register(sub)
    return parser


def main(argv=None) -> int:
    try:
        try:
            args = build_parser().parse_args(argv)
            return int(args.run(args) or 0)
        finally:
            end_line()                     # (a progress bar's line, cut short)
    except UserError as exc:
        print(f"hmblur: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:                 # an output that cannot be written (full disk, ...)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"hmblur: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("hmblur: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
