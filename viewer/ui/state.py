"""What the viewer shows, as plain data: the panel edits it, scripts set it, the main loop
renders from it."""
from __future__ import annotations

import json
from dataclasses import dataclass, field

from viewer.io.sidecar import camera_dict
from viewer.render.graph.params import ParamSet
from viewer.render.passes.debug_view import ViewSettings
from ..render.modes import MODE_GROUPS
from world.scene import Scene

FIXED_STEP = 1.0 / 60.0          # seconds per frame when playing a scripted run


@dataclass
class ViewState:
    scene_arg: str                 # what the user typed: a path or a built-in name
    scene: Scene
    mode: str
    time: float
    params: ParamSet
    seed: int = 0
    playing: bool = False
    speed: float = 1.0
    buffer: str = ""               # pool texture shown; "" = the mode's output
    view: ViewSettings = field(default_factory=ViewSettings)
    sub_frames: int = 2            # progressive sub-frames per displayed frame
    show_panel: bool = True
    overlay: str = "full"          # overlay level: full, compact or off (ui/overlay.py)
    scene_text: str = ""           # the panel's "open scene" field
    error: str = ""                # shown in the panel until dismissed
    errors: list = field(default_factory=list)   # every distinct error, for --stats-json
    shots: list = field(default_factory=list)    # screenshot paths written
    animations: dict = field(default_factory=dict)   # {gltf entry: animation} chosen here

    def report(self, message: str):
        message = " ".join(str(message).split()) or "unknown error"
        self.error = message
        if message not in self.errors:
            self.errors.append(message)

    def image_key(self, size: tuple[int, int]) -> str:
        """Everything the image depends on, as one string: a change restarts a progressive
        accumulation."""
        return json.dumps({
            "scene": id(self.scene), "mode": self.mode, "time": self.time, "seed": self.seed,
            "size": list(size), "camera": camera_dict(self.scene.camera),
            "params": self.params.to_dict(MODE_GROUPS.get(self.mode, ())),
        }, sort_keys=True, default=str)
