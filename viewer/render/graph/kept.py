"""State kept from frame to frame: what passes build once and reuse (the Embree scene,
tile lists' vertex buffers, the static objects' raster), in one object that the Renderer
owns, gives to each of its frames (Frame.kept) and releases with itself.

Each piece is a KeptSlot (a name and a type) declared by the module that uses it; a
value is checked against its slot's type when put. Values are keyed by what they were
made from (the scene, the context, matrices, views), never by a frame's time, so any
frame, a sub-exposure step's too, finds them correct.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class KeptSlot:
    name: str
    type: type
    help: str = ""


class KeptState:
    def __init__(self):
        self._values: dict[KeptSlot, object] = {}

    def get(self, slot: KeptSlot):
        """The slot's value, or None before the first put."""
        return self._values.get(slot)

    def get_or_make(self, slot: KeptSlot, make, fits=None):
        """The slot's value; made by make() and kept where there is none yet, or where
        fits(value) is false (it was made for another scene or context)."""
        value = self.get(slot)
        if value is None or fits is not None and not fits(value):
            value = self.put(slot, make())
        return value

    def put(self, slot: KeptSlot, value):
        """Keep `value` in `slot` (releasing what it held); returns value."""
        if not isinstance(value, slot.type):
            raise TypeError(f"kept state {slot.name}: expected {slot.type.__name__}, "
                            f"got {type(value).__name__}")
        old = self._values.get(slot)
        if old is not None and old is not value and hasattr(old, "release"):
            old.release()
        self._values[slot] = value
        return value

    def names(self) -> list[str]:
        return [s.name for s in self._values]

    def items(self) -> list[tuple[str, object]]:
        return [(s.name, v) for s, v in self._values.items()]

    def release(self):
        for value in self._values.values():
            if hasattr(value, "release"):
                value.release()
        self._values.clear()
