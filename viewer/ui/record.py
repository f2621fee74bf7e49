"""Recording what the viewer animates: the scene image as shown in the window (the chosen
buffer through the debug view; no panel, no overlay), one frame per displayed frame, to
the formats of `hmblur video` through the same writer. While recording, a playing
animation advances by exactly 1 / fps per displayed frame, so the recording plays at the
speed of the scene however long each frame took to render."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from viewer.io.sidecar import camera_dict
from viewer.cli import args as cliargs
from viewer.io.video_writer import VideoPaths, VideoWriter, video_paths


def next_path(folder: Path, stem: str) -> Path:
    """folder/stem_NNN.mp4 with the first number not taken."""
    k = 0
    while (folder / f"{stem}_{k:03d}.mp4").exists():
        k += 1
    return folder / f"{stem}_{k:03d}.mp4"


class Recorder:
    def __init__(self, out: VideoPaths, fps: float, state, size: tuple[int, int]):
        """`state`: the viewer's ViewState at the first frame (what the sidecar records)."""
        self.out, self.fps, self.size = out, float(fps), tuple(size)
        self.writer = VideoWriter(out, fps)
        self.start = self.side = None
        self._state_at_start(state)

    @classmethod
    def open(cls, path: str, fps: float, state, size, flag: str = "--record") -> "Recorder":
        return cls(video_paths(path, flag), fps, state, size)

    def _state_at_start(self, s):
        self.side = {
            **cliargs.scene_source(s.scene_arg), "scene_name": s.scene.name,
            **({"animations": dict(s.animations)} if s.animations else {}),
            "modes": [s.mode], "fps": self.fps, "size": list(self.size),
            "seed": s.seed, "params": s.params.to_dict(), "camera": camera_dict(s.scene.camera),
            "format": self.out.kind,
            "viewer": {"buffer": s.buffer or "output", "speed": s.speed, "playing": s.playing},
        }

    @property
    def step(self) -> float:
        return 1.0 / self.fps

    def add(self, frame: np.ndarray, t: float) -> bool:
        """Append the frame shown for time `t`; False (nothing added) when the window's
        size has changed."""
        if (frame.shape[1], frame.shape[0]) != self.size:
            return False
        if self.writer.count == 0:
            self.side["time"] = t          # the first frame's, as `hmblur video` counts
        self.writer.add(frame)
        return True

    def stop(self) -> Path | None:
        """Write the video and its sidecar (none for a recording of no frames)."""
        if self.writer.count == 0:
            self.writer.abort()
            return None
        self.side["frames"] = self.writer.count
        files = self.out.output_set()
        files.json(self.out.beside("", ".json"), self.side)
        self.writer.commit(files)
        return self.out.video

    def abort(self):
        self.writer.abort()
