"""world/images.py's SceneImages: a scene's image textures (scene-file textures and glTF
images alike) decoded once per distinct content and shared, every texel held counted
against one limit for the scene, decoding that holds little beyond its result, and
running out of memory said in one line naming the file."""
from __future__ import annotations

import io
import json
import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from PIL import Image

from gltf_builder import UBYTE, Builder
from world import images, limits
from world.errors import SceneError
from world.loader import load_scene

QUAD = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n"
CAMERA = "[camera]\nposition = [0.0, 0.5, 6.0]\nlook_at = [0.0, 0.5, 0.0]\nfov_y = 45.0\n"


def png_bytes(a: np.ndarray) -> bytes:
    out = io.BytesIO()
    Image.fromarray(a).save(out, "PNG")
    return out.getvalue()


def texture_object(name: str, path: str) -> str:
    return (f'[[objects]]\nname = "{name}"\nmesh = "quad.obj"\n'
            f'material = {{ texture = {{ kind = "image", path = "{path}" }} }}\n')


def gltf_entry(name: str, gltf: str) -> str:
    return f'[[objects]]\nname = "{name}"\ngltf = "{gltf}"\n'


def textured_asset(folder, name: str, uris: list[str], factors: list | None = None) -> str:
    """A glTF asset of one quad per material, material k drawing images[k] (uri uris[k])
    tinted by factors[k]."""
    b = Builder()
    p = b.accessor(np.float32([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]))
    uv = b.accessor(np.float32([[0, 1], [1, 1], [1, 0], [0, 0]]))
    ind = b.accessor(np.uint8([0, 1, 2, 0, 2, 3]), UBYTE)
    for k, uri in enumerate(uris):
        b.add("images", {"uri": uri})
        b.add("textures", {"source": k})
        pbr = {"baseColorTexture": {"index": k}}
        if factors is not None:
            pbr["baseColorFactor"] = list(factors[k]) + [1.0]
        b.add("materials", {"pbrMetallicRoughness": pbr})
        b.add("meshes", {"primitives": [{"attributes": {"POSITION": p, "TEXCOORD_0": uv},
                                         "indices": ind, "material": k}]})
        b.add("nodes", {"mesh": k, "translation": [1.5 * k, 0, 0]})
    b.doc["scenes"] = [{"nodes": list(range(len(uris)))}]
    b.write(folder, name)
    return name


def scene(folder, *objects: str):
    (folder / "quad.obj").write_text(QUAD)
    p = folder / "scene.toml"
    p.write_text(CAMERA + "".join(objects))
    return p


def test_a_file_named_by_many_objects_and_materials_is_decoded_once(tmp_path):
    codes = np.arange(4 * 5 * 3, dtype=np.uint8).reshape(4, 5, 3) * 4
    data = png_bytes(codes)
    for name in ("a.png", "same_bytes.png"):
        (tmp_path / name).write_bytes(data)
    asset = textured_asset(tmp_path, "asset.gltf", ["a.png", "a.png", "same_bytes.png"])
    objects = [texture_object(f"q{k}", "a.png") for k in range(3)]
    objects += [texture_object("copy", "same_bytes.png"), gltf_entry("g", asset)]
    sc = load_scene(scene(tmp_path, *objects))
    textures = [m.texture for o in sc.objects for m in ([o.material] + [p[2] for p in o.parts or []])]
    assert len(sc.objects) == 7 and all(t is textures[0] for t in textures)
    np.testing.assert_array_equal(textures[0].image, images.SRGB8_LINEAR[codes])
    assert textures[0].path == tmp_path / "a.png"


def test_a_glTF_image_is_tinted_once_per_colour(tmp_path):
    codes = np.full((2, 3, 3), 200, np.uint8)
    (tmp_path / "t.png").write_bytes(png_bytes(codes))
    red, white = (1.0, 0.25, 0.5), (1.0, 1.0, 1.0)
    asset = textured_asset(tmp_path, "asset.gltf", ["t.png"] * 4, [red, white, red, white])
    sc = load_scene(scene(tmp_path, gltf_entry("g", asset)))
    tex = [o.material.texture for o in sc.objects]
    assert tex[0] is tex[2] and tex[1] is tex[3] and tex[0] is not tex[1]
    lin = images.SRGB8_LINEAR[200]
    np.testing.assert_array_equal(tex[1].image, np.full((2, 3, 3), lin, np.float32))
    np.testing.assert_array_equal(tex[0].image[0, 0], lin * np.float32(red))
    assert not tex[0].image.flags.writeable and not tex[1].image.flags.writeable


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 3), st.booleans()), min_size=1, max_size=6),
       st.integers(4, 40))
def test_the_scene_holds_at_most_its_limit_of_texels_each_content_once(tmp_path_factory, uses, most):
    """Objects name four files (sides 1..4, two of them the same bytes) from scene files
    and glTF entries; the scene loads exactly when the distinct images' pixels fit the
    limit, and then holds that many."""
    folder = tmp_path_factory.mktemp("budget")
    sides = [1, 2, 3, 3]
    for k, side in enumerate(sides):
        codes = np.full((side, side, 3), 40 + 60 * min(k, 2), np.uint8)     # files 2 and 3: same bytes
        (folder / f"f{k}.png").write_bytes(png_bytes(codes))
    objects = [textured_asset(folder, f"a{i}.gltf", [f"f{k}.png"]) if glb else None
               for i, (k, glb) in enumerate(uses)]
    objects = [gltf_entry(f"g{i}", objects[i]) if glb else texture_object(f"o{i}", f"f{k}.png")
               for i, (k, glb) in enumerate(uses)]
    distinct = {min(k, 2): sides[k] ** 2 for k, _ in uses}
    need = sum(distinct.values())
    old = limits.MAX_SCENE_IMAGE_PIXELS
    limits.MAX_SCENE_IMAGE_PIXELS = most
    try:
        if need <= most:
            sc = load_scene(scene(folder, *objects))
            held = {id(o.material.texture.image) for o in sc.objects}
            assert len(held) == len(distinct)
            assert sum(o.material.texture.image.shape[0] ** 2 for o in
                       {id(o.material.texture): o for o in sc.objects}.values()) == need
        else:
            with pytest.raises(SceneError, match=rf"more than the limit of {most} for a scene") as e:
                load_scene(scene(folder, *objects))
            assert "\n" not in str(e.value) and "scene.toml: objects[" in str(e.value)
    finally:
        limits.MAX_SCENE_IMAGE_PIXELS = old


def test_decoding_holds_little_beyond_its_result():
    """An 8-bit 2048x2048 PNG decodes to float32 with at most a tenth more memory
    (numpy's, traced) than the 48 MiB result: a strip at a time, no full-size uint8 or
    float64 copy. The result is stored bottom row first: the GL rows the upload needs
    are a view of it, not a copy."""
    codes = (np.arange(2048 * 2048 * 3, dtype=np.uint32) * 7 % 251).astype(np.uint8)
    codes = codes.reshape(2048, 2048, 3)
    data = png_bytes(codes)
    tracemalloc.start()
    try:
        texels = images.SceneImages().from_bytes(data)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert texels.nbytes == 48 << 20 and peak < texels.nbytes * 11 // 10, peak
    np.testing.assert_array_equal(texels, images.SRGB8_LINEAR[codes])
    gl_rows = np.ascontiguousarray(texels[::-1])
    assert np.shares_memory(gl_rows, texels)


def test_running_out_of_memory_is_one_line_naming_the_file(tmp_path, monkeypatch):
    (tmp_path / "t.png").write_bytes(png_bytes(np.zeros((2, 2, 3), np.uint8)))

    def no_memory(*args, **kwargs):
        raise MemoryError()

    monkeypatch.setattr(images, "linear_rgb", no_memory)
    for objects in ([texture_object("q", "t.png")],
                    [gltf_entry("g", textured_asset(tmp_path, "asset.gltf", ["t.png"]))]):
        with pytest.raises(SceneError) as e:
            load_scene(scene(tmp_path, *objects))
        msg = str(e.value)
        assert "\n" not in msg and "out of memory decoding its 2x2 pixels" in msg
        assert str(tmp_path / ("t.png" if objects[0].count("mesh") else "asset.gltf")) in msg
    monkeypatch.undo()
    import trimesh
    monkeypatch.setattr(trimesh, "load", no_memory)
    with pytest.raises(SceneError, match=r"objects\[1\] \(q\)\.mesh: .*quad\.obj: out of memory "
                                         r"reading the mesh"):
        load_scene(scene(tmp_path, texture_object("q", "t.png")))
    monkeypatch.undo()
    from world import gltf_entry as entry_module
    monkeypatch.setattr(entry_module, "_mesh", no_memory)
    with pytest.raises(SceneError, match=r"scene\.toml: out of memory while loading the scene"):
        load_scene(scene(tmp_path, gltf_entry("g", "asset.gltf")))


def test_a_gif_decoded_for_a_scene_file_is_still_no_glTF_image(tmp_path):
    gif = io.BytesIO()
    Image.new("RGB", (2, 2), (9, 9, 9)).save(gif, "GIF")
    (tmp_path / "t.gif").write_bytes(gif.getvalue())
    asset = textured_asset(tmp_path, "asset.gltf", ["t.gif"])
    with pytest.raises(SceneError, match=r"images\[0\]: cannot decode the image \(a GIF, not PNG or JPEG\)"):
        load_scene(scene(tmp_path, texture_object("q", "t.gif"), gltf_entry("g", asset)))
    doc = json.loads((tmp_path / asset).read_text())
    assert doc["images"] == [{"uri": "t.gif"}]
