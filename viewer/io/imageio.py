"""sRGB encoding and atomic, deterministic file output.

Encoding (docs/scene-format.md): linear colour is clamped to [0, 1] once, passed through the
standard sRGB transfer function in float64, and stored as `floor(255 * srgb + 0.5)`.
Non-finite input is mapped before the clamp: NaN -> 0, +inf -> 1, -inf -> 0, so a bad
pixel shows up black instead of poisoning the encoder (numpy would cast NaN to 0 anyway,
but only by accident and with a warning).

Writers go through a temporary file in the destination directory followed by
`os.replace`, so a reader never sees a half-written file and a failed write leaves the
previous file (or nothing) in place. Every temp file and staging folder that exists is in
PARTIAL from the instant it is made (signals held meanwhile) until it is renamed or
removed, so whatever ends the program (an exception, Ctrl-C, SIGTERM) `remove_partials`
leaves none behind.
"""
from __future__ import annotations

import io
import json
import math
import os
import secrets
import shutil
from pathlib import Path
from typing import Any, Callable

import numpy as np
from PIL import Image

from .ending import held

_SRGB_LINEAR_MAX = 0.0031308   # linear-side breakpoint of the sRGB curve


def _clamped(linear) -> np.ndarray:
    x = np.asarray(linear, dtype=np.float64)
    x = np.nan_to_num(x, nan=0.0, posinf=1.0, neginf=0.0)
    return np.clip(x, 0.0, 1.0)


def _encode(x: np.ndarray) -> np.ndarray:
    """sRGB transfer function on float64 values already in [0, 1]."""
    return np.where(x <= _SRGB_LINEAR_MAX, 12.92 * x,
                    1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def linear_to_srgb8(linear) -> np.ndarray:
    """Linear colour (any shape) -> uint8 sRGB: clamp once, encode, floor(255*s + 0.5)."""
    s = _encode(_clamped(linear))
    return np.floor(255.0 * s + 0.5).astype(np.uint8)


def srgb_float(linear) -> np.ndarray:
    """Linear colour -> float32 sRGB in [0, 1], unquantised (what FLIP's "LDR" expects)."""
    return _encode(_clamped(linear)).astype(np.float32)


# --- atomic writers ------------------------------------------------------------------

PARTIAL: set[Path] = set()      # temp files and staging folders on disk now
# A signal that ends the program waits for the block (a file made and entered in PARTIAL,
# or renamed and taken out, is one step).
signals_held = held


def remove_partials():
    """Remove every temp file and staging folder still on disk (the CLI's last step)."""
    for p in list(PARTIAL):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
        PARTIAL.discard(p)


def forget_partial(p: Path, remove: bool = True):
    """`p` is renamed into place (remove False) or no longer wanted."""
    with signals_held():
        if remove:
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p, ignore_errors=True)
            else:
                p.unlink(missing_ok=True)
        PARTIAL.discard(p)


def _write_temp(path: Path, write: Callable[[io.BufferedWriter], None],
                made: list | None = None) -> Path:
    """Run `write(fileobj)` on a new temp file beside `path` and fsync it; its path, also
    appended to `made` the moment the file exists."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    # os.open with 0o666 lets the umask decide the final mode, as a plain open() would.
    with signals_held():
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        PARTIAL.add(tmp)
        if made is not None:
            made.append(tmp)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
    except BaseException:
        forget_partial(tmp)
        raise
    return tmp


def _atomic_write(path, write: Callable[[io.BufferedWriter], None]) -> Path:
    """Run `write(fileobj)` on a temp file beside `path`, fsync, then rename over it (an
    OutputSet of one file)."""
    files = OutputSet()
    files.add(path, write)
    files.commit()
    return Path(path)


class OutputSet:
    """Files that appear together or not at all (an image and its sidecar, a comparison's
    images and metrics): each is written to a temp file beside its path, and only when
    every one is written are they renamed into place, after creating their folders (and
    any missing parents). A
    failure on the way (a full disk, a directory where a file goes) leaves none of them.

    `folder` (viewer.io.outdir.OutputFolder): the files inside it follow its rule (none
    replaces a file hmblur did not write there; checked before any is written), and its
    list of hmblur's files is renamed into place with them; `remove(path)` unlinks a file
    of hmblur's there once the others are in place (a longer earlier clip's last frames)."""

    def __init__(self, folder=None):
        self._files: list[tuple[Path, Callable]] = []
        self._folder = folder
        self._remove: list[Path] = []

    def remove(self, path):
        if self._folder is None or self._folder.rel(Path(path)) is None:
            raise ValueError(f"OutputSet.remove: {path} is not in the set's folder")
        self._remove.append(Path(path))

    def add(self, path, write: Callable[[io.BufferedWriter], None]):
        self._files.append((Path(path), write))

    def png(self, path, image):
        data = _png_bytes(image)          # encoded now: a bad image fails before any write
        self.add(path, lambda f: f.write(data))

    def json(self, path, obj: Any):
        data = _json_bytes(obj)
        self.add(path, lambda f: f.write(data))

    def npy(self, path, array):
        a = np.asarray(array)
        self.add(path, lambda f: np.save(f, a, allow_pickle=False))

    def commit(self):
        for path, _ in self._files:       # what a rename would fail on, or replace
            if path.exists() and not path.is_file():
                raise IsADirectoryError(21, "exists and is not a regular file", str(path))
        rule = self._folder
        doc = rule.before([p for p, _ in self._files] + self._remove) if rule else None
        files = list(self._files)
        done: list[Path] = []
        made: list[Path] = []
        try:
            for path, _ in self._files:
                missing = []                  # the folder and its missing parents
                folder = path.parent
                while not folder.exists() and folder != folder.parent:
                    missing.append(folder)
                    folder = folder.parent
                for folder in reversed(missing):
                    with signals_held():
                        folder.mkdir()
                        made.append(folder)
            for path, write in files:
                _write_temp(path, write, done)
            if rule is not None:              # hmblur's list of its files there, renamed last
                removed = [rule.rel(p) for p in self._remove]
                listed = rule.after(doc, list(zip(done, [p for p, _ in files])), removed)
                if listed is not None:
                    from .outdir import MANIFEST
                    files.append((rule.path / MANIFEST, lambda f: f.write(listed)))
                    _write_temp(rule.path / MANIFEST, files[-1][1], done)
            with signals_held():              # the renames: all of them, then a signal
                for tmp, (path, _) in zip(done, files):
                    os.replace(tmp, path)
                    PARTIAL.discard(tmp)
                for path in self._remove:
                    path.unlink(missing_ok=True)
        except BaseException:
            for tmp in done:
                if tmp in PARTIAL:
                    forget_partial(tmp)
            for folder in reversed(made):     # deepest first
                try:
                    folder.rmdir()
                except OSError:               # (a file renamed into it before a failure)
                    pass
            raise


def _png_bytes(image) -> bytes:
    """A uint8 (H,W,3) RGB or (H,W) grey image as PNG with no metadata chunks.

    Pillow writes no tIME/tEXt chunks unless asked, and the compression level is pinned,
    so the same pixels give the same bytes.
    """
    a = np.asarray(image)
    if a.dtype != np.uint8:
        raise ValueError(f"write_png_atomic: expected uint8 pixels, got {a.dtype}")
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 3)):
        raise ValueError(f"write_png_atomic: expected (H,W) or (H,W,3), got {a.shape}")
    img = Image.fromarray(np.ascontiguousarray(a), mode="L" if a.ndim == 2 else "RGB")
    buf = io.BytesIO()
    img.save(buf, format="PNG", compress_level=6)
    return buf.getvalue()


png_bytes = _png_bytes           # (public: a worker sends an image's file as bytes)


def write_png_atomic(path, image) -> Path:
    """Write a uint8 (H,W,3) RGB or (H,W) grey image as PNG (_png_bytes), atomically."""
    data = _png_bytes(image)
    return _atomic_write(path, lambda f: f.write(data))


def json_safe(obj: Any) -> Any:
    """Plain-JSON form of `obj`: numpy scalars/arrays become Python values and lists,
    tuples become lists, and non-finite floats become the strings "inf", "-inf", "nan"
    (standard JSON has no infinities; PSNR of identical images is inf)."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, np.generic):
        return json_safe(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return "nan" if math.isnan(obj) else ("inf" if obj > 0 else "-inf")
    return obj


def _json_bytes(obj: Any) -> bytes:
    text = json.dumps(json_safe(obj), sort_keys=True, indent=2, allow_nan=False) + "\n"
    return text.encode("utf-8")


def write_json_atomic(path, obj: Any) -> Path:
    """Write `obj` as JSON (sorted keys, indent 2, trailing newline) via `json_safe`."""
    data = _json_bytes(obj)      # encoded first: a serialisation error must not touch disk
    return _atomic_write(path, lambda f: f.write(data))
