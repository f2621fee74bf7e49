"""glTF 2.0 assets (scene format v1.2) read into plain numpy arrays, by concern as bevy_gltf
and three.js's GLTFLoader split them: the container (`.gltf`/`.glb`, buffers, data URIs,
files beside the asset; container.py), the accessors (accessors.py), typed access to the
JSON (document.py), the data model (model.py), the animation curves and their sampling
(curves.py), what an asset may hold (checks.py), and the reader that checks and
assembles them (reader.py, `load_gltf`); images decode through world/images.py.
Evaluating the node tree and skinning belong to the scene tree: world/gltf_scene.py and
world/skinning.py."""
from world.gltf.curves import GltfSampler, sample
from world.gltf.document import GltfError
from world.gltf.model import (GltfAnimation, GltfAsset, GltfChannel, GltfMaterial, GltfNode,
                              GltfPart, GltfSkin)
from world.gltf.reader import load_gltf

__all__ = ["GltfError", "GltfAsset", "GltfMaterial", "GltfPart", "GltfNode", "GltfSkin",
           "GltfSampler", "GltfChannel", "GltfAnimation", "load_gltf", "sample"]
