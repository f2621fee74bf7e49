"""`hmblur`: the command line. Each subcommand lives in its own module and adds itself
through `register(subparsers)`; a user's mistake prints one line and exits 2."""
from __future__ import annotations

import argparse
import os
import signal
import sys
import textwrap
import threading
from pathlib import Path

from world import jit_notice
from world.errors import UserError, printable
from viewer.cli.args import OTHER_SCENE_DIRS
from viewer.io.ending import Terminated, catch_signals, received, restore_signals
from viewer.io.imageio import remove_partials
from viewer.io.progress import end_line
from viewer.io.sidecar import version

COMMANDS = ("shot", "compare", "bench", "view", "params", "graph", "video", "scene",
            "sweep")

EPILOG = """\
MODE is one of {modes} (shot and view: hybrid by default).

SCENE is a scene file (.toml) or a built-in name ({builtins}); more scenes:
{others}. A glTF asset (.gltf, .glb) is a scene too: framed, lit and played
('hmblur scene ASSET' writes that scene as TOML).

examples:
  hmblur shot living_room --mode hybrid --out out/hybrid.png
  hmblur compare spinner --size 640x360 --out out/spinner
  hmblur params hybrid
  hmblur shot model.glb --mode hybrid --out out/model.png
  hmblur scene model.glb --out model.toml                  (the same scene, to edit)
  hmblur shot --params out/hybrid.json --out again.png     (the same image, byte for byte)

'hmblur COMMAND --help' describes a command. A user's mistake prints one line
'hmblur: error: ...' and exits with status 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):              # one line, exit 2, no usage dump
        command = self.prog.removeprefix("hmblur").strip()
        raise UserError(f"{command}: {message}" if command else message)


def other_scenes() -> str:
    """The scene files beside the built-in ones, by folder (cliargs.OTHER_SCENE_DIRS and the
    conformance scenes' subfolders), as the help lists them."""
    from world.loader import builtin_dir
    groups = []
    for folder in OTHER_SCENE_DIRS:
        base = (builtin_dir() / folder).resolve()
        for sub in [base] + sorted(p for p in base.glob("*") if p.is_dir()):
            names = sorted(p.stem for p in sub.glob("*.toml"))
            if names:
                shown = Path(folder.removeprefix("../")) if folder.startswith("..") else \
                    Path("scenes") / folder
                shown = shown / sub.relative_to(base) if sub != base else shown
                groups.append(f"{shown.as_posix()}/*.toml ({', '.join(names)})")
    return ", ".join(groups)


def epilog(text: str) -> str:
    """The help's closing text, its long paragraphs (the lists) wrapped at 88 columns."""
    return "\n".join(textwrap.fill(line, 88) if len(line) > 88 else line
                     for line in text.split("\n"))


def build_parser() -> argparse.ArgumentParser:
    import importlib

    from world.loader import builtin_scene_names
    from viewer.render.modes import MODES
    parser = _Parser(prog="hmblur", formatter_class=argparse.RawDescriptionHelpFormatter,
                     description="Motion blur: post-process (McGuire 2012, UE4-style, "
                     "Guertin 2014), the hybrid ray-traced reveal, and a ground-truth reference "
                     "to measure them against.",
                     epilog=epilog(EPILOG.format(builtins=", ".join(builtin_scene_names()),
                                                 modes=", ".join(MODES),
                                                 others=other_scenes())))
    parser.add_argument("--version", action="version", version=f"hmblur {version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser,
                                metavar="COMMAND", title="commands")
    for name in COMMANDS:
        importlib.import_module(f"viewer.commands.{name}").register(sub)
    return parser


def _terminated(signum: int, exc: BaseException | None = None) -> int:
    """One line: the signal, and what the command noted on the way out (a sweep: the
    cells it kept)."""
    said = "interrupted" if signum == signal.SIGINT else \
        f"terminated ({signal.Signals(signum).name})"
    notes = getattr(exc, "__notes__", None) or []
    print(printable("; ".join([f"hmblur: {said}", *notes])), file=sys.stderr)
    return 128 + signum


def _reader_gone() -> int:
    """stdout's reader has closed the pipe (`hmblur graph | head`): nothing more to say to
    it, so no message; stdout goes to /dev/null so that the interpreter's last flush is
    quiet, and the status is a SIGPIPE's, as for any tool in such a pipeline."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):   # a stdout without a descriptor
        pass
    return 128 + signal.SIGPIPE


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    old_handlers = catch_signals() if threading.current_thread() is threading.main_thread() else {}
    try:
        try:
            parser = build_parser()
            if not argv:                   # bare `hmblur`: what it takes, on stderr
                parser.print_help(sys.stderr)
                return 2
            args = parser.parse_args(argv)
            jit_notice.install()
            return int(args.run(args) or 0)
        finally:
            end_line()                     # (a progress bar's line, cut short)
            remove_partials()              # (what an interrupted write left: none, else)
            restore_signals(old_handlers)
            sys.stdout.flush()             # (a reader gone away shows here, not at exit)
    except BrokenPipeError:
        return _reader_gone()
    except Terminated as exc:
        return _terminated(exc.signum, exc)
    except KeyboardInterrupt as exc:
        return _terminated(signal.SIGINT, exc)
    except Exception as exc:
        if received:
            # Raised inside C code (numpy's tofile, ...), Terminated can come out as
            # another exception; the clean-up ran all the same.
            return _terminated(received[0])
        if isinstance(exc, UserError):
            print(f"hmblur: error: {exc}", file=sys.stderr)
            return 2
        if isinstance(exc, MemoryError):   # (what was allocated is freed by now)
            print("hmblur: error: out of memory: this machine (or the process's memory "
                  "limit) cannot hold the work: give a smaller size, fewer samples, "
                  "variants or frames", file=sys.stderr)
            return 2
        if isinstance(exc, OSError):       # an output that cannot be written (full disk, ...)
            where = f"{exc.filename}: " if exc.filename else ""
            print(printable(f"hmblur: error: {where}{exc.strerror or exc}"), file=sys.stderr)
            return 2
        raise


if __name__ == "__main__":
    sys.exit(main())
