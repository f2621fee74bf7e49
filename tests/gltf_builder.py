"""Tiny glTF 2.0 assets built by hand for tests/test_gltf.py: a JSON document and one binary
buffer assembled with numpy, written as .gltf (base64 data URI or external .bin) or .glb."""
from __future__ import annotations

import base64
import copy
import json
import struct
from pathlib import Path

import numpy as np

BYTE, UBYTE, SHORT, USHORT, UINT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
_DTYPE = {BYTE: "<i1", UBYTE: "<u1", SHORT: "<i2", USHORT: "<u2", UINT: "<u4", FLOAT: "<f4"}
_NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.doc: dict = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [],
                          "accessors": []}

    # -- binary data

    def view(self, data: bytes, stride: int | None = None) -> int:
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride is not None:
            v["byteStride"] = stride
        self.bin.extend(data)
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, ctype: int = FLOAT, atype: str | None = None,
                 normalized: bool = False, **extra) -> int:
        """An accessor over a new, tightly packed bufferView holding `values`."""
        arr = np.asarray(values)
        if arr.ndim == 1:
            arr = arr[:, None]
        atype = atype or ("SCALAR" if arr.shape[1] == 1 else f"VEC{arr.shape[1]}")
        view = self.view(arr.astype(_DTYPE[ctype]).tobytes())
        acc = {"bufferView": view, "componentType": ctype, "count": int(arr.shape[0]), "type": atype}
        if normalized:
            acc["normalized"] = True
        acc.update(extra)
        return self.add_accessor(acc)

    def add_accessor(self, acc: dict) -> int:
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    # -- structure

    def add(self, key: str, item: dict) -> int:
        self.doc.setdefault(key, []).append(item)
        return len(self.doc[key]) - 1

    def triangle_mesh(self, positions, faces=None, **attrs) -> int:
        """A mesh of one primitive: POSITION (float), optional indices, extra attributes
        given as accessor indices."""
        a = {"POSITION": self.accessor(np.asarray(positions, dtype=np.float32))}
        a.update(attrs)
        prim = {"attributes": a}
        if faces is not None:
            prim["indices"] = self.accessor(np.asarray(faces).reshape(-1), USHORT)
        return self.add("meshes", {"primitives": [prim]})

    # -- output

    def _doc_with_buffer(self, uri: str | None) -> dict:
        doc = copy.deepcopy(self.doc)
        buf = {"byteLength": len(self.bin)}
        if uri is not None:
            buf["uri"] = uri
        if self.bin:
            doc["buffers"] = [buf]
        else:
            doc.pop("buffers")
            doc.pop("bufferViews")
        return doc

    def gltf_dict(self) -> dict:
        return self._doc_with_buffer("data:application/octet-stream;base64,"
                                     + base64.b64encode(bytes(self.bin)).decode())

    def write(self, folder: Path, name: str = "asset.gltf", external: str | None = None) -> Path:
        """A .gltf with the buffer embedded, or in the file `external` (relative URI)."""
        folder = Path(folder)
        if external is None:
            doc = self.gltf_dict()
        else:
            doc = self._doc_with_buffer(external)
            from urllib.parse import unquote
            (folder / unquote(external)).write_bytes(bytes(self.bin))
        path = folder / name
        path.write_text(json.dumps(doc))
        return path

    def glb(self) -> bytes:
        return make_glb(self._doc_with_buffer(None), bytes(self.bin))


def make_glb(doc: dict, binary: bytes | None) -> bytes:
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary:
        b = binary + b"\0" * (-len(binary) % 4)
        out += struct.pack("<II", len(b), 0x004E4942) + b
    return struct.pack("<III", 0x46546C67, 2, 12 + len(out)) + out
