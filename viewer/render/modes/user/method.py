"""A user's blur method: `glsl:PATH` (a fragment shader) or `py:PATH:FUNCTION` (a Python
function), read once as bytes (at most limits.MAX_METHOD_BYTES), or a Python callable given
through the API. The bytes travel with the method (a sweep's tasks pickle it), so the code
that runs on a worker is the code that was named, and its digest keys the sweep's cells.

A method file is code that runs, with the user's rights: a Python file's top level runs
when it is loaded, once per process and content (docs/api.md).

Mistakes are UserErrors: a file that cannot be read, a shader without `#version`, a Python
file that does not parse or lacks the function, a function that raises (MethodError: its
message carries the frames of the user's own file, not the renderer's)."""
from __future__ import annotations

import hashlib
import linecache
import os
import sys
import traceback
import types
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from world import limits
from world.errors import UserError, printable
from world.regular_file import Grew, NotRegular, TooLarge, read_regular

KINDS = ("glsl", "py")
GLSL_VERSION = "#version 330 core"


class MethodError(UserError):
    """A user's Python method that raised: the headline, then the frames of the user's own
    code (most recent call last), each line made printable; the CLI prints it whole."""

    def __init__(self, headline: str, frames: list[str]):
        super().__init__(headline)
        self.headline, self.frames = headline, frames

    def __str__(self) -> str:
        return "\n".join(printable(line) for line in (self.headline, *self.frames))


@dataclass(frozen=True)
class UserPass:
    """A user's blur pass. `spec`: how it was named (`glsl:PATH`, `py:PATH:FUNCTION`), for
    messages and tables; `path`: the file's absolute path (None for a callable);
    `source`: the file's bytes; `function`: the Python function's name; `fn`: a callable
    given directly (the API), which runs in this process only."""
    kind: str
    spec: str
    path: Path | None = None
    source: bytes = b""
    function: str = ""
    fn: Callable | None = field(default=None, compare=False, repr=False)

    @property
    def digest(self) -> str:
        """sha256 of the kind, the function's name and the file's bytes (a callable: its
        code's), what a result of this method depends on."""
        h = hashlib.sha256(f"{self.kind}\0{self.function}\0".encode())
        if self.fn is not None:
            code = getattr(self.fn, "__code__", None)
            h.update(repr((getattr(self.fn, "__module__", ""), self.function,
                           code.co_code if code else id(self.fn))).encode())
        h.update(self.source)
        return h.hexdigest()

    @property
    def text(self) -> str:
        return self.source.decode("utf-8")

    @property
    def label(self) -> str:
        """The pass's name (`hmblur graph`, `hmblur bench`): kind and file or function."""
        if self.path is None:
            return f"{self.kind}:{self.function}"
        return f"{self.kind}:{self.path.name}" + (f":{self.function}" if self.function else "")

    def callable(self, where: str = "") -> Callable:
        """The Python function (the file run once per process and content); `where`
        names the method in messages (default: its spec)."""
        if self.fn is not None:
            return self.fn
        key = (self.digest, str(self.path))
        if key not in _LOADED:
            _LOADED[key] = _load_function(self, where or self.spec)
        return _LOADED[key]


# The functions of the Python method files run in this process, by (digest, path).
_LOADED: dict[tuple[str, str], Callable] = {}


def parse_method(text: str, base: Path | None = None, label: str = "") -> UserPass:
    """`glsl:PATH` or `py:PATH:FUNCTION` (a mode's place in --variant and sweep files),
    PATH relative to `base` (default: the current folder); the file read and checked now.
    `label` names where the text came from in messages."""
    kind, _, rest = text.partition(":")
    where = label or text
    if kind not in KINDS:
        raise UserError(f"{where}: expected glsl:PATH or py:PATH:FUNCTION")
    if kind == "glsl":
        path_text, function = rest, ""
    else:
        path_text, _, function = rest.rpartition(":")
        if not path_text or not function.isidentifier():
            raise UserError(f"{where}: expected py:PATH:FUNCTION, a Python file and the "
                            "name of the function in it, e.g. py:blur.py:gather")
    if not path_text:
        raise UserError(f"{where}: expected glsl:PATH, the path of a fragment shader file")
    path = Path(os.path.abspath((base or Path.cwd()) / path_text))
    source = read_method_file(path, where)
    m = UserPass(kind, text, path, source, function)
    check(m, where)
    return m


def from_callable(fn: Callable, name: str | None = None) -> UserPass:
    """A Python function given directly (the API): it runs in this process."""
    if not callable(fn):
        raise UserError(f"python method: expected a function, got {type(fn).__name__}")
    function = name or getattr(fn, "__qualname__", None) or type(fn).__name__
    return UserPass("py", f"py:{function}", None, b"", function, fn)


def read_method_file(path: Path, where: str) -> bytes:
    """The file's bytes: a regular file of at most limits.MAX_METHOD_BYTES, else one line."""
    try:
        data = read_regular(path, limits.MAX_METHOD_BYTES)
    except FileNotFoundError:
        raise UserError(f"{where}: {path}: file not found") from None
    except NotRegular:
        raise UserError(f"{where}: {path}: not a regular file") from None
    except TooLarge as exc:
        raise UserError(f"{where}: {path}: {exc.size} bytes, more than the "
                        f"{limits.MAX_METHOD_BYTES} a method file may hold") from None
    except Grew:
        raise UserError(f"{where}: {path}: grew while it was read") from None
    except OSError as exc:
        raise UserError(f"{where}: {path}: cannot read ({exc.strerror or exc})") from None
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UserError(f"{where}: {path}: not UTF-8 text (byte {exc.start})") from None
    return data


def check(m: UserPass, where: str):
    """What can be checked without a GL context: a shader's `#version 330 core` first
    line (its compile is checked with the renderer's context: pipeline.py); a Python
    file's function, loaded now."""
    if m.kind == "glsl":
        first = next((line.strip() for line in m.text.splitlines() if line.strip()), "")
        if first != GLSL_VERSION:
            raise UserError(f"{where}: {m.path}:1: expected '{GLSL_VERSION}' as the first "
                            "line (the inputs are GLSL 3.30 samplers: docs/api.md)")
    else:
        m.callable(where)


def _load_function(m: UserPass, where: str) -> Callable:
    """Run the file's top level in a module of its own, then find the function."""
    name = str(m.path)
    text = m.text
    try:
        code = compile(text, name, "exec")
    except SyntaxError as exc:
        raise UserError(f"{where}: {name}:{exc.lineno}: {type(exc).__name__}: "
                        f"{exc.msg}") from None
    # The source for tracebacks, kept (mtime None: never checked against the disk), so a
    # worker without the file shows the user's lines too.
    linecache.cache[name] = (len(text), None, text.splitlines(True), name)
    module = types.ModuleType(f"hmblur_method_{m.digest[:16]}")
    module.__file__ = name
    sys.modules[module.__name__] = module      # (dataclasses and pickling look it up)
    try:
        exec(code, module.__dict__)
    except Exception as exc:
        sys.modules.pop(module.__name__, None)
        raise user_code_error(f"{where}: loading {name}", exc, {name}) from exc
    fn = getattr(module, m.function, None)
    if not callable(fn):
        found = sorted(k for k, v in vars(module).items()
                       if callable(v) and getattr(v, "__module__", None) == module.__name__)
        raise UserError(f"{where}: {name}: no function {m.function!r} (it defines "
                        f"{', '.join(found) or 'no function'})")
    return fn


def user_files(m: UserPass) -> set[str]:
    """The file names whose frames are the user's: the method file, or the callable's."""
    if m.path is not None:
        return {str(m.path)}
    code = getattr(m.fn, "__code__", None) or getattr(getattr(m.fn, "__call__", None),
                                                      "__code__", None)
    return {code.co_filename} if code is not None else set()


def user_code_error(headline: str, exc: BaseException, files: set[str]) -> MethodError:
    """MethodError for an exception raised in the user's code: `headline: Type: message`
    and the traceback's frames in `files` (the user's own), most recent call last."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if f.filename in files]
    lines = []
    for f in frames:
        lines.append(f'  File "{f.filename}", line {f.lineno}, in {f.name}')
        if f.line:
            lines.append(f"    {f.line.strip()}")
    detail = " ".join(str(exc).split())
    return MethodError(f"{headline}: {type(exc).__name__}" + (f": {detail}" if detail else ""),
                       lines)
