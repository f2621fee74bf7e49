"""glTF 2.0 assets (scene format v1.2) read into plain numpy arrays."""
from world.gltf.reader import (GltfAnimation, GltfAsset, GltfChannel, GltfError, GltfMaterial,
                               GltfNode, GltfPart, GltfSampler, GltfSkin, load_gltf, sample,
                               skin_vertices)

__all__ = ["GltfError", "GltfAsset", "GltfMaterial", "GltfPart", "GltfNode", "GltfSkin",
           "GltfSampler", "GltfChannel", "GltfAnimation", "load_gltf", "sample", "skin_vertices"]
