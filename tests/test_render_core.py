"""The G-buffer and the `off` / `reference` modes against numpy, analytic cases and an
independent ray cast."""
import dataclasses

import numpy as np
import pytest

from conftest import CONFORMANCE, scene_from
from world.camera import Camera
from world.conventions import BACKGROUND_DEPTH
from viewer.io.imageio import linear_to_srgb8
from viewer.render.graph.params import ParamSet
from viewer.render.renderer import Renderer
from world.loader import load_scene


TWO_BOXES = """
    background = [0.1, 0.2, 0.3]
    ambient = [0.2, 0.2, 0.2]
    [camera]
    position = [0.0, 0.5, 5.0]
    look_at = [0.0, 0.3, 0.0]
    fov_y = 40.0
    shutter = 0.05
    [[lights]]
    direction = [-0.3, -1.0, -0.5]
    [[objects]]
    mesh = { box = [1.0, 1.0, 1.0] }
    position = [-0.8, 0.3, 0.0]
    rotation = [10.0, 30.0, 0.0]
    velocity = [4.0, 1.0, 0.0]
    angular_velocity = [0.0, 0.0, 6.0]
    material = { albedo = [0.9, 0.2, 0.2], texture = { kind = "checker", size = 0.25, albedo2 = [0.1, 0.1, 0.9] } }
    [[objects]]
    mesh = { sphere = { radius = 0.5, subdivisions = 2 } }
    position = [0.9, 0.3, -0.5]
    material = { albedo = [0.2, 0.8, 0.2], specular = 0.5, shininess = 20.0 }
"""


def test_ids_background_and_depth(ctx, tmp_path):
    sc = scene_from(tmp_path, TWO_BOXES)
    r = Renderer(ctx, sc, (96, 64))
    try:
        res = r.render("off", 0.0)
        b = r.buffers()
    finally:
        r.release()
    assert set(np.unique(b["id"])) == {0, 1, 2}
    bg = b["id"] == 0
    assert np.all(b["depth"][bg] == np.float32(BACKGROUND_DEPTH))
    assert np.allclose(res.image[bg], [0.1, 0.2, 0.3])
    assert np.all(b["velocity"][bg] == 0)
    assert np.all((b["depth"][~bg] > 3.0) & (b["depth"][~bg] < 7.0))


def world_points_at_pixels(cam, t, depth, ii, jj):
    o, d = cam.rays(t, ii, jj)
    fwd = cam.spec.pose(t)[1]
    return o + d * (depth[jj, ii] / (d @ fwd))[:, None]


@pytest.mark.parametrize("camera_motion", [False, True])
def test_velocity_is_the_exposure_displacement(ctx, tmp_path, camera_motion):
    text = TWO_BOXES
    if camera_motion:
        text = text.replace("shutter = 0.05", "shutter = 0.05\nvelocity = [1.0, 0.5, -2.0]\n"
                                                "angular_velocity = [0.0, 0.8, 0.3]")
    sc = scene_from(tmp_path, text)
    t = 0.1
    r = Renderer(ctx, sc, (128, 96))
    try:
        r.render("off", t)
        b = r.buffers()
    finally:
        r.release()
    cam = Camera(sc.camera, 128, 96)
    t0, t1 = t - sc.camera.shutter / 2, t + sc.camera.shutter / 2     # the contract's exposure
    checked = 0
    for obj in sc.objects:
        jj, ii = np.nonzero(b["id"] == obj.id)
        pick = np.linspace(0, len(ii) - 1, 40).astype(int)
        ii, jj = ii[pick], jj[pick]
        world = world_points_at_pixels(cam, t, b["depth"], ii, jj)
        local = (np.linalg.inv(obj.matrix(t)) @ np.c_[world, np.ones(len(world))].T).T
        p0 = (obj.matrix(t0) @ local.T).T[:, :3]
        p1 = (obj.matrix(t1) @ local.T).T[:, :3]
        expect = cam.project(t1, p1)[0] - cam.project(t0, p0)[0]
        got = b["velocity"][jj, ii]
        assert np.allclose(got, expect, atol=0.02 + 1e-3 * np.abs(expect).max())
        checked += len(ii)
    assert checked == 80


def test_velocity_stays_finite_across_the_near_plane(ctx, tmp_path):
    # A wall rushing at the camera: at shutter close its points are behind the near plane.
    sc = scene_from(tmp_path, """
        [camera]
        position = [0.0, 0.0, 2.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 60.0
        near = 0.1
        shutter = 0.1
        [[objects]]
        mesh = { box = [4.0, 4.0, 0.1] }
        velocity = [0.0, 0.0, 30.0]
    """)
    r = Renderer(ctx, sc, (64, 48))
    try:
        r.render("off", 0.0)
        v, ids = r.buffers()["velocity"], r.buffers()["id"]
    finally:
        r.release()
    assert np.all(ids == 1)
    assert np.all(np.isfinite(v))
    # Radial expansion: displacement points away from the image centre (GL axes, y up).
    jj, ii = np.mgrid[0:48, 0:64]
    rx, ry = ii + 0.5 - 32, (47 - jj) + 0.5 - 24
    away = v[..., 0] * rx + v[..., 1] * ry
    assert np.all(away[np.hypot(rx, ry) > 4] > 0)


def test_reference_equals_off_for_a_static_scene(ctx, tmp_path):
    sc = scene_from(tmp_path, TWO_BOXES.replace("velocity = [4.0, 1.0, 0.0]", "")
                    .replace("angular_velocity = [0.0, 0.0, 6.0]", ""))
    r = Renderer(ctx, sc, (80, 48))
    params = ParamSet()
    params.set("reference.samples", 16)
    try:
        off = r.render("off", 0.3).image
        ref = r.render("reference", 0.3, params).image
    finally:
        r.release()
    assert np.allclose(off, ref, atol=1e-6)
    assert np.array_equal(linear_to_srgb8(off), linear_to_srgb8(ref))


def test_reference_of_a_translating_quad_matches_analytic_coverage(ctx, tmp_path):
    # An unlit quad (ambient 1, no lights) crossing a black background: each pixel's value is
    # the albedo times the fraction of the exposure its centre is covered.
    sc = scene_from(tmp_path, """
        ambient = [1.0, 1.0, 1.0]
        [camera]
        position = [0.0, 0.0, 4.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 50.0
        shutter = 0.1
        [[objects]]
        mesh = { box = [0.6, 1.0, 0.01] }
        material = { albedo = [0.5, 0.25, 1.0] }
        velocity = [8.0, 0.0, 0.0]
    """)
    n = 256
    params = ParamSet()
    params.set("reference.samples", n)
    w, h = 120, 40
    r = Renderer(ctx, sc, (w, h))
    try:
        ref = r.render("reference", 0.0, params).image
    finally:
        r.release()
    cam = Camera(sc.camera, w, h)
    row = h // 2
    o, d = cam.rays(0.0, np.arange(w), np.full(w, row))
    x = (o + d * ((0.005 - o[:, 2]) / d[:, 2])[:, None])[:, 0]   # front face at z = 0.005
    t0, t1 = -0.05, 0.05
    # covered while -0.3 + 8 t <= x <= 0.3 + 8 t
    lo, hi = np.maximum((x - 0.3) / 8, t0), np.minimum((x + 0.3) / 8, t1)
    coverage = np.clip(hi - lo, 0, None) / (t1 - t0)
    assert np.isclose(coverage.max(), 0.75) and coverage.min() == 0.0   # moves 0.8, 0.6 wide
    assert np.allclose(ref[row, :, 0], 0.5 * coverage, atol=0.5 / n + 1e-4)
    assert np.allclose(ref[row, :, 2], 1.0 * coverage, atol=1.0 / n + 1e-4)


def independent_ray_cast(sc, w, h, t):
    """Object ids at pixel centres from a numpy ray cast written here, with its own rays."""
    eye = sc.camera.position
    fwd = (sc.camera.look_at - eye) / np.linalg.norm(sc.camera.look_at - eye)
    right = np.cross(fwd, sc.camera.up)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    th = np.tan(np.radians(sc.camera.fov_y) / 2)
    jj, ii = np.mgrid[0:h, 0:w]
    x = ((ii + 0.5) / w * 2 - 1) * th * w / h
    y = (1 - (jj + 0.5) / h * 2) * th
    dirs = fwd + x.reshape(-1, 1) * right + y.reshape(-1, 1) * up
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    best = np.full(len(dirs), np.inf)
    ids = np.zeros(len(dirs), np.uint32)
    for obj in sc.objects:
        v = (obj.matrix(t) @ np.c_[obj.mesh.vertices, np.ones(len(obj.mesh.vertices))].T).T[:, :3]
        for a, b, c in v[obj.mesh.faces]:          # Moller-Trumbore, all rays at once
            e1, e2 = b - a, c - a
            p = np.cross(dirs, e2)
            det = p @ e1
            ok = np.abs(det) > 1e-12
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            s_ = eye - a
            u = (p @ s_) * inv
            q = np.cross(s_, e1)
            w_ = (dirs @ q) * inv
            dist = (q @ e2) * inv
            hit = ok & (u >= 0) & (w_ >= 0) & (u + w_ <= 1) & (dist > 0) & (dist < best)
            best[hit] = dist[hit]
            ids[hit] = obj.id
    return ids.reshape(h, w)


def test_off_ids_match_an_independent_ray_cast(ctx, tmp_path):
    sc = scene_from(tmp_path, TWO_BOXES)
    w, h = 64, 40
    r = Renderer(ctx, sc, (w, h))
    try:
        r.render("off", 0.02)
        ids = r.buffers()["id"]
    finally:
        r.release()
    expect = independent_ray_cast(sc, w, h, 0.02)
    assert (expect > 0).sum() > 200
    assert (ids != expect).sum() <= 6      # silhouette pixels rounded the other way


def test_same_input_same_bytes(ctx, tmp_path):
    sc = scene_from(tmp_path, TWO_BOXES)
    r = Renderer(ctx, sc, (64, 40))
    params = ParamSet()
    params.set("reference.samples", 8)
    try:
        a = r.render("reference", 0.1, params).image
        b = r.render("reference", 0.1, params).image
    finally:
        r.release()
    assert a.tobytes() == b.tobytes()


def test_resize_reallocates(ctx, tmp_path):
    sc = scene_from(tmp_path, TWO_BOXES)
    r = Renderer(ctx, sc, (64, 40))
    try:
        assert r.render("off", 0.0).image.shape == (40, 64, 3)
        r.resize((33, 17))
        assert r.render("off", 0.0).image.shape == (17, 33, 3)
        assert r.pool.get("color").size == (33, 17)
    finally:
        r.release()


def numpy_directions(cam, t, i, j):
    """Camera.rays' directions as numpy statements of the same formula."""
    from world.conventions import pixel_centres_ndc
    eye, fwd, up = cam.spec.pose(t)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    x, y = pixel_centres_ndc(i, j, cam.width, cam.height)
    tan_half = np.tan(np.radians(cam.spec.fov_y) * 0.5)
    sx, sy = x * (tan_half * cam.aspect), y * tan_half
    d = np.empty((len(sx), 3))
    for k in range(3):
        d[:, k] = fwd[k] + sx * right[k] + sy * true_up[k]
    return d / np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])[:, None]


def test_camera_rays_equal_the_numpy_formula():
    # The compiled ray directions equal the formula in numpy bit for bit (well, to the
    # last ulp of the normalisation), at two poses, another field of view and size.
    import dataclasses
    from world.camera import Camera
    from world.loader import load_scene
    spec = load_scene(str(CONFORMANCE / "vase_pan.toml")).camera      # a moving camera
    rng = np.random.default_rng(2)
    i, j = rng.integers(0, 64, 500), rng.integers(0, 40, 500)
    cam = Camera(spec, 64, 40)
    for t in (0.0, 0.3):
        o, d = cam.rays(t, i, j)
        np.testing.assert_allclose(d, numpy_directions(cam, t, i, j), rtol=0, atol=4e-16)
        np.testing.assert_array_equal(o, np.broadcast_to(spec.pose(t)[0], o.shape))
        assert o.strides[0] == 0
    wide = Camera(dataclasses.replace(spec, fov_y=spec.fov_y * 1.5), 33, 17)
    i, j = rng.integers(0, 33, 100), rng.integers(0, 17, 100)
    np.testing.assert_allclose(wide.rays(0.1, i, j)[1], numpy_directions(wide, 0.1, i, j),
                               rtol=0, atol=4e-16)
    # The camera's basis (made in the compiled pass): random poses, any up not along the
    # view, and a turning camera.
    for k in range(50):
        pose = dataclasses.replace(spec, position=rng.normal(size=3) * 10,
                                   look_at=rng.normal(size=3), up=rng.normal(size=3),
                                   angular_velocity=rng.normal(size=3) * (k % 2))
        cam = Camera(pose, 33, 17)
        np.testing.assert_allclose(cam.rays(0.2, i, j)[1], numpy_directions(cam, 0.2, i, j),
                                   rtol=0, atol=4e-16)


def test_pass_timer_splits_host_cpu_from_waiting(monkeypatch):
    # pass_ms is the wall time between two ctx.finish() (the GPU's work included),
    # pass_cpu_ms the main thread's CPU time in the pass; repeats add up. Scripted clocks
    # and a recording context: the arithmetic and the order, no real time.
    from types import SimpleNamespace
    from viewer.render.graph import frame as frame_mod
    log, wall, cpu = [], [10.0], [3.0]
    clock = SimpleNamespace(perf_counter=lambda: (log.append("wall"), wall[0])[1],
                            thread_time=lambda: (log.append("cpu"), cpu[0])[1])
    monkeypatch.setattr(frame_mod, "_time", clock)
    gl = SimpleNamespace(finish=lambda: log.append("finish"))
    frame = SimpleNamespace(ctx=gl, timing=True, pass_ms={}, pass_cpu_ms={})

    def run(name, dwall, dcpu):
        with frame_mod.PassTimer(frame, name):
            wall[0] += dwall
            cpu[0] += dcpu

    run("waits", 0.050, 0.001)         # e.g. a sleep: wall time, next to no CPU
    assert log == ["finish", "wall", "cpu", "cpu", "finish", "wall"]
    run("computes", 0.050, 0.040)
    run("computes", 0.010, 0.010)
    assert frame.pass_ms == pytest.approx({"waits": 50.0, "computes": 60.0})
    assert frame.pass_cpu_ms == pytest.approx({"waits": 1.0, "computes": 50.0})
    log.clear()
    frame.timing = False                # untimed frames: no finish, nothing recorded
    run("off", 1.0, 1.0)
    assert log == [] and "off" not in frame.pass_ms
    frame.timing = True
    with pytest.raises(ValueError):     # a failing pass records no time
        with frame_mod.PassTimer(frame, "fails"):
            raise ValueError
    assert "fails" not in frame.pass_ms and "fails" not in frame.pass_cpu_ms


@pytest.mark.parametrize("mode", ["off", "hybrid"])
def test_any_number_of_lights_adds_up_light_by_light(ctx, tmp_path, mode):
    """docs/scene-format.md: any number of lights. Shading is linear in them, and so is every
    blur of it: the frame lit by 20 lights (more than one shader array of 16) is the sum
    of the frames lit by each alone, plus the ambient term (the background black: it is
    in every frame), on every object pixel (the hybrid's revealed surfaces lit by all 20
    too)."""
    rng = np.random.default_rng(7)
    dirs = rng.normal(size=(20, 3))
    dirs[:, 1] = -np.abs(dirs[:, 1])
    cols = rng.uniform(0.02, 0.12, size=(20, 3))
    base = TWO_BOXES.replace("""    [[lights]]
    direction = [-0.3, -1.0, -0.5]
""", "{lights}").replace("background = [0.1, 0.2, 0.3]", "background = [0.0, 0.0, 0.0]")

    def lit(k_lights, ambient=True):
        def vec(v):
            return "[" + ", ".join(f"{x:.6f}" for x in v) + "]"
        lights = "".join(f"    [[lights]]\n    direction = {vec(dirs[k])}\n"
                         f"    color = {vec(cols[k])}\n" for k in k_lights)
        text = base.replace("{lights}", lights)
        if not ambient:
            text = text.replace("ambient = [0.2, 0.2, 0.2]", "ambient = [0.0, 0.0, 0.0]")
        sc = scene_from(tmp_path, text, f"l{len(k_lights)}{ambient}")
        r = Renderer(ctx, sc, (96, 54))
        try:
            ids = r.render("off", 0.0, ParamSet()) and r.buffers()["id"]
            return r.render(mode, 0.0, ParamSet()).image.astype(np.float64), ids
        finally:
            r.release()

    every, ids = lit(range(20))
    total, _ = lit([])                          # ambient alone
    for k in range(20):
        total += lit([k], ambient=False)[0]
    objects = ids > 0
    assert objects.sum() > 400
    np.testing.assert_allclose(every[objects], total[objects], atol=5e-6)
    assert np.abs(every[objects] - lit([], True)[0][objects]).max() > 0.3   # the lights count


def test_lights_beyond_the_drivers_uniform_storage_go_in_a_texture():
    from world.errors import SceneError
    from viewer.render.graph.gpu_scene import light_slots

    class Info:                                  # only the limits light_slots reads
        def __init__(self, vectors, texture=16384):
            self.info = {"GL_MAX_FRAGMENT_UNIFORM_VECTORS": vectors,
                         "GL_MAX_TEXTURE_SIZE": texture}
    scene = load_scene(CONFORMANCE / "basic.toml")
    assert light_slots(Info(4096), scene) == 16
    many = dataclasses.replace(scene, lights=scene.lights * 200)
    n = len(many.lights)
    assert light_slots(Info(4096), many) == -(-n // 16) * 16
    assert light_slots(Info(256), many) == 0                   # uniforms hold only 96
    with pytest.raises(SceneError) as info:                     # 1 row of 1024 lights
        light_slots(Info(256, 1), dataclasses.replace(scene, lights=scene.lights * 1025))
    assert "lights" in str(info.value) and "at most 1024" in str(info.value)


@pytest.mark.parametrize("mode", ["off", "hybrid"])
def test_lights_in_a_texture_shade_as_lights_in_uniforms(ctx, tmp_path, mode, monkeypatch):
    """Past the uniform storage (2016 lights on llvmpipe) the lights are read from a
    texture: the same 40 lights give the same image both ways, and 2100 lights (more
    than llvmpipe's uniforms hold) render, lit by all of them."""
    import viewer.render.graph.gpu_scene as gs
    rng = np.random.default_rng(11)

    def lights_text(n, scale):
        dirs = rng.normal(size=(n, 3))
        dirs[:, 1] = -np.abs(dirs[:, 1]) - 0.1
        cols = rng.uniform(0.2, 1.0, size=(n, 3)) * scale
        return "".join(f"    [[lights]]\n    direction = [{d[0]:.6f}, {d[1]:.6f}, {d[2]:.6f}]\n"
                       f"    color = [{c[0]:.6f}, {c[1]:.6f}, {c[2]:.6f}]\n"
                       for d, c in zip(dirs, cols))
    base = TWO_BOXES.replace("""    [[lights]]
    direction = [-0.3, -1.0, -0.5]
""", "{lights}")

    def render(text, name):
        r = Renderer(ctx, scene_from(tmp_path, text, name), (64, 36))
        try:
            return r.render(mode, 0.0, ParamSet()).image, r.gpu.light_texture is not None
        finally:
            r.release()
    forty = base.replace("{lights}", lights_text(40, 0.02))
    in_uniforms, texture = render(forty, "u")
    assert not texture
    monkeypatch.setattr(gs, "OTHER_UNIFORM_VECTORS", 10 ** 6)   # no room: a texture
    in_texture, texture = render(forty, "t")
    assert texture
    np.testing.assert_array_equal(in_texture, in_uniforms)
    monkeypatch.undo()
    many, texture = render(base.replace("{lights}", lights_text(2100, 1e-3)), "m")
    assert texture
    none, _ = render(base.replace("{lights}", ""), "n")
    assert np.abs(many - none).max() > 0.2


@pytest.mark.parametrize("mode", ["off", "hybrid"])
def test_a_zero_normal_shades_as_ambient_only(ctx, tmp_path, mode):
    """A quad listed with both windings on shared vertices has (next to) zero vertex
    normals (trimesh: 0 or ~1e-32, whose square underflows in float32): normalize(0) is
    undefined in GLSL (NaN on llvmpipe), so such a surface is lit by the ambient term
    alone, and the normal target holds 0, not NaN, on every driver."""
    (tmp_path / "quad.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                       "f 1 2 3\nf 1 3 4\nf 1 3 2\nf 1 4 3\n")
    sc = scene_from(tmp_path, """
        ambient = [0.25, 0.5, 0.75]
        background = [0.25, 0.5, 0.75]
        [camera]
        position = [0.0, 0.0, 4.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 50.0
        shutter = 0.04
        [[lights]]
        direction = [-0.3, -0.5, -1.0]
        [[objects]]
        mesh = "quad.obj"
        velocity = [5.0, 0.0, 0.0]
        material = { albedo = [1.0, 1.0, 1.0], specular = 0.5 }
    """)
    assert np.abs(sc.objects[0].mesh.vertex_normals).max() < 1e-30
    r = Renderer(ctx, sc, (64, 36))
    try:
        ids = r.render("off", 0.0, ParamSet()) and r.buffers()["id"]
        p = ParamSet()
        if mode == "hybrid":
            p.set("hybrid.range_check", True)      # (the hybrid writes normals for it)
        img = r.render(mode, 0.0, p).image
        bufs = r.buffers()
    finally:
        r.release()
    for name, a in bufs.items():
        assert np.isfinite(a).all(), name
    quad = ids > 0
    assert quad.sum() > 200
    assert not np.abs(bufs["normal"][..., :3][quad]).any()
    # (the background is the ambient colour: blurred or not, every pixel is that colour)
    np.testing.assert_allclose(img, np.broadcast_to([0.25, 0.5, 0.75], img.shape), atol=1e-6)


def test_an_image_texture_past_the_drivers_size_limit_is_a_scene_error(ctx, tmp_path):
    import trimesh
    from PIL import Image
    from world.errors import SceneError
    from viewer.render.graph.gpu_scene import GpuScene
    limit = ctx.info["GL_MAX_TEXTURE_SIZE"]
    Image.new("RGB", (limit + 1, 1), (255, 128, 0)).save(tmp_path / "wide.png")
    m = trimesh.creation.box(extents=[1, 1, 1])
    m.visual = trimesh.visual.TextureVisuals(uv=m.vertices[:, :2] + 0.5)
    m.export(tmp_path / "box.obj")
    sc = scene_from(tmp_path, """
        [camera]
        position = [0.0, 0.0, 3.0]
        look_at = [0.0, 0.0, 0.0]
        fov_y = 50.0
        [[objects]]
        name = "crate"
        mesh = "box.obj"
        material = { texture = { kind = "image", path = "wide.png" } }
    """)
    with pytest.raises(SceneError) as info:
        GpuScene(ctx, sc)
    assert "objects[1] (crate).material.texture.path" in str(info.value)
    assert f"at most {limit} px" in str(info.value)


@pytest.mark.parametrize("mode", ["off", "reference", "hybrid"])
def test_depth_holds_with_a_tiny_near_and_far_surfaces(ctx, tmp_path, mode):
    """near 1e-4: the standard mapping in a 24-bit buffer rounded a wall at 2000 m to
    depth 1 (gone), and a box 30 m behind another at 1000 m showed through it. With
    reversed Z in a float buffer (viewer/render/graph/depth.py) both render as a ray caster
    sees them."""
    from viewer.render.graph import depth
    assert depth.reversed_z(ctx)                 # (llvmpipe: GL 4.5)
    sc = scene_from(tmp_path, """
        background = [0.0, 0.0, 1.0]
        ambient = [1.0, 1.0, 1.0]
        [camera]
        position = [0.0, 0.0, 0.0]
        look_at = [0.0, 0.0, -1.0]
        fov_y = 50.0
        near = 0.0001
        far = 100000.0
        shutter = 0.04
        [[objects]]
        mesh = { box = [2000.0, 2000.0, 1.0] }
        position = [-1000.0, 0.0, -2000.0]
        material = { albedo = [1.0, 0.0, 0.0] }
        [[objects]]
        mesh = { box = [200.0, 200.0, 10.0] }
        position = [300.0, 0.0, -1035.0]
        material = { albedo = [1.0, 1.0, 0.0] }
        [[objects]]
        mesh = { box = [400.0, 400.0, 400.0] }
        position = [300.0, 0.0, -1200.0]
        velocity = [100.0, 0.0, 0.0]
        material = { albedo = [0.0, 1.0, 0.0] }
    """)
    r = Renderer(ctx, sc, (64, 36))
    try:
        img = r.render(mode, 0.0, ParamSet(), read_image=True).image
    finally:
        r.release()
    red = (img[..., 0] > 0.99) & (img[..., 1] < 0.01)
    yellow = (img[..., 0] > 0.99) & (img[..., 1] > 0.99)
    green = (img[..., 1] > 0.99) & (img[..., 0] < 0.01)
    assert red.sum() > 100                       # the far wall, left half
    assert green.sum() > 50 and yellow.sum() == 0   # the nearer box hides the one behind


@pytest.mark.parametrize("mode", ["off", "hybrid"])
def test_a_scene_far_from_the_origin_renders_as_at_the_origin(ctx, tmp_path, mode):
    """The G-buffer's and reveal_shade's transforms are composed on the host in float64
    relative to the eye: the conformance scene `basic` moved 1e5 m along x (camera and
    objects) gives the same image (in float32 world space 1221 of its `off` pixels moved,
    381 by more than 2)."""
    import re
    src = (CONFORMANCE / "basic.toml").read_text()

    def moved(text, dx):
        def one(m):
            v = [float(x) for x in m.group(2).split(",")]
            return f"{m.group(1)}[{v[0] + dx!r}, {v[1]!r}, {v[2]!r}]"
        return re.sub(r"((?:position|look_at)\s*=\s*)\[([^\]]*)\]", one, text)
    images = []
    for dx in (0.0, 1e5):
        p = tmp_path / f"moved{int(dx)}.toml"
        p.write_text(moved(src, dx))
        r = Renderer(ctx, load_scene(p), (160, 90))
        try:
            images.append(linear_to_srgb8(r.render(mode, 0.0, ParamSet()).image))
        finally:
            r.release()
    assert len(re.findall(r"(?:position|look_at)\s*=", src)) >= 5
    np.testing.assert_array_equal(images[1], images[0])
