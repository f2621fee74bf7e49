"""CPU ray tracer for the hybrid mode: Embree geometry queries, shading left to the GPU.

RayScene is built once per loaded scene; `reveal` casts the masked pixels' rays at a time t
and returns, per revealed layer, the ids, barycentrics and local attributes the deferred
shader needs to shade the revealed surface exactly as the rasteriser shades it.
"""
from .attributes import LocalSurface, barycentric_weights, local_surface
from .embree_scene import Hits, RayScene
from .reveal import RevealLayer, RevealResult, reveal

__all__ = ["Hits", "LocalSurface", "RayScene", "RevealLayer", "RevealResult",
           "barycentric_weights", "local_surface", "reveal"]
