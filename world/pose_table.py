"""The poses a frame reads at many times, evaluated once: every node's world matrix
M(t_k) for the table's times, each node evaluated once per time whatever hangs from it
(a rotor's matrix once for its four blades), from the scene tree (docs/architecture.md,
"The scene tree")."""
from __future__ import annotations

import numpy as np

from world.gltf_scene import AssetInstance, AssetNode


class PoseTable:
    """World matrices of the scene's nodes at `times`, made as they are asked for."""

    def __init__(self, times):
        self.times = tuple(float(t) for t in times)
        self._worlds: dict[int, tuple[object, np.ndarray]] = {}
        self._assets: dict[int, tuple[AssetInstance, np.ndarray]] = {}

    def world(self, node) -> np.ndarray:
        """(len(times), 4, 4) M(t_k) of a placement, object or glTF node (read-only)."""
        kept = self._worlds.get(id(node))
        if kept is None:
            w = self._evaluate(node)
            w.flags.writeable = False
            kept = self._worlds[id(node)] = (node, w)       # (the node kept: its id stays its)
        return kept[1]

    def _evaluate(self, node) -> np.ndarray:
        if isinstance(node, AssetNode):
            root = self.world(node.instance.root)
            if node.skinned:                     # (glTF: a skinned node's own World is not applied)
                return root.copy()
            return root @ self._asset(node.instance)[:, node.index]
        if node.own_moving:
            own = node.own_matrices(self.times)
        else:
            own = np.broadcast_to(node.own_matrix(self.times[0]), (len(self.times), 4, 4))
        return own.copy() if node.parent is None else self.world(node.parent) @ own

    def _asset(self, instance: AssetInstance) -> np.ndarray:
        """(len(times), N, 4, 4) every node's World in the asset's space."""
        kept = self._assets.get(id(instance))
        if kept is None:
            kept = self._assets[id(instance)] = (
                instance, np.stack([instance.worlds(t) for t in self.times]))
        return kept[1]
