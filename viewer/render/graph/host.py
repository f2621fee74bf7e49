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

from contextlib import contextmanager
from dataclasses import dataclass


@dataclass(frozen=True)
class HostResource:
    name: str
    type: type | tuple[type, ...]      # what a value must be (isinstance)
    help: str = ""
    optional: bool = False             # None is a value too ("not known this frame")

    def type_name(self) -> str:
        types = self.type if isinstance(self.type, tuple) else (self.type,)
        return " | ".join(t.__name__ for t in types) + (" | None" if self.optional else "")


class HostResources:
    """One frame's host resources, put by their producers (module doc)."""

    def __init__(self):
        self._values: dict[HostResource, object] = {}
        self._pass = None                  # the pass a pipeline is running, if any

    @contextmanager
    def opened_to(self, p):
        """While pass `p` runs: what it puts and gets is checked against its declarations."""
        before, self._pass = self._pass, p
        try:
            yield self
        finally:
            self._pass = before

    def put(self, res: HostResource, value) -> None:
        if self._pass is not None and res not in self._pass.host_outputs:
            raise RuntimeError(f"pass {self._pass.name} puts host resource {res.name}, "
                               f"which it does not declare in host_outputs")
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
        p = self._pass
        if p is not None and res not in p.host_inputs and res not in p.host_outputs:
            raise RuntimeError(f"pass {p.name} reads host resource {res.name}, which it "
                               f"does not declare in host_inputs")
