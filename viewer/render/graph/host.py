"""Host-side resources: what a pass computes on the CPU for later passes or for the
caller (tile lists, the masked pixels, the reveal's hits, the reference's regions),
declared like textures.

A HostResource is a name and a type. A pass lists those it makes in `host_outputs` and
those it reads in `host_inputs` (viewer/render/graph/passes.py); the Pipeline checks, when it
is built, that every one read is made by an earlier pass, and `describe()` shows each
with its producer and readers. Values live in the frame's HostResources (Frame.host),
which holds only declared resources of the declared type: while a pipeline runs a pass,
the pass may put only its outputs and get only what it declares. A pass run on its own
(outside a pipeline, as unit tests do) finds nothing it did not put: `get` answers the
default, and the pass does without (e.g. draws full screen instead of on tile lists).
"""
from __future__ import annotations

from dataclasses import dataclass

from .opened import OpenToPass


@dataclass(frozen=True)
class HostResource:
    name: str
    type: type | tuple[type, ...]      # what a value must be (isinstance)
    help: str = ""
    optional: bool = False             # None is a value too ("not known this frame")

    def type_name(self) -> str:
        types = self.type if isinstance(self.type, tuple) else (self.type,)
        return " | ".join(t.__name__ for t in types) + (" | None" if self.optional else "")


class HostResources(OpenToPass):
    """One frame's host resources, put by their producers (module doc)."""

    def __init__(self):
        super().__init__()
        self._values: dict[HostResource, object] = {}

    def put(self, res: HostResource, value) -> None:
        self._require((res,), lambda p: p.host_outputs, "puts host resource {}",
                      "host_outputs", lambda r: r.name)
        if not (isinstance(value, res.type) or value is None and res.optional):
            raise TypeError(f"host resource {res.name}: expected {res.type_name()}, "
                            f"got {type(value).__name__}")
        self._values[res] = value

    def get(self, res: HostResource, default=None):
        self._check_read(res)
        return self._values.get(res, default)

    def __getitem__(self, res: HostResource):
        self._check_read(res)
        try:
            return self._values[res]
        except KeyError:
            raise KeyError(f"host resource {res.name} was not produced this frame") from None

    def __contains__(self, res: HostResource) -> bool:
        return res in self._values

    def names(self) -> list[str]:
        return [r.name for r in self._values]

    def _check_read(self, res: HostResource):
        self._require((res,), lambda p: (*p.host_inputs, *p.host_outputs),
                      "reads host resource {}", "host_inputs", lambda r: r.name)
