"""glTF accessors decoded as glTF 2.0 says: byteStride, matrix column padding, normalized
integer components, sparse substitution; float or normalized accessors as float64, others
as int64, read-only (several primitives may share one: copy before modifying).
"""
from __future__ import annotations

import numpy as np
import pygltflib as G

from world import limits
from world.gltf.container import Container
from world.gltf.document import fail, integer, is_int, kept, obj, ref, show

_COMPONENT = {                         # componentType -> little-endian numpy dtype
    G.BYTE: np.dtype("<i1"), G.UNSIGNED_BYTE: np.dtype("<u1"),
    G.SHORT: np.dtype("<i2"), G.UNSIGNED_SHORT: np.dtype("<u2"),
    G.UNSIGNED_INT: np.dtype("<u4"), G.FLOAT: np.dtype("<f4"),
}
_TYPE = {"SCALAR": (1, 0), "VEC2": (2, 0), "VEC3": (3, 0), "VEC4": (4, 0),
         "MAT2": (4, 2), "MAT3": (9, 3), "MAT4": (16, 4)}     # -> (components, matrix rows)
_NORM_DIVISOR = {G.BYTE: 127.0, G.UNSIGNED_BYTE: 255.0, G.SHORT: 32767.0,
                 G.UNSIGNED_SHORT: 65535.0}
FLOATISH = (G.FLOAT, G.BYTE, G.UNSIGNED_BYTE, G.SHORT, G.UNSIGNED_SHORT)   # float or normalized


class Accessors:
    """An asset's accessors, each decoded once, their decoded components counted against
    limits.MAX_GLTF_COMPONENTS."""

    def __init__(self, container: Container, doc: dict):
        self.container = container
        self.items = [obj(b, f"accessors[{i}]") for i, b in enumerate(doc.get("accessors", []))]
        self.components = 0
        self._decoded: dict[int, np.ndarray] = {}

    def get(self, i: int, where_used: str, types=None, components=None,
            normalized_ok=True) -> np.ndarray:
        """accessors[i] decoded: (count, components), checked to be of one of `types` and
        `components` (and normalized as `normalized_ok` says, None: either) where
        `where_used` uses it."""
        a, where = self.items[i], f"accessors[{i}]"
        ctype = a.get("componentType")
        if not is_int(ctype) or ctype not in _COMPONENT:
            fail(f"{where}.componentType: {show(ctype)} is not a glTF component type")
        atype = a.get("type")
        if not isinstance(atype, str) or atype not in _TYPE:
            fail(f"{where}.type: {show(atype)} is not a glTF accessor type")
        norm = a.get("normalized", False)
        if not isinstance(norm, bool):
            fail(f"{where}.normalized: expected true or false")
        if norm and ctype in (G.FLOAT, G.UNSIGNED_INT):
            fail(f"{where}: normalized is not allowed for componentType {ctype}")
        if types is not None and atype not in types:
            fail(f"{where_used}: accessors[{i}] is {atype}, expected {' or '.join(types)}")
        if components is not None:
            ok = ctype in components and (ctype == G.FLOAT or normalized_ok is None
                                          or normalized_ok == norm)
            if not ok:
                fail(f"{where_used}: accessors[{i}] has componentType {ctype}"
                     f"{' (normalized)' if norm else ''}, not allowed here")
        return kept(self._decoded, i, lambda: self._decode(i, a, ctype, atype, norm))

    def _decode(self, i: int, a: dict, ctype: int, atype: str, norm: bool) -> np.ndarray:
        where = f"accessors[{i}]"
        count = integer(a, "count", where, lo=1)
        ncomp, rows = _TYPE[atype]
        if count * ncomp > limits.MAX_GLTF_COMPONENTS - self.components:
            fail(f"{where}: count {count} makes the asset larger than the limit of "
                 f"{limits.MAX_GLTF_COMPONENTS} decoded components")
        dt = _COMPONENT[ctype]
        cs = dt.itemsize
        if rows:
            col = -(-rows * cs // 4) * 4            # matrix columns start on 4-byte boundaries
            offsets = [(c // rows) * col + (c % rows) * cs for c in range(ncomp)]
            esize = rows * col
        else:
            offsets = [c * cs for c in range(ncomp)]
            esize = ncomp * cs
        view_i = ref(a, "bufferView", where, self.container.views, "bufferViews")
        byte_offset = integer(a, "byteOffset", where, 0)
        if view_i is None:
            if "byteOffset" in a and byte_offset:
                fail(f"{where}: byteOffset without bufferView")
            raw = np.zeros((count, ncomp), dtype=dt)
        else:
            data, voff, vlen, vstride = self.container.view(view_i)
            stride = esize if vstride is None else vstride
            if stride < esize:
                fail(f"{where}: bufferViews[{view_i}].byteStride {stride} is smaller than the element ({esize} bytes)")
            need = byte_offset + (count - 1) * stride + esize
            if need > vlen:
                fail(f"{where}: byteOffset + (count - 1) * stride + element size = {need} exceeds "
                     f"bufferViews[{view_i}] ({vlen} bytes)")
            raw = _gather(data, voff + byte_offset, count, stride, offsets, dt)
        if "sparse" in a:
            self._sparse(a, i, raw, count, offsets, esize, dt)
        self.components += count * ncomp
        if ctype == G.FLOAT:
            out = raw.astype(np.float64)
        elif norm:
            out = raw.astype(np.float64)
            if ctype in (G.BYTE, G.SHORT):
                out = np.maximum(out / _NORM_DIVISOR[ctype], -1.0)
            else:
                out /= _NORM_DIVISOR[ctype]
        else:
            out = raw.astype(np.int64)
        out.flags.writeable = False
        return out

    def _sparse(self, a, i, raw, count, offsets, esize, dt) -> None:
        where = f"accessors[{i}].sparse"
        sp = obj(a["sparse"], where)
        n = integer(sp, "count", where, lo=1, hi=count)
        ind = obj(sp.get("indices"), f"{where}.indices") if "indices" in sp else fail(f"{where}: missing indices")
        val = obj(sp.get("values"), f"{where}.values") if "values" in sp else fail(f"{where}: missing values")
        ict = ind.get("componentType")
        if ict not in (G.UNSIGNED_BYTE, G.UNSIGNED_SHORT, G.UNSIGNED_INT) or not is_int(ict):
            fail(f"{where}.indices.componentType: {show(ict)} is not UNSIGNED_BYTE, _SHORT or _INT")
        idt = _COMPONENT[ict]
        parts = []
        for sub, d, off_list, size in (("indices", ind, [0], idt.itemsize), ("values", val, offsets, esize)):
            w = f"{where}.{sub}"
            vi = ref(d, "bufferView", w, self.container.views, "bufferViews", required=True)
            bo = integer(d, "byteOffset", w, 0)
            data, voff, vlen, _ = self.container.view(vi)
            need = bo + n * size
            if need > vlen:
                fail(f"{w}: byteOffset + count * element size = {need} exceeds bufferViews[{vi}] ({vlen} bytes)")
            parts.append(_gather(data, voff + bo, n, size, off_list, idt if sub == "indices" else dt))
        idx = parts[0][:, 0].astype(np.int64)
        if idx.size > 1 and not (np.diff(idx) > 0).all():
            fail(f"{where}.indices: not strictly increasing")
        if idx.size and idx[-1] >= count:
            fail(f"{where}.indices: index {int(idx[-1])} out of range of the accessor's count {count}")
        raw[idx] = parts[1]


def _gather(data, start, count, stride, offsets, dt) -> np.ndarray:
    """(count, len(offsets)) elements of dtype dt, element k's component c at byte
    start + k stride + offsets[c]."""
    ncomp = len(offsets)
    if offsets == [c * dt.itemsize for c in range(ncomp)]:
        arr = np.ndarray((count, ncomp), dtype=dt, buffer=data, offset=start,
                         strides=(stride, dt.itemsize))
        return arr.copy()
    out = np.empty((count, ncomp), dtype=dt)
    for c, o in enumerate(offsets):
        out[:, c] = np.ndarray((count,), dtype=dt, buffer=data, offset=start + o, strides=(stride,))
    return out
