"""The glTF container: a `.gltf` (JSON) or `.glb` (chunks) file, and the bytes that buffers,
bufferViews and images hold, from the GLB BIN chunk, data URIs or files in the asset's
folder. The JSON is parsed here with the standard library (strict: NaN and Infinity
literals refused), so that every malformation gets its own message.
"""
from __future__ import annotations

import base64
import binascii
import json
import os
import struct
import urllib.parse
from pathlib import Path

from world import limits
from world.gltf.document import GltfError, fail, integer, kept, obj, ref, show, string
from world import regular_file
from world.regular_file import Grew, NotRegular, TooLarge

_GLB_MAGIC = 0x46546C67               # b"glTF"
_CHUNK_JSON = 0x4E4F534A
_CHUNK_BIN = 0x004E4942


def read_regular(path: Path, what: str) -> bytes:
    """The bytes of a regular file of at most limits.MAX_GLTF_FILE_BYTES."""
    cap = limits.MAX_GLTF_FILE_BYTES
    try:
        return regular_file.read_regular(path, cap)
    except NotRegular:
        raise GltfError(f"{what}: {path} is not a regular file") from None
    except TooLarge as e:
        raise GltfError(f"{what}: {path} is {e.size} bytes, more than the limit of {cap}") from None
    except Grew:
        raise GltfError(f"{what}: {path} grew while it was read") from None
    except OSError as e:
        raise GltfError(f"{what}: cannot read {path}: {e.strerror or e}") from None


def read_document(path: Path) -> tuple[dict, bytes | None]:
    """(the JSON document, the GLB BIN chunk or None) of a .gltf or .glb file: the GLB magic
    decides, whatever the suffix."""
    data = read_regular(path, "asset")
    if data[:4] == b"glTF" or path.suffix.lower() == ".glb":
        return parse_glb(data)
    return parse_json(data, "JSON"), None


def parse_glb(data: bytes) -> tuple[dict, bytes | None]:
    if len(data) < 12:
        fail(f"GLB: truncated header ({len(data)} bytes, expected 12)")
    magic, version, length = struct.unpack_from("<III", data, 0)
    if magic != _GLB_MAGIC:
        fail("GLB: bad magic (expected 'glTF')")
    if version != 2:
        fail(f"GLB: header version {version}, expected 2")
    if length > len(data):
        fail(f"GLB: header length {length} exceeds the file ({len(data)} bytes): truncated")
    if length < 20:
        fail(f"GLB: header length {length} leaves no room for the JSON chunk")
    pos, js, binary, k = 12, None, None, 0
    while pos < length:
        if pos + 8 > length:
            fail(f"GLB: chunk {k}: truncated chunk header at byte {pos}")
        clen, ctype = struct.unpack_from("<II", data, pos)
        if pos + 8 + clen > length:
            fail(f"GLB: chunk {k}: length {clen} at byte {pos} exceeds the file ({length} bytes): truncated")
        body = data[pos + 8: pos + 8 + clen]
        if k == 0:
            if ctype != _CHUNK_JSON:
                fail("GLB: the first chunk is not JSON")
            js = body
        elif ctype == _CHUNK_JSON:
            fail(f"GLB: chunk {k}: a second JSON chunk")
        elif ctype == _CHUNK_BIN:
            if binary is not None:
                fail(f"GLB: chunk {k}: a second BIN chunk")
            if k != 1:
                fail(f"GLB: chunk {k}: the BIN chunk must come second")
            binary = body
        pos += 8 + clen
        k += 1
    if js is None:
        fail("GLB: no JSON chunk")
    return parse_json(js.rstrip(b" \t\r\n\x00"), "GLB JSON chunk"), binary


def _reject_constant(name):
    raise ValueError(f"{name} is not JSON")


def parse_json(raw: bytes, what: str) -> dict:
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise GltfError(f"{what}: not UTF-8 ({e.reason} at byte {e.start})") from None
    if text.startswith("\ufeff"):
        text = text[1:]
    try:
        doc = json.loads(text, parse_constant=_reject_constant)
    except json.JSONDecodeError as e:
        raise GltfError(f"{what}: JSON syntax error at line {e.lineno} column {e.colno}: {e.msg}") from None
    except (ValueError, RecursionError) as e:
        raise GltfError(f"{what}: bad JSON: {str(e)[:100] or type(e).__name__}") from None
    if not isinstance(doc, dict):
        fail(f"{what}: the top level is not a JSON object")
    return doc


class Container:
    """The bytes of an asset's buffers and bufferViews (each read once), and of any file or
    data URI it names."""

    def __init__(self, path: Path, doc: dict, glb_bin: bytes | None):
        self.folder = Path(path).parent
        self.glb_bin = glb_bin
        self.buffers = [obj(b, f"buffers[{i}]") for i, b in enumerate(doc.get("buffers", []))]
        self.views = [obj(b, f"bufferViews[{i}]") for i, b in enumerate(doc.get("bufferViews", []))]
        self._files: dict[str, bytes] = {}
        self._buffers: dict[int, bytes] = {}
        self._views: dict[int, tuple[bytes, int, int, int | None]] = {}

    def external(self, uri: str, where: str) -> bytes:
        """The bytes a `uri` names: a data URI's, or a file's inside the asset's folder."""
        if uri.startswith("data:"):
            return self.data_uri(uri, where)
        parsed = urllib.parse.urlsplit(uri)
        if parsed.scheme or parsed.netloc:
            fail(f"{where}.uri: {show(uri)}: only relative file paths and data URIs are supported")
        rel = urllib.parse.unquote(parsed.path)
        if not rel or rel.startswith(("/", "\\")) or "\x00" in rel or os.path.isabs(rel):
            fail(f"{where}.uri: {show(uri)} is not a relative path")
        base = os.path.realpath(self.folder)
        full = os.path.realpath(os.path.join(base, rel))
        if os.path.commonpath([base, full]) != base:
            fail(f"{where}.uri: {show(uri)} leaves the asset's folder")
        return kept(self._files, full, lambda: read_regular(Path(full), f"{where}.uri"))

    @staticmethod
    def data_uri(uri: str, where: str) -> bytes:
        head, sep, payload = uri.partition(",")
        if not sep:
            fail(f"{where}.uri: bad data URI (no comma)")
        cap = limits.MAX_GLTF_FILE_BYTES
        if len(payload) > cap * 4 // 3 + 4:
            fail(f"{where}.uri: data URI of {len(payload)} characters, more than the limit of "
                 f"{cap} bytes")
        if head.endswith(";base64"):
            try:
                return base64.b64decode(payload, validate=True)
            except (binascii.Error, ValueError) as e:
                raise GltfError(f"{where}.uri: bad base64 in data URI ({e})") from None
        return urllib.parse.unquote_to_bytes(payload)

    def buffer(self, i: int) -> bytes:
        return kept(self._buffers, i, lambda: self._read_buffer(i))

    def _read_buffer(self, i: int) -> bytes:
        b, where = self.buffers[i], f"buffers[{i}]"
        length = integer(b, "byteLength", where, lo=1)
        if "uri" in b:
            data = self.external(string(b, "uri", where), where)
        elif i == 0 and self.glb_bin is not None:
            data = self.glb_bin
        else:
            fail(f"{where}: no uri (and no GLB BIN chunk)" if i == 0 else f"{where}: no uri")
        if len(data) < length:
            fail(f"{where}: {len(data)} bytes of data, shorter than its byteLength {length}")
        return data[:length] if len(data) > length else data

    def view(self, i: int) -> tuple[bytes, int, int, int | None]:
        """(buffer bytes, offset, length, byteStride or None) of bufferViews[i]."""
        return kept(self._views, i, lambda: self._read_view(i))

    def _read_view(self, i: int) -> tuple[bytes, int, int, int | None]:
        v, where = self.views[i], f"bufferViews[{i}]"
        b = ref(v, "buffer", where, self.buffers, "buffers", required=True)
        offset = integer(v, "byteOffset", where, 0)
        length = integer(v, "byteLength", where, lo=1)
        stride = integer(v, "byteStride", where, None, lo=4, hi=252)
        if stride is not None and stride % 4:
            fail(f"{where}.byteStride: {stride} is not a multiple of 4")
        data = self.buffer(b)
        if offset + length > len(data):
            fail(f"{where}: byteOffset + byteLength = {offset + length} exceeds buffers[{b}] ({len(data)} bytes)")
        return data, offset, length, stride

    def view_bytes(self, i: int) -> bytes:
        """The bytes of bufferViews[i] (an image's)."""
        data, offset, length, _ = self.view(i)
        return data[offset: offset + length]
