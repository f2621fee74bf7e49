"""Frame sequences to disk: MP4 (H.264 by the libx264 that PyAV's wheel bundles), GIF
(Pillow), or a folder of PNGs, chosen by the output path (`video_paths`, the one place for
that rule).

Nothing appears until every file is written (imageio.OutputSet's rule): frames are encoded
into a hidden staging folder beside the output as they come, and `commit` moves the video,
its sidecar and any metrics files into place together; an error or Ctrl-C on the way
removes the staging folder and leaves the destination as it was.
"""
from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np
from PIL import Image

from viewer.cli import args as cliargs
from world.errors import UserError
from .imageio import PARTIAL, OutputSet, forget_partial, signals_held, write_png_atomic
from .outdir import OutputFolder

KINDS = ("mp4", "gif", "png")
SUFFIXES = {".mp4": "mp4", ".gif": "gif"}
OUT_HELP = ("PATH.mp4 (H.264), PATH.gif, or a folder of PNG frames (a path without "
            "extension or ending in /); the JSON sidecar goes to PATH.json, in a folder to "
            "video.json inside it")
# H.264 settings: constant quality (CRF 18 is close to visually lossless), 4:2:0 chroma
# for every player, BT.709 matrix and limited range, tagged so that decoders convert back
# with the same matrix.
CRF = "18"
PRESET = "medium"
FRAME = re.compile(r"frame_(\d{4,})\.png")


@dataclass(frozen=True)
class VideoPaths:
    kind: str           # "mp4", "gif" or "png" (a folder of frames)
    video: Path         # the file, or the folder of frames
    flag: str = "--out"

    @property
    def folder(self) -> Path:
        """Where the sidecar and metrics files go."""
        return self.video if self.kind == "png" else self.video.parent

    def output_set(self) -> OutputSet:
        """The set the video and its files are committed in (a folder of frames: under
        the rule of viewer/io/outdir.py)."""
        return OutputSet(OutputFolder(self.video, self.flag) if self.kind == "png" else None)

    def beside(self, name: str, suffix: str) -> Path:
        """A file that belongs to the video: `clip.mp4` -> clip_NAME.SUFFIX (clip.json for
        the sidecar, name ""); a folder `frames/` -> frames/NAME.SUFFIX (video.json)."""
        if self.kind == "png":
            return self.video / f"{name or 'video'}{suffix}"
        stem = self.video.stem
        return self.video.with_name(f"{stem}_{name}{suffix}" if name else f"{stem}{suffix}")


def video_paths(text: str, flag: str = "--out", extra: tuple[tuple[str, str], ...] = ()) -> VideoPaths:
    """The output kind from PATH, checked as writable, with its sidecar and the `extra`
    (name, suffix) files that go beside it."""
    if not text:
        raise UserError(f"{flag} '': expected a path: {OUT_HELP}")
    p = Path(text)
    is_folder = text.endswith(("/", os.sep)) or p.suffix == ""
    if is_folder:
        out = VideoPaths("png", p, flag)
        cliargs.check_output_dir(text, flag)
    else:
        kind = SUFFIXES.get(p.suffix.lower())
        if kind is None:
            hint = " (a folder of PNGs: give a path without extension)" if p.suffix.lower() == ".png" else ""
            raise UserError(f"{flag} {text}: unknown extension {p.suffix!r}: expected .mp4, "
                            f".gif, or a folder path{hint}")
        out = VideoPaths(kind, p, flag)
        cliargs.check_output_file(text, flag)
    for name, suffix in (("", ".json"),) + tuple(extra):
        path = out.beside(name, suffix)
        if path.exists() and not path.is_file():
            raise UserError(f"{flag} {text}: {path} exists and is not a regular file")
    return out


def check_folder_collisions(out: VideoPaths, frames: int, extra=()):
    """A folder of frames may hold files of its own: the ones this run writes must be
    absent or hmblur's (the rule of viewer/io/outdir.py), checked before any frame is rendered."""
    if out.kind != "png":
        return
    OutputFolder(out.video, out.flag).check(
        [f"frame_{k:04d}.png" for k in range(frames)] + ["video.json"]
        + [f"{n}{s}" for n, s in extra])


def even_size(frame: np.ndarray) -> np.ndarray:
    """4:2:0 chroma needs even sides: repeat the last row / column where one is odd."""
    h, w = frame.shape[:2]
    return np.pad(frame, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")


def gif_durations(n: int, fps: float) -> list[int]:
    """GIF delays are whole centiseconds: frame k lasts round(100 (k+1) / fps) -
    round(100 k / fps) of them, so the clip keeps its length (24 fps: 4, 4, 4, 5, ...)."""
    ends = [round(100.0 * k / fps) for k in range(n + 1)]
    return [max(1, 10 * (b - a)) for a, b in zip(ends, ends[1:])]


class VideoWriter:
    """Frames (uint8 (H,W,3) sRGB, all one size) in, one video out on `commit`."""

    def __init__(self, out: VideoPaths, fps: float):
        if not (fps > 0 and np.isfinite(fps)):
            raise UserError(f"--fps {fps!r}: expected a number > 0")
        self.out, self.fps = out, float(fps)
        # Staged beside the destination, in its nearest existing folder (one file system,
        # so the move is a rename); missing folders are made only at commit (OutputSet).
        parent = out.video.parent if str(out.video.parent) else Path(".")
        while not parent.exists() and parent != parent.parent:
            parent = parent.parent
        with signals_held():
            self.stage = Path(tempfile.mkdtemp(prefix=f".{out.video.name}.", suffix=".part",
                                               dir=parent))
            PARTIAL.add(self.stage)
        self.count = 0
        self.size: tuple[int, int] | None = None
        self._container = self._stream = None
        self._gif: list[np.ndarray] = []

    # -- frames
    def add(self, frame: np.ndarray):
        a = np.ascontiguousarray(frame)
        if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] != 3:
            raise ValueError(f"VideoWriter: expected uint8 (H,W,3), got {a.dtype} {a.shape}")
        size = (a.shape[1], a.shape[0])
        if self.size is None:
            self.size = size
        elif size != self.size:
            raise ValueError(f"VideoWriter: frame {self.count} is {size[0]}x{size[1]}, "
                             f"the first was {self.size[0]}x{self.size[1]}")
        if self.out.kind == "png":
            write_png_atomic(self.stage / self.frame_name(self.count), a)
        elif self.out.kind == "gif":
            self._gif.append(a)
        else:
            self._encode(even_size(a))
        self.count += 1

    @property
    def file_size(self) -> tuple[int, int] | None:
        """The frames' size as the file holds them: an MP4's sides rounded up to even
        (even_size), the frames' own otherwise."""
        if self.size is None or self.out.kind != "mp4":
            return self.size
        return (self.size[0] + self.size[0] % 2, self.size[1] + self.size[1] % 2)

    def frame_name(self, k: int) -> str:
        return f"frame_{k:04d}.png"

    def _encode(self, a: np.ndarray):
        import av
        from av.video.reformatter import ColorRange, Colorspace, Interpolation
        if self._container is None:
            self._container = av.open(str(self.stage / "video.mp4"), "w", format="mp4")
            s = self._container.add_stream("libx264", rate=Fraction(self.fps).limit_denominator(100000))
            s.width, s.height = a.shape[1], a.shape[0]
            s.pix_fmt = "yuv420p"
            s.options = {"crf": CRF, "preset": PRESET}
            cc = s.codec_context
            cc.colorspace, cc.color_range = Colorspace.ITU709, ColorRange.MPEG
            cc.color_primaries, cc.color_trc = 1, 13      # BT.709 primaries, sRGB curve
            self._stream = s
        rgb = av.VideoFrame.from_ndarray(a, format="rgb24")
        yuv = rgb.reformat(format="yuv420p", src_colorspace=Colorspace.ITU709,
                           dst_colorspace=Colorspace.ITU709, src_color_range=ColorRange.JPEG,
                           dst_color_range=ColorRange.MPEG,
                           interpolation=Interpolation.BILINEAR | Interpolation.ACCURATE_RND
                           | Interpolation.BITEXACT)
        yuv.pts = self.count
        for packet in self._stream.encode(yuv):
            self._container.mux(packet)

    # -- the end
    def _finish(self) -> list[tuple[Path, Path]]:
        """Close the encoder: [(staged file, destination)]."""
        if self.count == 0:
            raise ValueError("VideoWriter: no frames")
        if self.out.kind == "png":
            return [(self.stage / self.frame_name(k), self.out.video / self.frame_name(k))
                    for k in range(self.count)]
        staged = self.stage / f"video.{self.out.kind}"
        if self.out.kind == "mp4":
            for packet in self._stream.encode():
                self._container.mux(packet)
            self._container.close()
            self._container = None
        else:
            self._write_gif(staged)
        return [(staged, self.out.video)]

    def _write_gif(self, path: Path):
        # One palette for the whole clip, no dithering: per-frame palettes and dither
        # patterns would add a flicker of their own to a clip made to judge flicker.
        step = max(1, int(np.sqrt(len(self._gif) * self._gif[0][..., 0].size / 4e6)))
        sample = np.concatenate([f[::step, ::step] for f in self._gif], axis=0)
        palette = Image.fromarray(sample).quantize(colors=256, method=Image.Quantize.MEDIANCUT)
        frames = [Image.fromarray(f).quantize(palette=palette, dither=Image.Dither.NONE)
                  for f in self._gif]
        frames[0].save(path, format="GIF", save_all=True, append_images=frames[1:],
                       duration=gif_durations(len(frames), self.fps), loop=0, optimize=False)

    def commit(self, files: OutputSet | None = None):
        """Move the video into place with `files` (sidecar, metrics; made by
        VideoPaths.output_set): all or none. In a folder, the frames past this clip's end
        that a longer earlier hmblur clip wrote there go with it (no other file is
        touched)."""
        files = files or self.out.output_set()
        try:
            for staged, dest in self._finish():
                files.add(dest, lambda f, src=staged: _copy(src, f))
            if self.out.kind == "png":
                for name in OutputFolder(self.out.video, self.out.flag).owned_files():
                    m = FRAME.fullmatch(name)
                    if m and int(m.group(1)) >= self.count:
                        files.remove(self.out.video / name)
            files.commit()
        finally:
            self.abort()

    def abort(self):
        if self._container is not None:
            try:
                self._container.close()
            except Exception:
                pass
            self._container = None
        self._gif = []
        forget_partial(self.stage)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.abort()
        return False


def _copy(src: Path, f):
    with open(src, "rb") as s:
        shutil.copyfileobj(s, f, 1 << 20)
