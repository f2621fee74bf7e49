"""Reading a glTF 2.0 asset (scene format v1.2): `load_gltf` reads a `.gltf` (embedded or
external buffers and images) or a `.glb`, checks everything the format relies on once,
and raises nothing but GltfError (one line naming the asset item, e.g. `accessors[3]:
...`; the scene loader prefixes file and entry). After a successful load, evaluation
(world.gltf.sample, world/gltf_scene.py's NodeTree, world/skinning.py) never raises for
the asset's own data.

glTF's (x, y, z, w) quaternions become (w, x, y, z) here, as they are read: node
rotations and the keys of rotation samplers (STEP and LINEAR keys normalised as well).

What the scene loader does with it (SCENE_FORMAT.md, v1.2): one object per
`mesh_nodes()` entry, in that order; M(t) = P(t) @ World(node, t), with
a = animation_time(t, ...); a skinned node draws its skinned vertices and P(t) only (its
own World is not applied); `ignored` is printed once.

Sizes are bounded before anything is allocated (world/limits.py), so that a small
hostile file cannot make the program allocate gigabytes: file sizes, decoded accessor
components, the objects, triangles and vertices the scene draws (checks.py, before a
mesh is read), nodes, joints, names, image pixels (world/images.py, the scene's images
together). Numbers are finite and in range where they enter (document.numbers, within).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib as G

from world import images, limits
from world import transforms as tf
from world.gltf import checks
from world.gltf.accessors import FLOATISH, Accessors
from world.gltf.container import Container, read_document
from world.gltf.curves import INTERPOLATIONS, GltfSampler
from world.gltf.document import (GltfError, array, fail, integer, is_int, kept, name, numbers,
                                 obj, ref, show, string, within)
from world.gltf.model import (GltfAnimation, GltfAsset, GltfChannel, GltfMaterial, GltfNode,
                              GltfPart, GltfSkin, walk)

TRS_PATHS = ("translation", "rotation", "scale")
WXYZ = [3, 0, 1, 2]                    # glTF's (x, y, z, w) -> (w, x, y, z)
_FLOAT_MAX = float(np.finfo(np.float64).max)     # (a bound that lets every finite value by)

# Required extensions this reader can honour by ignoring them (the format ignores what they
# add: material models, lights, texture transforms) or by decoding them (quantized
# attributes are ordinary normalized/integer accessors here).
_TOLERATED_REQUIRED = ("KHR_mesh_quantization", "KHR_lights_punctual", "KHR_texture_transform",
                       "KHR_materials_variants", "KHR_xmp_json_ld")


def _check_depth(doc) -> None:
    stack = [(doc, 0)]
    while stack:
        v, d = stack.pop()
        if d > limits.MAX_GLTF_JSON_DEPTH:
            fail(f"JSON nested more than {limits.MAX_GLTF_JSON_DEPTH} levels deep")
        if isinstance(v, dict):
            stack.extend((x, d + 1) for x in v.values())
        elif isinstance(v, list):
            stack.extend((x, d + 1) for x in v)


class _Reader:
    """One asset's reading: the document and its top-level arrays checked on construction,
    the asset built by load()."""

    def __init__(self, path: Path, scene_images: images.SceneImages | None = None):
        self.path = Path(path)
        self.scene_images = images.SceneImages() if scene_images is None else scene_images
        self.ignored: list[str] = []
        self.doc, glb_bin = read_document(self.path)
        doc = self.doc
        _check_depth(doc)
        asset = obj(doc.get("asset"), "asset") if "asset" in doc else fail("missing asset")
        version = asset.get("version")
        if version != "2.0":
            fail(f"asset.version is {show(version)}, expected exactly \"2.0\"")
        self.extensions()
        for key in ("buffers", "bufferViews", "accessors", "meshes", "materials", "textures",
                    "images", "skins", "animations", "nodes", "scenes", "cameras", "samplers"):
            if key in doc and not isinstance(doc[key], list):
                fail(f"{key}: expected an array")
            if len(doc.get(key, [])) > limits.MAX_GLTF_ITEMS:
                fail(f"{key}: {len(doc[key])} entries, more than the limit of {limits.MAX_GLTF_ITEMS}")
        self.container = Container(self.path, doc, glb_bin)
        self.accessors = Accessors(self.container, doc)
        self.images = [obj(b, f"images[{i}]") for i, b in enumerate(doc.get("images", []))]
        self.textures = [obj(b, f"textures[{i}]") for i, b in enumerate(doc.get("textures", []))]
        self._decoded_images: dict[int, np.ndarray] = {}
        if doc.get("cameras"):
            self.ignore("cameras")

    def ignore(self, what: str) -> None:
        if what not in self.ignored:
            self.ignored.append(what)

    def entries(self, key: str):
        """(index, "key[index]", the JSON object) of each entry of the top-level array `key`."""
        for i, item in enumerate(self.doc.get(key, [])):
            where = f"{key}[{i}]"
            yield i, where, obj(item, where)

    def accessor(self, i: int, where_used: str, types=None, components=None,
                 normalized_ok=True) -> np.ndarray:
        return self.accessors.get(i, where_used, types, components, normalized_ok)

    def load(self) -> GltfAsset:
        nodes = self.nodes()
        roots = self.scene(nodes)
        for key in ("mesh", "skin"):
            n = len(self.doc.get(f"{key}es" if key == "mesh" else f"{key}s", []))
            for nd in nodes:
                i = getattr(nd, key)
                if i is not None and i >= n:
                    fail(f"nodes[{nd.index}].{key}: {i} is not an index of {key}"
                         f"{'es' if key == 'mesh' else 's'} ({n} entries)")
        checks.check_drawn(self.doc, self.accessors.items, nodes, roots)
        materials = self.materials()
        meshes = self.meshes(len(materials))
        skins = self.skins(len(nodes))
        animations = self.animations(nodes)
        asset = GltfAsset(self.path, nodes, meshes, materials, skins, animations, roots, self.ignored)
        checks.check_skins(asset)
        checks.check_reach(asset)
        return asset

    def extensions(self) -> None:
        used = self.doc.get("extensionsUsed", [])
        req = self.doc.get("extensionsRequired", [])
        for key, v in (("extensionsUsed", used), ("extensionsRequired", req)):
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                fail(f"{key}: expected an array of strings")
        for name in req:
            if name in ("KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression"):
                fail(f"extensionsRequired: {name} (compressed geometry) is not supported")
            if not (name.startswith("KHR_materials_") or name in _TOLERATED_REQUIRED):
                fail(f"extensionsRequired: {name} is not supported")
        for name in list(used) + list(req):
            if name.startswith("KHR_materials_"):
                self.ignore("KHR_materials_* extensions")
            elif name == "KHR_mesh_quantization":
                pass
            else:
                self.ignore(name)

    # -- nodes and the scene

    def nodes(self) -> list[GltfNode]:
        raw = self.doc.get("nodes", [])
        if len(raw) > limits.MAX_GLTF_NODES:
            fail(f"nodes: {len(raw)} nodes, more than the limit of {limits.MAX_GLTF_NODES}")
        n = len(raw)
        out: list[GltfNode] = []
        parent: list[int | None] = [None] * n
        for i, nd in enumerate(raw):
            where = f"nodes[{i}]"
            obj(nd, where)
            node_name = name(nd, where, f"node{i}")
            children = array(nd, "children", where)
            for c in children:
                if not is_int(c) or not 0 <= c < n:
                    fail(f"{where}.children: {show(c)} is not an index of nodes ({n} entries)")
                if c == i:
                    fail(f"{where}.children: the node is its own child")
                if parent[c] is not None:
                    fail(f"nodes[{c}] has two parents (nodes[{parent[c]}] and nodes[{i}])")
                parent[c] = i
            matrix = None
            if "matrix" in nd:
                m = numbers(nd, "matrix", where, 16, None)
                matrix = m.reshape(4, 4).T.copy()          # column-major in the file
            t = numbers(nd, "translation", where, 3, [0.0, 0.0, 0.0])
            r = numbers(nd, "rotation", where, 4, [0.0, 0.0, 0.0, 1.0])
            nr = float(np.sqrt(r @ r))
            if nr == 0.0:
                fail(f"{where}.rotation: a zero quaternion")
            r = (r / nr)[WXYZ]
            s = numbers(nd, "scale", where, 3, [1.0, 1.0, 1.0])
            mesh = integer(nd, "mesh", where, None)
            skin = integer(nd, "skin", where, None)
            if "camera" in nd:
                self.ignore("cameras")
            if "weights" in nd:
                self.ignore("morph target weights")
            out.append(GltfNode(i, node_name, None, [int(c) for c in children], matrix, t, r, s, mesh, skin))
        for i, p in enumerate(parent):
            out[i].parent = p
        # cycles: with one parent each, the nodes on (or below) a cycle are exactly those
        # that a walk down from the parentless nodes never reaches
        reached = set(walk(out, [i for i in range(n) if parent[i] is None]))
        if len(reached) < n:
            fail(f"nodes[{min(set(range(n)) - reached)}]: the node graph has a cycle")
        return out

    def scene(self, nodes: list[GltfNode]) -> list[int]:
        scenes = self.doc.get("scenes", [])
        if "scene" in self.doc:
            s = ref(self.doc, "scene", "scene", scenes, "scenes")
            where = f"scenes[{s}]"
        elif scenes:
            s, where = 0, "scenes[0]"
        else:
            return [nd.index for nd in nodes if nd.parent is None]
        sc = obj(scenes[s], where)
        roots, listed = [], set()
        for r in array(sc, "nodes", where):
            if not is_int(r) or not 0 <= r < len(nodes):
                fail(f"{where}.nodes: {show(r)} is not an index of nodes ({len(nodes)} entries)")
            if nodes[r].parent is not None:
                fail(f"{where}.nodes: nodes[{r}] is not a root (its parent is nodes[{nodes[r].parent}])")
            if nodes[r].index in listed:
                fail(f"{where}.nodes: nodes[{r}] listed twice")
            listed.add(nodes[r].index)
            roots.append(int(r))
        return roots

    # -- materials and images

    def materials(self) -> list[GltfMaterial]:
        out = []
        for i, where, m in self.entries("materials"):
            material_name = name(m, where, f"material{i}")
            pbr = obj(m.get("pbrMetallicRoughness", {}), f"{where}.pbrMetallicRoughness")
            color = numbers(pbr, "baseColorFactor", f"{where}.pbrMetallicRoughness", 4, [1.0, 1.0, 1.0, 1.0])
            image = None
            if "baseColorTexture" in pbr:
                ti = obj(pbr["baseColorTexture"], f"{where}.pbrMetallicRoughness.baseColorTexture")
                t = ref(ti, "index", f"{where}.pbrMetallicRoughness.baseColorTexture",
                         self.textures, "textures", required=True)
                tex = self.textures[t]
                src = ref(tex, "source", f"textures[{t}]", self.images, "images")
                if src is None:
                    self.ignore("textures without a core image source")
                else:
                    image = self.image(src)
            for key, what in (("normalTexture", "normal textures"), ("emissiveTexture", "emissive"),
                              ("occlusionTexture", "occlusion textures")):
                if key in m:
                    self.ignore(what)
            if "metallicRoughnessTexture" in pbr:
                self.ignore("metallic-roughness textures")
            if m.get("alphaMode", "OPAQUE") != "OPAQUE" or (color[3] != 1.0):
                self.ignore("alpha")
            if isinstance(m.get("extensions"), dict) and m["extensions"]:
                self.ignore("KHR_materials_* extensions")
            out.append(GltfMaterial(color, image, material_name))
        return out

    def image(self, i: int) -> np.ndarray:
        return kept(self._decoded_images, i, lambda: self._decode(i))

    def _decode(self, i: int) -> np.ndarray:
        im, where = self.images[i], f"images[{i}]"
        if "uri" in im:
            data = self.container.external(string(im, "uri", where), where)
        elif "bufferView" in im:
            vi = ref(im, "bufferView", where, self.container.views, "bufferViews", required=True)
            data = self.container.view_bytes(vi)
        else:
            fail(f"{where}: neither uri nor bufferView")
        try:
            return self.scene_images.from_bytes(data, ("PNG", "JPEG"))
        except images.ImageError as e:
            raise GltfError(f"{where}: {e}") from None

    # -- meshes

    def meshes(self, n_materials: int) -> list[list[GltfPart]]:
        out = []
        for mi, where, m in self.entries("meshes"):
            prims = array(m, "primitives", where, required=True)
            if not prims:
                fail(f"{where}.primitives: empty")
            if "weights" in m:
                self.ignore(f"morph targets ({where})")
            parts = [self.primitive(obj(p, f"{where}.primitives[{k}]"), f"{where}.primitives[{k}]",
                                    n_materials, mi) for k, p in enumerate(prims)]
            out.append(parts)
        return out

    def primitive(self, p: dict, where: str, n_materials: int, mi: int) -> GltfPart:
        mode = p.get("mode", G.TRIANGLES)
        if mode != G.TRIANGLES or not is_int(mode):
            fail(f"{where}: primitives must be triangles (mode 4), this one has mode {show(mode)}")
        attrs = obj(p.get("attributes"), f"{where}.attributes") if "attributes" in p else fail(f"{where}: missing attributes")
        if "targets" in p:
            self.ignore(f"morph targets (meshes[{mi}])")
        for k in attrs:
            if k.startswith("COLOR_"):
                self.ignore("vertex colours")
        pos = self.attribute(attrs, "POSITION", where, ("VEC3",), None)
        if pos is None:
            fail(f"{where}.attributes: no POSITION")
        n = pos.shape[0]
        pos = within(pos.astype(np.float64, copy=False), f"{where}.attributes.POSITION")   # (quantized: ints)

        def same_count(arr, name):
            if arr is not None and arr.shape[0] != n:
                fail(f"{where}.attributes.{name}: {arr.shape[0]} elements, POSITION has {n}")
            if arr is not None and arr.dtype == np.float64 and not np.isfinite(arr).all():
                fail(f"{where}.attributes.{name}: non-finite values")
            return arr

        nrm = same_count(self.attribute(attrs, "NORMAL", where, ("VEC3",), (G.FLOAT, G.BYTE, G.SHORT), True), "NORMAL")
        uv = same_count(self.attribute(attrs, "TEXCOORD_0", where, ("VEC2",), FLOATISH, None), "TEXCOORD_0")
        if uv is not None:
            uv = within(uv.astype(np.float64, copy=False), f"{where}.attributes.TEXCOORD_0")
        joints = weights = None
        for s in ("0", "1"):
            j = same_count(self.attribute(attrs, f"JOINTS_{s}", where, ("VEC4",),
                                          (G.UNSIGNED_BYTE, G.UNSIGNED_SHORT), False), f"JOINTS_{s}")
            w = same_count(self.attribute(attrs, f"WEIGHTS_{s}", where, ("VEC4",),
                                          (G.FLOAT, G.UNSIGNED_BYTE, G.UNSIGNED_SHORT), True), f"WEIGHTS_{s}")
            if (j is None) != (w is None):
                fail(f"{where}.attributes: JOINTS_{s} and WEIGHTS_{s} must come together")
            if j is None:
                break
            if (w < 0.0).any():
                fail(f"{where}.attributes.WEIGHTS_{s}: a negative weight at vertex "
                     f"{int(np.nonzero((w < 0.0).any(axis=1))[0][0])} (weights are >= 0)")
            joints = j if joints is None else np.concatenate([joints, j], axis=1)
            weights = w if weights is None else np.concatenate([weights, w], axis=1)
        faces = self.faces(p, where, n)
        mat = ref(p, "material", where, range(n_materials), "materials")
        part = GltfPart(pos, nrm, uv, faces, joints, weights, mat)
        for arr in (pos, nrm, uv, faces, joints, weights):
            if arr is not None:
                arr.flags.writeable = False
        return part

    def attribute(self, attrs: dict, name: str, where: str, types, comps, norm_ok=None):
        """The decoded accessor of attribute `name`, None where the primitive has none."""
        if name not in attrs:
            return None
        i = ref(attrs, name, f"{where}.attributes", self.accessors.items, "accessors")
        return self.accessor(i, f"{where}.attributes.{name}", types, comps, norm_ok)

    def faces(self, p: dict, where: str, n: int) -> np.ndarray:
        """(m, 3) int64: the indices in threes, or without indices the vertices in order."""
        if "indices" not in p:
            if n % 3:
                fail(f"{where}: {n} vertices without indices, not a multiple of 3")
            return np.arange(n, dtype=np.int64).reshape(-1, 3)
        ii = ref(p, "indices", where, self.accessors.items, "accessors")
        idx = self.accessor(ii, f"{where}.indices", ("SCALAR",),
                            (G.UNSIGNED_BYTE, G.UNSIGNED_SHORT, G.UNSIGNED_INT), False)[:, 0]
        if idx.size % 3:
            fail(f"{where}.indices: {idx.size} indices, not a multiple of 3")
        if idx.size and int(idx.max()) >= n:
            fail(f"{where}.indices: index {int(idx.max())} out of range of the {n} vertices")
        return idx.reshape(-1, 3)

    # -- skins

    def skins(self, n_nodes: int) -> list[GltfSkin]:
        out = []
        for si, where, s in self.entries("skins"):
            joints = array(s, "joints", where, required=True)
            if not joints:
                fail(f"{where}.joints: a skin with no joints")
            if len(joints) > limits.MAX_GLTF_JOINTS:
                fail(f"{where}.joints: {len(joints)} joints, more than the limit of {limits.MAX_GLTF_JOINTS}")
            for j in joints:
                if not is_int(j) or not 0 <= j < n_nodes:
                    fail(f"{where}.joints: {show(j)} is not an index of nodes ({n_nodes} entries)")
            if len(set(joints)) != len(joints):
                fail(f"{where}.joints: a node listed twice")
            J = len(joints)
            if "inverseBindMatrices" in s:
                ai = ref(s, "inverseBindMatrices", where, self.accessors.items, "accessors")
                m = self.accessor(ai, f"{where}.inverseBindMatrices", ("MAT4",), (G.FLOAT,))
                if m.shape[0] < J:
                    fail(f"{where}.inverseBindMatrices: {m.shape[0]} matrices for {J} joints")
                within(m[:J], f"{where}.inverseBindMatrices")
                ibm = m[:J].reshape(J, 4, 4).transpose(0, 2, 1).copy()
            else:
                ibm = np.tile(np.eye(4), (J, 1, 1))
            if "skeleton" in s:
                ref(s, "skeleton", where, range(n_nodes), "nodes")
            out.append(GltfSkin([int(j) for j in joints], ibm))
        return out

    # -- animations

    def animations(self, nodes: list[GltfNode]) -> list[GltfAnimation]:
        out = []
        for ai, where, an in self.entries("animations"):
            animation_name = name(an, where, f"animation{ai}")
            samplers = [obj(s, f"{where}.samplers[{k}]") for k, s in enumerate(array(an, "samplers", where))]
            times: dict[int, np.ndarray] = {}
            for k, s in enumerate(samplers):
                times[k] = self.key_times(s, f"{where}.samplers[{k}]")
            span = None
            if times:
                span = (min(float(t[0]) for t in times.values()), max(float(t[-1]) for t in times.values()))
            built: dict[tuple[int, str], GltfSampler] = {}
            channels = []
            for c, ch in enumerate(array(an, "channels", where)):
                cw = f"{where}.channels[{c}]"
                obj(ch, cw)
                k = ref(ch, "sampler", cw, samplers, f"{where}.samplers", required=True)
                tgt = obj(ch.get("target"), f"{cw}.target") if "target" in ch else fail(f"{cw}: missing target")
                path = tgt.get("path")
                if path not in TRS_PATHS + ("weights",):
                    if isinstance(path, str) and path:
                        self.ignore(f"{path} channels")
                        continue
                    fail(f"{cw}.target.path: {show(path)} is not translation, rotation, scale or weights")
                node = ref(tgt, "node", f"{cw}.target", nodes, "nodes")
                if path == "weights":
                    self.ignore("weights channels")
                    continue
                if node is None:                    # targeted through an extension: ignored
                    continue
                if (k, path) not in built:
                    built[(k, path)] = self.sampler(samplers[k], times[k], path, f"{where}.samplers[{k}]")
                channels.append(GltfChannel(node, path, built[(k, path)]))
            out.append(GltfAnimation(animation_name, channels, span))
        return out

    def key_times(self, s: dict, where: str) -> np.ndarray:
        i = ref(s, "input", where, self.accessors.items, "accessors", required=True)
        t = self.accessor(i, f"{where}.input", ("SCALAR",), (G.FLOAT,))
        t = within(t[:, 0], f"{where}.input", "key times", limits.MAX_TIME)
        if t.size > 1 and not (np.diff(t) > 0).all():
            k = int(np.nonzero(~(np.diff(t) > 0))[0][0])
            fail(f"{where}.input: key times not strictly increasing (key {k + 1}: {float(t[k + 1])!r} after {float(t[k])!r})")
        return t

    def sampler(self, s: dict, times: np.ndarray, path: str, where: str) -> GltfSampler:
        interp = s.get("interpolation", "LINEAR")
        if interp not in INTERPOLATIONS:
            fail(f"{where}.interpolation: {show(interp)} is not STEP, LINEAR or CUBICSPLINE")
        o = ref(s, "output", where, self.accessors.items, "accessors", required=True)
        c = 4 if path == "rotation" else 3
        comps = (G.FLOAT, G.BYTE, G.UNSIGNED_BYTE, G.SHORT, G.UNSIGNED_SHORT) if path == "rotation" else (G.FLOAT,)
        v = self.accessor(o, f"{where}.output", (f"VEC{c}",), comps, True)
        n = times.shape[0]
        per = 3 if interp == "CUBICSPLINE" else 1
        if v.shape[0] != per * n:
            fail(f"{where}: {n} key times but {v.shape[0]} output values "
                  f"(expected {per * n} for {interp})")
        # (a rotation's length is normalised away: finite is enough)
        within(v, f"{where}.output", "key values", _FLOAT_MAX if path == "rotation" else limits.MAX_SCENE_NUMBER)
        if interp == "CUBICSPLINE":
            v = v.reshape(n, 3, c)
            if path == "rotation" and not (np.einsum("ij,ij->i", v[:, 1], v[:, 1]) > 0).all():
                fail(f"{where}.output: a zero rotation quaternion")
        elif path == "rotation" and not (np.einsum("ij,ij->i", v, v) > 0).all():
            fail(f"{where}.output: a zero rotation quaternion")
        if path == "rotation":             # keys normalised (not tangents), then reordered
            v = (v if interp == "CUBICSPLINE" else tf.quat_normalised(v))[..., WXYZ]
        return GltfSampler(times, v, interp)


def load_gltf(path, scene_images: images.SceneImages | None = None) -> GltfAsset:
    """Read and check a .gltf or .glb; GltfError (one line) for anything malformed. Its
    images are decoded by `scene_images` (the scene's: shared with its other images and
    counted against its limit), else by a SceneImages of their own."""
    try:
        return _Reader(Path(path), scene_images).load()
    except GltfError:
        raise
    except MemoryError:
        raise GltfError("out of memory while reading the asset") from None
    except RecursionError:
        raise GltfError("the asset is nested too deeply") from None
    except Exception as e:                       # a safety net: never anything but GltfError
        raise GltfError(f"malformed asset ({type(e).__name__}: {str(e)[:100]})") from None
