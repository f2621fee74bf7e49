"""What a pipeline opens to the pass it runs: the pool's textures (pool.py) and the frame's
host resources (host.py). While open to a pass, each access is checked against what the
pass declares; outside a pipeline (a pass run on its own, the caller reading results)
nothing is checked."""
from __future__ import annotations

from contextlib import contextmanager


class OpenToPass:
    def __init__(self):
        self._pass = None                  # the pass a pipeline is running, if any

    @contextmanager
    def opened_to(self, p):
        """While pass `p` runs: what it touches is checked against its declarations."""
        before, self._pass = self._pass, p
        try:
            yield self
        finally:
            self._pass = before

    def _require(self, items, declared, doing: str, where: str, label=str):
        """Raise where the open pass touches one of `items` that declared(pass) does not
        hold: 'pass P <doing with the items' labels>, which it does not declare in
        <where>'."""
        p = self._pass
        if p is None:
            return
        allowed = declared(p)
        bad = [label(i) for i in items if i not in allowed]
        if bad:
            raise RuntimeError(f"pass {p.name} {doing.format(', '.join(bad))}, which it "
                               f"does not declare in {where}")
