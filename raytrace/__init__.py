"""CPU ray tracer for the hybrid mode: Embree geometry queries, shading left to the GPU.

RayScene is built once per loaded scene; `reveal` casts the masked pixels' rays at a time t
and returns the revealed surface's object ids, faces and barycentrics, from which the
deferred shader shades it exactly as the rasteriser shades it.
"""
from .embree_scene import Hits, RayScene
from .reveal import RevealLayer, RevealResult, reveal

__all__ = ["Hits", "RayScene", "RevealLayer", "RevealResult", "reveal"]
