"""A small GLSL preprocessor and program cache.

- `#include "file.glsl"` pastes a file from glsl/ once per program (include-once).
- A program's fragment may also come as text of the caller's (a user's blur pass, read from
  a file outside glsl/: viewer/render/modes/user/): its errors then name that file, and its
  `#include`s still read the library files of glsl/ (e.g. graph/noise.glsl).
- Defines are inserted right after `#version`, from Python values (never written twice).
- `#line` markers give every file its own line range: file k's line n is reported as
  k * LINE_BASE + n. Mesa prints source-string 0 whatever `#line` says, so the line number
  alone must identify the file. Compile errors are rewritten as `file:line: message`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import moderngl

from glsl import DIR as GLSL_DIR

LINE_BASE = 100000
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$')
_VERSION = re.compile(r"^\s*#version\b")
# Mesa: "0:12(5): error: ...", NVIDIA: "0(12) : error ...".
_ERRLINE = re.compile(r"^\s*(\d+)[:(](\d+)\)?(?:\(\d+\))?\s*:?\s*(.*)$")


class ShaderError(RuntimeError):
    """A shader that failed to compile or link; the message points at file:line."""


@dataclass
class Source:
    text: str
    files: list[str] = field(default_factory=list)    # index -> file name

    def locate(self, line: int) -> str:
        k, n = divmod(line, LINE_BASE)
        name = self.files[k - 1] if 1 <= k <= len(self.files) else "?"
        return f"{name}:{n}"


def _format_define(value) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return repr(value) if "e" not in repr(value) else f"{value:.9e}"
    return str(value)


def preprocess(name: str, defines: dict | None = None, root: Path = GLSL_DIR,
               text: str | None = None) -> Source:
    """`name` from `root` with its includes; `text`: the top file's own text instead of
    root/name (`name` then only labels it, e.g. a user's path)."""
    src = Source("")
    out: list[str] = []
    seen: set[str] = set()

    def emit(fname: str, top: bool):
        if fname in seen:
            return
        seen.add(fname)
        path = root / fname
        if top and text is not None:
            lines = text.splitlines()
        elif path.is_file():
            lines = path.read_text().splitlines()
        else:
            raise ShaderError(f"{fname}: no such shader file in {root}")
        src.files.append(fname)
        k = len(src.files)
        if not top:
            out.append(f"#line {k * LINE_BASE + 1} {k}")
        for n, line in enumerate(lines, start=1):
            m = _INCLUDE.match(line)
            if m:
                emit(m.group(1), top=False)
                out.append(f"#line {k * LINE_BASE + n + 1} {k}")
            elif _VERSION.match(line):
                if not top:
                    raise ShaderError(f"{fname}:{n}: #version in an included file")
                out.append(line)
                for key, value in (defines or {}).items():
                    out.append(f"#define {key} {_format_define(value)}")
                out.append(f"#line {k * LINE_BASE + n + 1} {k}")
            else:
                out.append(line)

    emit(name, top=True)
    src.text = "\n".join(out) + "\n"
    return src


def _rewrite_errors(message: str, sources: list[Source]) -> str:
    lines = []
    for raw in message.splitlines():
        m = _ERRLINE.match(raw)
        if m and int(m.group(2)) >= LINE_BASE:
            lines.append(f"{sources[0].locate(int(m.group(2)))}: {m.group(3)}")
        elif raw.strip() and not set(raw.strip()) <= {"="}:
            lines.append(raw.strip())
    return "\n".join(lines)


def build_program(ctx: moderngl.Context, vertex: str, fragment: str,
                  defines: dict | None = None, root: Path = GLSL_DIR,
                  fragment_text: str | None = None) -> moderngl.Program:
    """Compile vertex + fragment files from glsl/ with the defines; errors name file:line.
    `fragment_text`: the fragment's own text, labelled `fragment` (preprocess)."""
    vs = preprocess(vertex, defines, root)
    fs = preprocess(fragment, defines, root, fragment_text)
    try:
        return ctx.program(vertex_shader=vs.text, fragment_shader=fs.text)
    except moderngl.Error as exc:
        msg = str(exc)
        stage = fs if "fragment_shader" in msg else vs
        raise ShaderError(f"shader {vertex} + {fragment}:\n" + _rewrite_errors(msg, [stage])) from None


class ProgramCache:
    """Programs keyed by (vertex, fragment, defines); released with the context owner."""

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._programs: dict = {}
        self._empty: dict = {}

    def get(self, vertex: str, fragment: str, defines: dict | None = None,
            fragment_text: str | None = None) -> moderngl.Program:
        """`fragment_text`: the fragment's text, labelled `fragment` (build_program)."""
        key = (vertex, fragment, tuple(sorted((defines or {}).items())), fragment_text)
        if key not in self._programs:
            self._programs[key] = build_program(self.ctx, vertex, fragment, defines,
                                                fragment_text=fragment_text)
        return self._programs[key]

    def empty_vao(self, prog: moderngl.Program) -> moderngl.VertexArray:
        """A vertex array without buffers, for passes that draw from gl_VertexID."""
        if prog.glo not in self._empty:
            self._empty[prog.glo] = self.ctx.vertex_array(prog, [])
        return self._empty[prog.glo]

    def clear(self):
        # GL objects are released explicitly, never in __del__ (the context may be gone).
        for vao in self._empty.values():
            vao.release()
        for prog in self._programs.values():
            prog.release()
        self._programs.clear()
        self._empty.clear()
