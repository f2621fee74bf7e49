"""The CPU ray tracer against analytic scenes, an independent numpy ray caster and the
conformance data of an independent Embree renderer."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import trimesh

from raytrace import RayScene, kernels, reveal
from raytrace import embree_scene
from raytrace.embree_scene import transform_points
from raytrace.workers import run_all
from raytrace.reveal import primary_view
from world.camera import Camera
from world.conventions import BACKGROUND_DEPTH
from world.scene import CameraSpec, Material, Mesh, Scene, SceneObject

CONFORMANCE = Path(__file__).parent / "conformance"
A = np.array


# ---------------------------------------------------------------- scene building helpers

def mesh_of(tm: trimesh.Trimesh, uv=None) -> Mesh:
    return Mesh(np.asarray(tm.vertices, dtype=np.float64), np.asarray(tm.faces, dtype=np.int64),
                np.asarray(tm.vertex_normals, dtype=np.float64),
                np.asarray(tm.face_normals, dtype=np.float64), uv)


def box(extents) -> Mesh:
    return mesh_of(trimesh.creation.box(extents=extents))


def obj(oid: int, mesh: Mesh, shading="flat", **kw) -> SceneObject:
    kw = {k: np.asarray(v, dtype=np.float64) for k, v in kw.items()}
    return SceneObject(f"o{oid}", oid, mesh, Material(), shading, **kw)


def scene_of(objects, eye=(0, 0, 0), look_at=(0, 0, -1), fov_y=90.0, near=0.05, far=100.0):
    cam = CameraSpec(A(eye, dtype=float), A(look_at, dtype=float), fov_y, near=near, far=far)
    return Scene("test", None, cam, objects=list(objects))


def down_z(n=1, xy=(0.0, 0.0)):
    """Rays from (x, y, 0) along -z."""
    o = np.tile(np.r_[xy, 0.0], (n, 1)).astype(np.float32)
    d = np.tile([0.0, 0.0, -1.0], (n, 1)).astype(np.float32)
    return o, d


def moller_trumbore(o, d, tri):
    """Independent reference: nearest hit of rays (n,3) against triangles (m,3,3)."""
    e1 = tri[:, 1] - tri[:, 0]
    e2 = tri[:, 2] - tri[:, 0]
    p = np.cross(d[:, None, :], e2[None])                      # (n, m, 3)
    det = np.einsum("mk,nmk->nm", e1, p)
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    s = o[:, None, :] - tri[None, :, 0]
    u = np.einsum("nmk,nmk->nm", s, p) * inv
    q = np.cross(s, e1[None])
    v = np.einsum("nk,nmk->nm", d, q) * inv
    t = np.einsum("mk,nmk->nm", e2, q) * inv
    valid = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    t = np.where(valid, t, np.inf)
    k = np.argmin(t, axis=1)
    r = np.arange(len(o))
    return k, t[r, k], u[r, k], v[r, k]


# ---------------------------------------------------------------- embree conventions

def test_barycentrics_weight_vertices_1_and_2_and_distance_is_metres():
    v = A([[1.0, -1.0, -4.0], [3.0, 0.5, -5.0], [0.0, 2.0, -6.0]])
    tri = Mesh(v, A([[0, 1, 2]]), np.tile([0.0, 0.0, 1.0], (3, 1)), A([[0.0, 0.0, 1.0]]))
    rs = RayScene(scene_of([obj(1, tri)]))
    w_true = A([[0.2, 0.5, 0.3], [0.6, 0.1, 0.3], [0.1, 0.1, 0.8]])
    target = w_true @ v
    o = np.zeros((3, 3), dtype=np.float32)
    d = target / np.linalg.norm(target, axis=1, keepdims=True)
    hits = rs.intersect(o, d.astype(np.float32), 0.0)
    assert hits.object_id.tolist() == [1, 1, 1]
    assert hits.prim_id.tolist() == [0, 0, 0]
    # u weights V1 and v weights V2: hit = (1-u-v) V0 + u V1 + v V2.
    np.testing.assert_allclose(np.c_[hits.u, hits.v], w_true[:, 1:], atol=2e-6)
    np.testing.assert_allclose(hits.distance, np.linalg.norm(target, axis=1), rtol=1e-6)


def test_miss_reads_id_zero_prim_minus_one_distance_inf():
    rs = RayScene(scene_of([obj(1, box([1, 1, 1]), position=[0, 0, -5])]))
    o, d = down_z(2)
    o[1] = [5.0, 0.0, 0.0]
    hits = rs.intersect(o, d, 0.0)
    assert hits.object_id.tolist() == [1, 0]
    assert hits.prim_id[1] == -1 and np.isinf(hits.distance[1])
    assert hits.distance[0] == pytest.approx(4.5, rel=1e-6)


def test_empty_batch():
    rs = RayScene(scene_of([obj(1, box([1, 1, 1]), position=[0, 0, -5])]))
    hits = rs.intersect(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.float32), 0.0)
    assert hits.object_id.shape == (0,) and hits.queries == 0


# ---------------------------------------------------------------- analytic scenes

def wall_scene():
    """A static slab whose front face is the plane z = -2.9 and another at z = -7.9."""
    return scene_of([obj(1, box([20, 20, 0.2]), position=[0, 0, -3]),
                     obj(2, box([40, 40, 0.2]), position=[0, 0, -8])])


def test_static_planes_at_analytic_distances():
    rs = RayScene(wall_scene())
    d = A([[0.0, 0.0, -1.0], [0.3, 0.1, -1.0], [-0.5, 0.4, -1.0]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hits = rs.intersect(np.zeros((3, 3), np.float32), d.astype(np.float32), 0.0)
    assert hits.object_id.tolist() == [1, 1, 1]
    np.testing.assert_allclose(hits.distance, 2.9 / -d[:, 2], rtol=1e-6)


def test_rays_through_pixel_centres_project_back_to_them():
    spec_scene = scene_of([obj(1, box([20, 20, 0.2]), position=[0, 0, -3]),
                           obj(2, mesh_of(trimesh.creation.icosphere(2, radius=0.5)),
                               "smooth", position=[0.4, -0.2, -2.0])],
                          eye=(0.3, 0.2, 1.0), look_at=(0.1, -0.1, -3.0), fov_y=50.0)
    cam = Camera(spec_scene.camera, 12, 8)
    jj, ii = np.mgrid[0:8, 0:12]
    pix = np.c_[ii.ravel(), jj.ravel()]
    res = reveal(RayScene(spec_scene), cam, 0.0, pix, np.zeros(len(pix)), threads=1)
    layer = res.layer
    assert (layer.object_id != 0).all() and set(layer.object_id.tolist()) == {1, 2}
    win, depth = cam.project(0.0, layer.world_position)
    # GL window y is up: image row j's centre is at height - (j + 0.5).
    np.testing.assert_allclose(win[:, 0], pix[:, 0] + 0.5, atol=1e-6)
    np.testing.assert_allclose(win[:, 1], 8 - (pix[:, 1] + 0.5), atol=1e-6)
    np.testing.assert_allclose(layer.depth, depth, rtol=1e-9)
    # Hits on the wall lie on its front face, the plane z = -2.9.
    on_wall = layer.object_id == 1
    np.testing.assert_allclose(layer.world_position[on_wall, 2], -2.9, atol=1e-5)


def test_near_and_far_clip_like_the_rasteriser():
    s = scene_of([obj(1, box([4, 4, 0.02]), position=[0, 0, -0.03]),     # in front of near
                  obj(2, box([4, 4, 0.2]), position=[0, 0, -3])], near=0.05, far=5.0)
    cam = Camera(s.camera, 3, 3)
    res = reveal(RayScene(s), cam, 0.0, A([[1, 1]]), A([0]), threads=1)
    assert res.layer.object_id.tolist() == [2]
    assert res.layer.depth[0] == pytest.approx(2.9, rel=1e-6)
    far = scene_of(s.objects[1:], far=2.0)
    res = reveal(RayScene(far), Camera(far.camera, 3, 3), 0.0, A([[1, 1]]), A([0]), threads=1)
    assert res.layer.object_id.tolist() == [0]
    assert res.layer.depth[0] == BACKGROUND_DEPTH and np.isinf(res.layer.distance[0])


# ---------------------------------------------------------------- moving objects

def moving_object(oid=1):
    """A non-uniformly scaled, rotated, translating and spinning icosphere."""
    return obj(oid, mesh_of(trimesh.creation.icosphere(1, radius=0.6)), "smooth",
               position=[0.2, -0.1, -4.0], rotation=[20.0, -35.0, 10.0], scale=[1.5, 0.7, 1.1],
               velocity=[3.0, 1.0, -2.0], angular_velocity=[0.5, 2.0, -1.0])


@pytest.mark.parametrize("t", [-0.1, 0.0, 0.13])
def test_moving_hit_matches_numpy_raycast_of_transformed_mesh(t):
    o_ = moving_object()
    rs = RayScene(scene_of([o_]))
    m = o_.matrix(t)
    world = o_.mesh.vertices @ m[:3, :3].T + m[:3, 3]
    centre = m[:3, 3]
    rng = np.random.default_rng(7)
    eye = A([0.1, 0.3, 0.5])
    aim = centre + rng.uniform(-1.2, 1.2, size=(200, 3))
    d = aim - eye
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.tile(eye, (len(d), 1))
    hits = rs.intersect(o.astype(np.float32), d.astype(np.float32), t)
    k, dist, u, v = moller_trumbore(o, d, world[o_.mesh.faces])
    ref_hit = np.isfinite(dist)
    assert 40 < ref_hit.sum() < 200           # both hits and misses are exercised
    # Rays grazing an edge may round to either side; all but a few must agree exactly.
    agree = ((hits.object_id != 0) == ref_hit) & (~ref_hit | (hits.prim_id == k))
    assert (~agree).sum() <= 2
    both = agree & ref_hit
    np.testing.assert_allclose(hits.distance[both], dist[both], rtol=2e-5)
    np.testing.assert_allclose(hits.u[both], u[both], atol=5e-4)
    np.testing.assert_allclose(hits.v[both], v[both], atol=5e-4)
    assert (hits.object_id[ref_hit & agree] == 1).all()


def test_the_hit_face_and_barycentrics_map_by_m_of_t_to_the_world_hit():
    t = 0.07
    o_ = moving_object(2)
    s = scene_of([obj(1, box([20, 20, 0.2]), position=[0, 0, -9]), o_], fov_y=60.0)
    cam = Camera(s.camera, 40, 40)
    jj, ii = np.mgrid[0:40, 0:40]
    pix = np.c_[ii.ravel(), jj.ravel()]
    layer = reveal(RayScene(s), cam, t, pix, np.zeros(len(pix)), threads=1).layer
    for oid in (1, 2):
        h = layer.object_id == oid
        assert h.sum() > 20
        mesh, m = s.objects[oid - 1].mesh, s.objects[oid - 1].matrix(t)
        corners = mesh.vertices[mesh.faces[layer.prim_id[h]]]          # (n, 3, 3), local
        u, v = layer.barycentrics[h, :1], layer.barycentrics[h, 1:]
        local = (1 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]
        world = local @ m[:3, :3].T + m[:3, 3]
        np.testing.assert_allclose(world, layer.world_position[h], atol=2e-5)


def test_scaled_moving_object_reports_world_distance():
    # Scale 2 in local space: a renormalised local direction would halve the distance.
    s = scene_of([obj(1, box([1, 1, 1]), position=[0, 0, -6], scale=[2.0, 3.0, 2.0],
                      velocity=[0.5, 0, 0])])
    hits = RayScene(s).intersect(*down_z(1), t=0.0)
    assert hits.object_id[0] == 1 and hits.distance[0] == pytest.approx(5.0, rel=1e-6)
    hits = RayScene(s).intersect(*down_z(1, xy=(1.4, 0.0)), t=1.0)     # moved +0.5 in x
    assert hits.object_id[0] == 1 and hits.distance[0] == pytest.approx(5.0, rel=1e-6)
    hits = RayScene(s).intersect(*down_z(1, xy=(-0.9, 0.0)), t=1.0)
    assert hits.object_id[0] == 0


# ---------------------------------------------------------------- exclusion and restarts

def test_moving_own_object_reveals_the_static_wall_behind():
    s = scene_of([obj(1, box([20, 20, 0.2]), position=[0, 0, -3]),
                  obj(2, mesh_of(trimesh.creation.icosphere(2, radius=0.5)), "smooth",
                      position=[0, 0, -1.5], velocity=[1.0, 0, 0])])
    rs = RayScene(s)
    o, d = down_z(2)
    plain = rs.intersect(o, d, 0.0)
    assert plain.object_id.tolist() == [2, 2]
    assert plain.distance[0] == pytest.approx(1.0, abs=1e-2)   # tessellated sphere
    hits = rs.intersect(o, d, 0.0, exclude_ids=A([2, 1]))
    assert hits.object_id.tolist() == [1, 2]
    assert hits.distance[0] == pytest.approx(2.9, rel=1e-6)
    assert hits.restarts == 0          # a moving object is skipped, not restarted


def test_rigid_body_of_a_moving_own_object_is_passed_not_revealed():
    """A wheel hidden under a moving car's body moves with it: the body's motion never
    uncovers it, so a ray from a body pixel passes it to the ground (it was revealed,
    a patch of wheel colour under the car). A wheel with its own spin is another body."""
    ground = obj(1, box([20, 20, 0.2]), position=[0, 0, -4])
    body = obj(2, box([2, 2, 0.4]), position=[0, 0, -2], velocity=[1.0, 0, 0])
    wheel = obj(3, box([1, 1, 0.4]), position=[0, 0, -0.6])
    wheel.parent = body
    spun = obj(4, box([1, 1, 0.4]), position=[0, 0, -0.6], angular_velocity=[0, 0, 1.0])
    spun.parent = body
    o, d = down_z(1, xy=(0.0, 0.0))
    for own_first, rest in ((body, wheel), (wheel, body)):
        rs = RayScene(scene_of([ground, body, wheel]))
        hits = rs.intersect(o, d, 0.0, exclude_ids=A([own_first.id]))
        assert hits.object_id.tolist() == [1]
        assert hits.distance[0] == pytest.approx(3.9, rel=1e-6)
    rs = RayScene(scene_of([ground, body, spun]))
    assert rs.intersect(o, d, 0.0, exclude_ids=A([2])).object_id.tolist() == [4]
    rs.cull = False                     # the plain per-object row selection agrees
    assert rs.intersect(o, d, 0.0, exclude_ids=A([2])).object_id.tolist() == [4]


def test_static_own_object_is_passed_by_restarts():
    rs = RayScene(wall_scene(), exclusion_budget=0)
    o, d = down_z(3)
    hits = rs.intersect(o, d, 0.0, exclude_ids=A([1, 2, 0]))
    assert hits.object_id.tolist() == [2, 1, 1]
    np.testing.assert_allclose(hits.distance, [7.9, 2.9, 2.9], rtol=1e-6)
    # Ray 0 stops on the slab's front face and its back face: two restarts.
    assert hits.restarts == 2 and hits.unresolved == 0
    assert hits.queries == 3 + 2


def test_static_own_object_is_passed_in_its_exclusion_scene():
    rs = RayScene(wall_scene())
    o, d = down_z(3)
    hits = rs.intersect(o, d, 0.0, exclude_ids=A([1, 2, 0]))
    assert hits.object_id.tolist() == [2, 1, 1]
    np.testing.assert_allclose(hits.distance, [7.9, 2.9, 2.9], rtol=1e-6)
    # One query per ray: rays 0 and 1 in the scenes without objects 1 and 2, ray 2 in the
    # whole static scene; no restarts, and each exclusion scene is built once.
    assert hits.restarts == 0 and hits.queries == 3
    assert rs.exclusion_scene(1) is rs.exclusion_scene(1)
    assert rs.exclusion_scene(1)[1].tolist() == [0, 2]      # geomID + 1 -> object id


def test_exclusion_scenes_stop_at_the_triangle_budget():
    # Each exclusion scene of the wall scene holds the other object's 12 triangles: a
    # budget of 12 builds the first one asked for; the other object is passed by restarts.
    rs = RayScene(wall_scene(), exclusion_budget=12)
    assert rs.exclusion_scene(2)[1].tolist() == [0, 1] and rs.exclusion_scene(1) is None
    hits = rs.intersect(*down_z(2), t=0.0, exclude_ids=A([1, 2]))
    assert hits.object_id.tolist() == [2, 1]
    np.testing.assert_allclose(hits.distance, [7.9, 2.9], rtol=1e-6)
    assert hits.restarts == 2          # ray 0 leaves its own slab (object 1) by restarts


def test_exclusion_scenes_and_restarts_find_the_same_hits():
    """Random rays through a busy scene, every ray's own object drawn at random: the
    exclusion scenes give the restarts' hits, and distances within the restart offset."""
    s = busy_scene()
    rng = np.random.default_rng(3)
    n = 4000
    o = np.tile([0.0, 0.0, 0.0], (n, 1)) + rng.normal(0, 0.3, (n, 3))
    d = np.c_[rng.uniform(-0.6, 0.6, (n, 2)), -np.ones(n)]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    own = rng.integers(0, 5, n).astype(np.uint32)
    a = RayScene(s).intersect(o, d, 0.05, exclude_ids=own)
    b = RayScene(s, exclusion_budget=0).intersect(o, d, 0.05, exclude_ids=own)
    assert b.restarts > 100 and a.restarts == 0 and a.queries < b.queries
    np.testing.assert_array_equal(a.object_id, b.object_id)
    np.testing.assert_array_equal(a.prim_id, b.prim_id)
    hit = a.object_id != 0
    np.testing.assert_allclose(a.distance[hit], b.distance[hit], rtol=1e-5)


@pytest.mark.parametrize("front", [False, True])
def test_bench_ceiling_traces_the_reveals_rays_into_its_scenes(front, monkeypatch):
    """`hmblur bench`'s bare-Embree ceiling: its calls, merged nearest-first, find the
    reveal's hit distance on every ray (static own objects skipped in their exclusion
    scenes, moving ones not traced); front=True stops rays at a static own object."""
    from raytrace.bench import bare_embree_rays_per_s, ceiling_jobs
    s = busy_scene()
    cam = Camera(s.camera, 64, 48)
    rng = np.random.default_rng(5)
    px = np.c_[rng.integers(0, 64, 500), rng.integers(0, 48, 500)]
    own = rng.integers(0, 5, 500).astype(np.uint32)
    rs = RayScene(s)
    batch = {"rayscene": rs, "camera": cam, "pixels": px, "own": own, "t": 0.05}
    best = np.full(len(px), np.inf)
    for es, o, d, rows in ceiling_jobs(batch, front):
        r = embree_scene._embree_run(es, o, d, np.full(len(rows), np.inf, np.float32))
        hit = r["geomID"] >= 0
        np.minimum.at(best, rows[hit], r["tfar"][hit])
    o, d = cam.rays(0.05, px[:, 0], px[:, 1])
    static_own = np.isin(own, rs.static_ids)
    want = rs.intersect(o, d, 0.05, exclude_ids=np.where(static_own & front, 0, own))
    # The two ceilings differ on many rays (a static own object in front).
    other = rs.intersect(o, d, 0.05, exclude_ids=np.where(static_own & ~front, 0, own))
    assert (want.object_id != 0).sum() > 300 and (want.distance != other.distance).sum() > 60
    np.testing.assert_allclose(best, want.distance, rtol=1e-5)
    # Rays per second: the rays over the clock's time around the runs (a scripted clock).
    from types import SimpleNamespace
    import raytrace.bench as rb
    ticks = iter([10.0, 10.25])
    monkeypatch.setattr(rb, "time", SimpleNamespace(perf_counter=lambda: next(ticks)))
    assert bare_embree_rays_per_s(batch, repeats=1, front=front) == len(px) / 0.25
    assert bare_embree_rays_per_s(dict(batch, pixels=px[:0], own=own[:0])) == 0.0


def test_restarts_are_bounded_by_max_restarts():
    rs = RayScene(wall_scene(), exclusion_budget=0)
    hits = rs.intersect(*down_z(1), t=0.0, exclude_ids=A([1]), max_restarts=1)
    assert hits.object_id.tolist() == [0] and hits.unresolved == 1 and hits.restarts == 1


def test_static_own_restart_stops_at_a_nearer_moving_object():
    # A moving sheet between the two faces of the own slab wins over the wall behind it.
    s = scene_of([obj(1, box([20, 20, 1.0]), position=[0, 0, -3]),
                  obj(2, box([20, 20, 0.2]), position=[0, 0, -8]),
                  obj(3, box([1, 1, 0.1]), position=[0, 0, -3], velocity=[0, 1, 0])])
    for budget, restarts in ((0, 1), (10**6, 0)):
        hits = RayScene(s, exclusion_budget=budget).intersect(*down_z(1), t=0.0,
                                                             exclude_ids=A([1]))
        assert hits.object_id.tolist() == [3]
        assert hits.distance[0] == pytest.approx(2.95, rel=1e-6)
        # Restarts: the front face only, the moving hit bounds the rest.
        assert hits.restarts == restarts


def same_colour_pair():
    """Two moving boxes of the same material: A (id 2) at z=-2, B (id 3) at z=-4 to the
    right, over a static wall (id 1) at z = -6 (front face -5.9)."""
    return scene_of([obj(1, box([40, 40, 0.2]), position=[0, 0, -6]),
                     obj(2, box([2, 2, 0.2]), position=[0, 0, -2], velocity=[1, 0, 0]),
                     obj(3, box([2, 2, 0.2]), position=[1.5, 0, -4], velocity=[-1, 0, 0])])


def test_same_coloured_moving_objects_reveal_by_id():
    rs = RayScene(same_colour_pair())
    o = A([[0.8, 0.0, 0.0], [-0.8, 0.0, 0.0]], dtype=np.float32)   # behind A: B; nothing
    d = np.tile(A([0, 0, -1.0], dtype=np.float32), (2, 1))
    plain = rs.intersect(o, d, 0.0)
    assert plain.object_id.tolist() == [2, 2]
    hits = rs.intersect(o, d, 0.0, exclude_ids=A([2, 2]))
    assert hits.object_id.tolist() == [3, 1]
    np.testing.assert_allclose(hits.distance, [3.9, 5.9], rtol=1e-6)
    # B's own pixel reveals the wall, never A (which is in front of it, not behind).
    assert rs.intersect(o[:1] + A([[0, 0, -3.0]], dtype=np.float32), d[:1], 0.0,
                        exclude_ids=A([3])).object_id.tolist() == [1]


# ---------------------------------------------------------------- attributes

def one_triangle(uv=None) -> Mesh:
    v = A([[-1.0, -1.0, -3.0], [2.0, -1.0, -3.0], [-1.0, 2.0, -3.0]])
    vn = A([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 2.0, 1.0]])     # deliberately unequal
    return Mesh(v, A([[0, 1, 2]]), vn, A([[0.0, 0.0, 1.0]]), uv)


def corners_at(rs: RayScene, hits) -> np.ndarray:
    """(n, 3 corners, 8) of each hit's face as the GPU reads them: position, shading normal,
    uv (SurfaceTable.gpu_corners, at the face's row)."""
    rows = rs.surfaces.face_offset[hits.object_id] + hits.prim_id
    return rs.surfaces.gpu_corners()[rows]


def interpolate(corners, u, v) -> np.ndarray:
    """What the shader interpolates at Embree's (u, v): (1-u-v) c0 + u c1 + v c2."""
    u, v = np.asarray(u, np.float64)[:, None], np.asarray(v, np.float64)[:, None]
    return (1 - u - v) * corners[:, 0] + u * corners[:, 1] + v * corners[:, 2]


def test_smooth_faces_carry_the_vertex_normals_and_the_hit_interpolates_them():
    s = scene_of([obj(1, one_triangle(), "smooth")])
    rs = RayScene(s)
    hits = rs.intersect(*down_z(1, xy=(0.5, 0.0)), t=0.0)
    # (0.5, 0) = (1-u-v) V0 + u V1 + v V2 with u = 0.5, v = 1/3.
    assert (hits.u[0], hits.v[0]) == pytest.approx((0.5, 1 / 3), abs=1e-6)
    c = corners_at(rs, hits)
    np.testing.assert_array_equal(c[0, :, 3:6], one_triangle().vertex_normals)
    np.testing.assert_allclose(interpolate(c[..., :3], hits.u, hits.v)[0], [0.5, 0.0, -3.0],
                               atol=1e-6)


def test_flat_faces_carry_the_face_normal_at_every_corner():
    s = scene_of([obj(1, one_triangle(), "flat")])
    rs = RayScene(s)
    hits = rs.intersect(*down_z(1, xy=(0.5, 0.0)), t=0.0)
    np.testing.assert_array_equal(corners_at(rs, hits)[0, :, 3:6], np.tile([0.0, 0.0, 1.0], (3, 1)))


def test_box_flat_normals_follow_the_face_hit():
    b = box([1, 1, 1])
    s = scene_of([obj(1, b, position=[0, 0, -3], rotation=[0, 90, 0], velocity=[0, 0, 1])])
    rs = RayScene(s)
    layer = reveal(rs, Camera(s.camera, 3, 3), 0.0, A([[1, 1]]), A([0]), threads=1).layer
    normals = rs.surfaces.gpu_corners()[rs.surfaces.face_offset[1] + layer.prim_id[0], :, 3:6]
    # Rotated 90 degrees about y, the face seen from +z is the local -x face.
    np.testing.assert_allclose(normals, np.tile([-1.0, 0.0, 0.0], (3, 1)), atol=1e-7)
    np.testing.assert_allclose(b.face_normals[layer.prim_id[0]], [-1.0, 0.0, 0.0], atol=1e-12)


def test_uv_is_interpolated_and_zero_without_uv():
    uv = A([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    s = scene_of([obj(1, one_triangle(uv)), obj(2, box([9, 9, 0.1]), position=[0, 0, -5])])
    rs = RayScene(s)
    o = A([[0.5, 0.0, 0.0], [2.5, 2.5, 0.0]], dtype=np.float32)
    d = np.tile(A([0, 0, -1.0], dtype=np.float32), (2, 1))
    hits = rs.intersect(o, d, 0.0)
    assert hits.object_id.tolist() == [1, 2]
    uvs = interpolate(corners_at(rs, hits)[..., 6:8], hits.u, hits.v)
    np.testing.assert_allclose(uvs, [[0.5, 1 / 3], [0.0, 0.0]], atol=1e-6)


# ---------------------------------------------------------------- threads and determinism

def busy_scene():
    return scene_of([obj(1, box([40, 40, 0.2]), position=[0, 0, -8]),
                     obj(2, box([3, 3, 0.5]), position=[-1, 0, -5]),
                     moving_object(3),
                     obj(4, mesh_of(trimesh.creation.icosphere(2, radius=0.8)), "smooth",
                         position=[1.0, 0.5, -5.0], velocity=[-2, 0, 0])], fov_y=60.0)



def test_split_embree_calls_give_the_single_threaded_result(monkeypatch):
    # One chunk whose Embree calls run on worker threads: the exclusion scenes' calls side
    # by side, every other call split into parts (PARALLEL_RAYS lowered so 1920 rays do).
    s = busy_scene()
    cam = Camera(s.camera, 48, 40)
    jj, ii = np.mgrid[0:40, 0:48]
    pix = np.c_[ii.ravel(), jj.ravel()]
    own = np.random.default_rng(2).integers(0, 5, len(pix))
    single = reveal(RayScene(s), cam, 0.05, pix, own, threads=1)
    calls = []
    run = embree_scene.run_all

    def counting(jobs, sizes, threads, purpose):
        calls.append((len(jobs), threads))
        return run(jobs, sizes, threads, purpose)
    monkeypatch.setattr(embree_scene, "run_all", counting)
    monkeypatch.setattr(embree_scene, "PARALLEL_RAYS", 64)
    split = reveal(RayScene(s), cam, 0.05, pix, own, threads=3)
    assert any(n > 1 and k == 3 for n, k in calls)           # the threads were used
    for name in ("rays", "queries", "restarts", "unresolved", "pixels_hit"):
        assert getattr(split, name) == getattr(single, name), name
    for name in single.layer.__dataclass_fields__:
        if name != "table":
            np.testing.assert_array_equal(getattr(single.layer, name), getattr(split.layer, name),
                                          name)


def test_run_all_runs_every_job_once_and_keeps_their_order():
    import threading
    seen = []
    jobs = [lambda k=k: (seen.append((k, threading.get_ident())), k * k)[1] for k in range(7)]
    assert run_all(jobs, [1, 5, 2, 9, 3, 3, 0], 3, "test") == [k * k for k in range(7)]
    assert sorted(k for k, _ in seen) == list(range(7))
    assert run_all(jobs[:1], [1], 3, "test") == [0]

def test_threads_give_the_single_threaded_result():
    s = busy_scene()
    rs = RayScene(s)
    cam = Camera(s.camera, 48, 40)
    jj, ii = np.mgrid[0:40, 0:48]
    pix = np.c_[ii.ravel(), jj.ravel()]
    rng = np.random.default_rng(1)
    own = rng.integers(0, 5, len(pix))
    rs_restarts = RayScene(s, exclusion_budget=0)
    assert reveal(rs_restarts, cam, 0.05, pix, own, threads=1).restarts > 0
    single = reveal(rs, cam, 0.05, pix, own, threads=1)
    # 1920 pixels in 12 chunks of 160 over 3 threads (each on a fresh RayScene, so the
    # static hits kept for the view are traced again and the query counts compare).
    multi = reveal(RayScene(s), cam, 0.05, pix, own, threads=3, min_chunk=50)
    again = reveal(RayScene(s), cam, 0.05, pix, own, threads=3, min_chunk=50)
    serial = reveal(RayScene(s), cam, 0.05, pix, own, threads=1, max_chunk=333)
    # And on the first one again, its static hits looked up: the same layer.
    kept = reveal(rs, cam, 0.05, pix, own, threads=3, min_chunk=50)
    assert kept.queries < single.queries
    for r in (multi, again, serial, kept):
        for name in ("rays", "queries", "restarts", "unresolved", "pixels_hit"):
            if r is not kept or name != "queries":
                assert getattr(r, name) == getattr(single, name), name
        for name in single.layer.__dataclass_fields__:
            if name != "table":         # (each RayScene's own attribute table)
                np.testing.assert_array_equal(getattr(single.layer, name), getattr(r.layer, name),
                                              name)


def test_static_hits_are_kept_per_view_and_change_nothing():
    """Primary rays of one view: the static scene is traced once per pixel and looked up
    in later frames; the hits equal tracing without the view (moving objects in front of
    the kept static hit included), frame after frame, and another view traces again.
    The looked-up hits are flagged (from_view)."""
    s = busy_scene()
    cam = Camera(s.camera, 48, 40)
    jj, ii = np.mgrid[0:40, 0:48]
    keys = (jj * 48 + ii).ravel()
    own = np.random.default_rng(4).integers(0, 5, keys.size).astype(np.uint32)
    rs = RayScene(s)
    view = primary_view(cam, 0.05)
    for t, rows in ((0.05, slice(None, None, 2)), (0.05, slice(None)), (0.3, slice(None))):
        o, d = cam.rays(t, ii.ravel()[rows], jj.ravel()[rows])
        got = rs.intersect(o, d, t, own[rows], view=view, pixels=keys[rows])
        want = RayScene(s).intersect(o, d, t, own[rows])
        for name in ("object_id", "prim_id", "u", "v", "distance"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), name)
        moving = np.isin(want.object_id, [3, 4])
        assert moving.any() and (want.object_id == 1).any()
        # from_view: the hits that are the kept static hit (a static object nearest, the
        # ray's own object not static): what the static objects' raster shows there.
        static_hit = np.isin(got.object_id, [1, 2]) & ~np.isin(own[rows], [1, 2])
        np.testing.assert_array_equal(got.from_view, static_hit)
        assert static_hit.any() and not want.from_view.any()
    assert got.queries < want.queries            # the static hits were looked up
    assert rs.static_view(view).known.sum() == np.count_nonzero(~np.isin(own, [1, 2]))
    moved = dataclasses.replace(s.camera, position=s.camera.position + [0.3, 0.0, 0.0])
    assert primary_view(Camera(moved, 48, 40), 0.05)[0] != view[0]
    assert not rs.static_view(primary_view(Camera(moved, 48, 40), 0.05)).known.any()
    # A moving camera's pose is new every frame of an animation: nothing is kept for it.
    panning = dataclasses.replace(s.camera, velocity=np.array([0.5, 0.0, 0.0]))
    assert primary_view(Camera(panning, 48, 40), 0.05) is None


def test_the_view_key_changes_with_each_thing_a_primary_ray_depends_on():
    """primary_view's key (what the static hits are kept by): the same for the same view at
    another time; another for each of the camera's pose, lens, clipping and image size."""
    s = busy_scene().camera
    key = primary_view(Camera(s, 48, 40), 0.05)[0]
    assert primary_view(Camera(dataclasses.replace(s), 48, 40), 0.3)[0] == key
    changed = {
        "position": Camera(dataclasses.replace(s, position=s.position + [0.0, 0.1, 0.0]), 48, 40),
        "look_at": Camera(dataclasses.replace(s, look_at=s.look_at + [0.1, 0.0, 0.0]), 48, 40),
        "up": Camera(dataclasses.replace(s, up=np.array([0.1, 1.0, 0.0])), 48, 40),
        "fov_y": Camera(dataclasses.replace(s, fov_y=s.fov_y + 1.0), 48, 40),
        "near": Camera(dataclasses.replace(s, near=s.near * 2.0), 48, 40),
        "far": Camera(dataclasses.replace(s, far=s.far / 2.0), 48, 40),
        "width": Camera(s, 40, 40),
        "height": Camera(s, 48, 48),
    }
    keys = {name: primary_view(cam, 0.05)[0] for name, cam in changed.items()}
    for name, k in keys.items():
        assert k != key, name
    assert len(set(keys.values())) == len(keys)


def test_reveal_of_no_pixels():
    s = busy_scene()
    res = reveal(RayScene(s), Camera(s.camera, 4, 4), 0.0, np.zeros((0, 2), int), [])
    assert len(res.layer.object_id) == 0
    assert res.rays == res.queries == res.pixels_hit == 0


def test_reveal_checks_its_arguments():
    s = busy_scene()
    rs = RayScene(s)
    cam = Camera(s.camera, 4, 4)
    with pytest.raises(ValueError, match="own ids"):
        reveal(rs, cam, 0.0, A([[0, 0], [1, 1]]), A([0]))


# ---------------------------------------------------------------- conformance

def basic_scene() -> Scene:
    """tests/conformance/basic.toml, built by hand with the trimesh calls of docs/scene-format.md."""
    sphere = mesh_of(trimesh.creation.icosphere(subdivisions=3, radius=0.35))
    objects = [
        obj(1, box([6.1, 0.1, 6.1]), position=[0.0, -0.05, 0.0]),
        obj(2, box([6.1, 3.1, 0.1]), position=[0.0, 1.5, -1.5]),
        obj(3, sphere, "smooth", position=[-0.4, 0.8, 0.8], velocity=[12.0, 0.0, 0.0]),
        obj(4, box([0.5, 0.5, 0.5]), position=[0.9, 0.45, 0.2], rotation=[0.0, 30.0, 0.0],
            angular_velocity=[0.0, 15.0, 0.0]),
    ]
    s = scene_of(objects, eye=(0.0, 1.0, 4.0), look_at=(0.0, 0.7, 0.0), fov_y=40.0)
    s.camera.shutter = 0.05
    return s


def test_conformance_basic_ids_and_depths():
    ref = np.load(CONFORMANCE / "basic.npz")
    h, w = ref["centre_id"].shape
    s = basic_scene()
    jj, ii = np.mgrid[0:h, 0:w]
    pix = np.c_[ii.ravel(), jj.ravel()]
    res = reveal(RayScene(s), Camera(s.camera, w, h), 0.0, pix, np.zeros(len(pix)), threads=2)
    ids = res.layer.object_id.reshape(h, w)
    depth = res.layer.depth.reshape(h, w)
    assert set(np.unique(ids).tolist()) == {0, 1, 2, 3, 4}
    assert (ids != ref["centre_id"]).sum() <= 10          # silhouette pixels at most
    same = (ids == ref["centre_id"]) & (ids > 0)
    rel = np.abs(depth[same] - ref["centre_depth"][same]) / ref["centre_depth"][same]
    assert rel.max() < 1e-3
    assert (depth[ids == 0] == BACKGROUND_DEPTH).all()
    assert res.pixels_hit == (ids > 0).sum()


def loaded(name: str) -> Scene:
    from world.loader import load_scene
    return load_scene(CONFORMANCE / f"{name}.toml")


def all_pixels(w, h):
    jj, ii = np.mgrid[0:h, 0:w]
    return np.c_[ii.ravel(), jj.ravel()]


@pytest.mark.parametrize("name", ["basic", "vase_pan"])
def test_conformance_loaded_scenes_match_ids_and_depths(name):
    ref = np.load(CONFORMANCE / f"{name}.npz")
    s = loaded(name)
    w, h, t = s.render.width, s.render.height, s.render.time
    assert ref["centre_id"].shape == (h, w)
    res = reveal(RayScene(s), Camera(s.camera, w, h), t, all_pixels(w, h),
                 np.zeros(w * h), threads=2)
    ids = res.layer.object_id.reshape(h, w)
    depth = res.layer.depth.reshape(h, w)
    assert (ids != ref["centre_id"]).sum() <= 10
    same = (ids == ref["centre_id"]) & (ids > 0)
    rel = np.abs(depth[same] - ref["centre_depth"][same]) / ref["centre_depth"][same]
    assert rel.max() < 1e-3


def test_reveal_equals_casting_the_scene_without_the_own_object():
    """The oracle of docs/algorithms.md 4.2: for primary rays, passing the own object is the same
    as removing it. Every pixel of basic, own = its own object, static ones included."""
    s = loaded("basic")
    w, h, t = 160, 90, 0.01
    cam = Camera(s.camera, w, h)
    pix = all_pixels(w, h)
    own = reveal(RayScene(s), cam, t, pix, np.zeros(len(pix)), threads=1).layer.object_id
    for budget in (0, 10**6):            # restarts, exclusion scenes
        res = reveal(RayScene(s, exclusion_budget=budget), cam, t, pix, own, threads=1)
        assert (res.restarts > 0) == (budget == 0) and res.unresolved == 0
        check_passes_own_object(s, cam, t, pix, own, res.layer)


def check_passes_own_object(s, cam, t, pix, own, got):
    for k in np.unique(own[own > 0]):
        rows = own == k
        without = Scene(s.name, None, s.camera, objects=[o for o in s.objects if o.id != k])
        want = reveal(RayScene(without), cam, t, pix[rows], np.zeros(rows.sum()),
                      threads=1).layer
        differ = got.object_id[rows] != want.object_id
        assert differ.sum() <= 3, (k, differ.sum())
        both = ~differ & (want.object_id != 0)
        np.testing.assert_allclose(got.depth[rows][both], want.depth[both], rtol=1e-5)
        np.testing.assert_array_equal(got.prim_id[rows][both], want.prim_id[both])


def test_box_culling_changes_no_hit():
    # The world-box test that keeps rays away from moving objects they cannot hit gives
    # exactly the hits of tracing every ray into every moving object.
    s = busy_scene()
    rs = RayScene(s)
    cam = Camera(s.camera, 48, 40)
    jj, ii = np.mgrid[0:40, 0:48]
    o, d = cam.rays(0.05, ii.ravel(), jj.ravel())
    own = np.random.default_rng(2).integers(0, 5, len(o))
    # Also rays that start part-way (past a restart, at the near plane): the test must take
    # [tnear, tfar] from the ray's origin, not from where Embree's ray starts.
    # Starts at 0.6 of the way to a moving hit keep that hit within (tnear, 2 tnear).
    first = rs.intersect(o, d, 0.05, own)
    tnear = np.where(np.isin(first.object_id, [3, 4]), 0.6 * first.distance, 0.0)
    for kw in ({}, {"tnear": tnear}):
        rs.cull = True
        culled = rs.intersect(o, d, 0.05, own, **kw)
        rs.cull = False
        full = rs.intersect(o, d, 0.05, own, **kw)
        assert culled.queries < full.queries
        for name in ("object_id", "prim_id", "u", "v", "distance"):
            np.testing.assert_array_equal(getattr(culled, name), getattr(full, name), name)
        assert np.count_nonzero(np.isin(culled.object_id, [3, 4])) > 50


def many_movers_scene(n=14, seed=5):
    """A floor and n moving boxes and spheres strewn in front of, beside and behind a
    camera that looks down a little (not along an axis), one straddling the eye's plane."""
    rng = np.random.default_rng(seed)
    objects = [obj(1, box([40, 0.2, 40]), position=[0, -1.5, 0])]
    for k in range(n):
        mesh = (box(rng.uniform(0.2, 0.8, 3)) if k % 2 else
                mesh_of(trimesh.creation.icosphere(1, radius=float(rng.uniform(0.2, 0.5)))))
        pos = [rng.uniform(-4, 4), rng.uniform(-1, 2), rng.uniform(-9, 1)]
        if k == 0:
            pos = [0.3, 0.0, 0.1]                          # around the eye's plane
        objects.append(obj(k + 2, mesh, position=pos, velocity=rng.normal(0, 2, 3),
                           angular_velocity=rng.normal(0, 1, 3)))
    return scene_of(objects, eye=(0.2, 0.4, 0.5), look_at=(0.5, -0.3, -6.0), fov_y=70.0)


@pytest.mark.parametrize("order", ["top_down", "bottom_up", "shuffled"])
def test_row_index_changes_no_hit(order):
    # With 8 or more movers, primary rays in image row order take each box test only
    # over the rows its box spans on screen: exactly the hits of testing every ray.
    s = many_movers_scene()
    assert len(RayScene(s).moving) >= embree_scene.ROW_INDEX_MOVERS
    cam = Camera(s.camera, 64, 48)
    jj, ii = np.mgrid[0:48, 0:64]
    pix = np.c_[ii.ravel(), jj.ravel()]
    if order == "bottom_up":
        pix = pix[::-1].copy()
    if order == "shuffled":
        pix = pix[np.random.default_rng(1).permutation(len(pix))]
    o, d = cam.rays(0.02, pix[:, 0], pix[:, 1])
    own = np.random.default_rng(3).integers(0, 8, len(o))
    eye, fwd, up = s.camera.pose(0.02)
    rs = RayScene(s)
    first = rs.intersect(o, d, 0.02, own)
    tnear = np.where(first.object_id > 1, 0.6 * first.distance, 0.0)
    for kw in ({}, {"tnear": tnear}):
        plain = rs.intersect(o, d, 0.02, own, **kw)
        indexed = rs.intersect(o, d, 0.02, own, image_axes=(fwd, up), **kw)
        for name in ("object_id", "prim_id", "u", "v", "distance"):
            np.testing.assert_array_equal(getattr(indexed, name), getattr(plain, name), name)
        assert np.count_nonzero(plain.object_id > 1) > 300
    index = embree_scene.RowIndex.of(eye, d, fwd, up)
    assert (index is None) == (order == "shuffled")
    if index is not None:
        poses = rs._poses(0.02)
        spans = index.spans(poses.lo, poses.hi)
        assert tuple(spans[0]) == (0, len(d))               # straddles the eye's plane
        assert np.mean(spans[1:, 1] - spans[1:, 0]) < 0.6 * len(d)


def test_row_index_kernels_match_numpy():
    # RowIndex's key and spans, compiled (raytrace/kernels.py), against their numpy
    # statements: rays of a 40 x 30 image top-down and bottom-up, boxes in front of the
    # eye, straddling its plane and behind it; out-of-order rays have no index.
    cam_spec = scene_of([], eye=(0.2, 0.4, 0.5), look_at=(0.5, -0.3, -6.0), fov_y=70.0).camera
    cam = Camera(cam_spec, 40, 30)
    eye, fwd, up = (np.asarray(v, np.float64) for v in cam_spec.pose(0.0))
    jj, ii = np.mgrid[0:30, 0:40]
    rng = np.random.default_rng(4)
    centre = eye + fwd * rng.uniform(-2, 12, (60, 1)) + rng.normal(0, 3, (60, 3))
    lo, hi = centre - rng.uniform(0.05, 2, (60, 3)), centre + rng.uniform(0.05, 2, (60, 3))
    pick = np.array([[(i >> k) & 1 for k in range(3)] for i in range(8)], bool)
    for flip in (False, True):
        pix = np.c_[ii.ravel(), jj.ravel()][::-1 if flip else 1]
        _, d = cam.rays(0.0, pix[:, 0], pix[:, 1])
        key, u = -(d @ up) / (d @ fwd), up
        if key[0] > key[-1]:
            key, u = -key, -up
        index = embree_scene.RowIndex.of(eye, d, fwd, up)
        # (the same sums, but numpy's matmul may round them differently: ~1e-16)
        np.testing.assert_allclose(index.key, np.maximum.accumulate(key), rtol=0, atol=1e-14)
        np.testing.assert_array_equal(index.up, u)
        c = np.where(pick[None], hi[:, None, :], lo[:, None, :]) - eye
        along = c @ fwd
        with np.errstate(divide="ignore", invalid="ignore"):
            k = -(c @ u) / along
        pad = 1e-6 * (1.0 + np.abs(k).max(axis=1))
        want = np.stack([np.searchsorted(index.key, k.min(axis=1) - pad, "left"),
                         np.searchsorted(index.key, k.max(axis=1) + pad, "right")], axis=1)
        want[~(along > 0.0).all(axis=1)] = (0, len(d))
        got = index.spans(lo, hi)
        np.testing.assert_array_equal(got, want)
        assert 10 < np.count_nonzero(got[:, 1] - got[:, 0] < len(d)) < 60
    assert embree_scene.RowIndex.of(eye, d[rng.permutation(len(d))], fwd, up) is None
    assert embree_scene.RowIndex.of(eye, np.r_[d, -d[:1]], fwd, up) is None   # one behind


def test_slab_hand_values():
    from raytrace.kernels import box_rows
    o = np.array([[0, 0, 5], [0, 0, 5], [3, 0, 5], [0.5, 0, 5], [0.99, 0, 5]], np.float32)
    d = np.array([[0, 0, -1], [0, 0, 1], [0, 0, -1], [0, 0, -1], [0, 0, -1]], np.float32)
    with np.errstate(divide="ignore"):
        inv_d = np.ascontiguousarray((np.float32(1.0) / d).T)      # (3, n), as box_rows takes it
    lo, hi = np.array([-1.0, -1, -1]), np.array([1.0, 1, 1])
    t0, t1 = np.zeros(5), np.full(5, np.inf)
    excl = np.zeros(5, np.uint32)
    # Towards the box, away from it, beside it, along the x = 0.5 line through it, just
    # inside its x = 1 face.
    n = len(o)
    np.testing.assert_array_equal(box_rows(o, inv_d, False, lo, hi, t0, t1, excl, 7, 0, n),
                                  [0, 3, 4])
    # The box lies 4 to 6 along the first ray: a far limit of 3.9 misses it; an excluded
    # ray is dropped; every ray from the first origin (all but the second meet it).
    assert not len(box_rows(o[:1], inv_d[:, :1], False, lo, hi, t0[:1], np.array([3.9]),
                            excl[:1], 7, 0, 1))
    np.testing.assert_array_equal(box_rows(o, inv_d, False, lo, hi, t0, t1,
                                           np.array([7, 0, 0, 0, 0], np.uint32), 7, 0, n),
                                  [3, 4])
    np.testing.assert_array_equal(box_rows(o, inv_d, True, lo, hi, t0, t1, excl, 7, 0, n),
                                  [0, 2, 3, 4])
    # Only rows first..end-1: the same rows of that span.
    np.testing.assert_array_equal(box_rows(o, inv_d, True, lo, hi, t0, t1, excl, 7, 2, 4),
                                  [2, 3])
    # Several boxes in one call: each box's rows of its own span, its own object skipped.
    from raytrace.kernels import boxes_rows
    los, his = np.array([lo, lo + 10, lo]), np.array([hi, hi + 10, hi])
    excl = np.array([0, 0, 0, 9, 0], np.uint32)
    rows, cuts = boxes_rows(o, inv_d, True, los, his, t0, t1, excl,
                            np.array([7, 8, 9], np.uint32), np.array([[0, 5], [0, 5], [1, 4]]))
    assert cuts.tolist() == [0, 4, 4, 5]
    np.testing.assert_array_equal(rows, [0, 2, 3, 4, 2])     # (ray 1 turns away)


def test_large_views_keep_no_static_hits(monkeypatch):
    import importlib
    rv = importlib.import_module("raytrace.reveal")     # (the package's `reveal` is the function)
    s = busy_scene()
    cam = Camera(s.camera, 48, 40)
    monkeypatch.setattr(rv, "MAX_VIEW_PIXELS", 48 * 40 - 1)
    assert primary_view(cam, 0.0) is None
    rs = RayScene(s)
    pix = np.c_[np.arange(48), np.full(48, 20)]
    a = reveal(rs, cam, 0.0, pix, np.zeros(48), threads=1)
    b = reveal(rs, cam, 0.0, pix, np.zeros(48), threads=1)
    assert a.queries == b.queries > 0 and rs._static_hits is None


def test_group_rows_is_a_stable_sort_by_id():
    from raytrace.kernels import group_rows
    rng = np.random.default_rng(8)
    values = rng.integers(0, 9, 500).astype(np.uint32)
    member = rng.uniform(size=500) < 0.6
    order, starts = group_rows(values, member)
    rows = np.flatnonzero(member)
    want = rows[np.argsort(values[rows], kind="stable")]
    np.testing.assert_array_equal(order, want)
    cuts = np.r_[0, np.flatnonzero(np.diff(values[want])) + 1, len(want)]
    np.testing.assert_array_equal(starts, cuts)
    order, starts = group_rows(values, np.zeros(500, bool))
    assert len(order) == 0 and starts.tolist() == [0]


def test_world_box_and_rotation_flag_match_numpy():
    # The box test's padded world boxes and "directions need the inverse" flags, compiled
    # for all moving objects at once (raytrace/kernels.py), against numpy per object.
    rng = np.random.default_rng(9)
    ms = np.tile(np.eye(4), (50, 1, 1))
    for k in range(1, 50, 2):
        ms[k, :3, :3] = rng.normal(size=(3, 3))
    ms[:, :3, 3] = rng.normal(size=(50, 3)) * 5
    corners = rng.normal(size=(50, 8, 3))
    lo, hi = kernels.world_boxes(ms, corners, 1e-4, 1e-6)
    invs = np.linalg.inv(ms).astype(np.float32)
    flags = kernels.turns_or_scales(invs)
    for k in range(50):
        world = transform_points(ms[k], corners[k])
        pad = 1e-4 * float(np.ptp(world, axis=0).max()) + 1e-6
        np.testing.assert_array_equal(lo[k], world.min(axis=0) - pad)
        np.testing.assert_array_equal(hi[k], world.max(axis=0) + pad)
        inv = np.linalg.inv(ms[k]).astype(np.float32)
        np.testing.assert_array_equal(invs[k], inv)      # batched: the same LU per matrix
        assert flags[k] == (not np.array_equal(inv[:3, :3], np.eye(3)))
        assert flags[k] == bool(k % 2)
    # The poses' inverses, compiled (adjugate over determinant), against LAPACK's to a
    # float32 ulp; a determinant out of its range says so (the caller takes LAPACK's).
    ms[::3, :3, :3] *= -1.0                                 # (mirrored ones too)
    fast, ok = kernels.affine_inverses(ms)
    assert ok
    np.testing.assert_allclose(fast, np.linalg.inv(ms).astype(np.float32), rtol=2e-7,
                               atol=1e-12)
    tiny = np.eye(4)[None].copy()
    tiny[0, :3, :3] *= 1e-110
    assert not kernels.affine_inverses(tiny)[1]


def test_run_all_raises_a_jobs_error_after_every_thread_is_done():
    import threading
    import time
    # A failing job and a slow one run at once on the two threads (each waits for the
    # other to start); whichever thread fails, run_all may raise only once the slow job
    # is done. Repeated, so that the failure falls on each thread.
    for _ in range(8):
        a_started, f_started, finished = threading.Event(), threading.Event(), []

        def slow():
            a_started.set()
            f_started.wait(1.0)
            time.sleep(0.02)
            finished.append(1)

        def fail():
            f_started.set()
            a_started.wait(1.0)
            raise RuntimeError("job failed")
        with pytest.raises(RuntimeError, match="job failed"):
            run_all([slow, fail], [2, 1], 2, "test")
        assert finished == [1]


@pytest.mark.parametrize("static_key", [-1, 9])
def test_record_inputs_match_their_numpy_statements(static_key):
    rng = np.random.default_rng(3)
    n, height = 200, 37
    px = np.c_[rng.integers(0, 50, n), rng.integers(0, height, n)]
    object_id = rng.integers(0, 4, n).astype(np.uint32)
    prim_id = np.where(object_id != 0, rng.integers(0, 30, n), -1).astype(np.int32)
    face_offset = np.array([0, 0, 30, 70], np.int64)
    static_view = rng.uniform(size=n) < 0.3
    from viewer.render.modes.hybrid.reveal_kernels import record_inputs
    gx, gy, key, face = record_inputs(px, height, object_id, prim_id, face_offset,
                                      static_view, static_key)
    np.testing.assert_array_equal(gx, px[:, 0])
    np.testing.assert_array_equal(gy, height - 1 - px[:, 1])
    want = object_id.astype(np.int64) + 1
    if static_key >= 0:
        want[static_view] = static_key
    np.testing.assert_array_equal(key, want)
    np.testing.assert_array_equal(face, np.where(object_id != 0,
                                                 face_offset[object_id] + prim_id, -1))
