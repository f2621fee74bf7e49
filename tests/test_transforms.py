"""Every matrix against an independent numpy formula (pyrr is row-vector and 2019-era)."""
import numpy as np
from world import transforms as tf
from world.camera import Camera
from world.scene import CameraSpec, Material, Mesh, SceneObject


def rodrigues(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def test_axis_angle_matches_rodrigues_and_integer_input():
    for w in ([0, 1, 0], [0.3, -0.2, 0.9], [2, 0, 0]):
        w = np.array(w)
        theta = np.linalg.norm(w)
        assert np.allclose(tf.axis_angle(w), rodrigues(w, theta), atol=1e-12)
    assert np.allclose(tf.axis_angle([0, 0, 0]), np.eye(3))
    # A right-handed quarter turn about z takes x to y.
    assert np.allclose(tf.axis_angle([0, 0, np.pi / 2]) @ [1, 0, 0], [0, 1, 0])


def test_euler_order_is_z_y_x():
    r = tf.euler_xyz_degrees([90, 90, 0])
    # X applied first: y -> z, then Y turns z -> x.
    assert np.allclose(r @ [0, 1, 0], [1, 0, 0], atol=1e-12)
    expect = rodrigues([0, 0, 1], 0.3) @ rodrigues([0, 1, 0], 0.2) @ rodrigues([1, 0, 0], 0.1)
    assert np.allclose(tf.euler_xyz_degrees(np.degrees([0.1, 0.2, 0.3])), expect)


def test_perspective_matches_opengl_formula():
    f = 1 / np.tan(np.radians(45) / 2)
    n, fa, a = 0.1, 50.0, 16 / 9
    expect = np.array([[f / a, 0, 0, 0], [0, f, 0, 0],
                       [0, 0, (fa + n) / (n - fa), 2 * fa * n / (n - fa)], [0, 0, -1, 0]])
    assert np.allclose(tf.perspective(45, a, n, fa), expect)
    # glsl/passes/motion.glsl's to_window relies on exact zeros off the diagonal of x and y and
    # on clip w = -z (a symmetric frustum): clip.xy = (P00, P11) * xy exactly.
    p = tf.perspective(45, a, n, fa)
    assert p[0, 1:].tolist() == [0, 0, 0] and p[1, [0, 2, 3]].tolist() == [0, 0, 0]
    assert p[3].tolist() == [0, 0, -1, 0]


def test_look_at_maps_eye_to_origin_and_forward_to_minus_z():
    eye, fwd, up = np.array([1.0, 2, 3]), np.array([0.0, -0.6, -0.8]), np.array([0.0, 1, 0])
    v = tf.look_at(eye, fwd, up)
    assert np.allclose(v @ np.r_[eye, 1], [0, 0, 0, 1])
    assert np.allclose(v[:3, :3] @ fwd, [0, 0, -1])
    assert np.allclose(v[:3, :3] @ v[:3, :3].T, np.eye(3))
    right = np.cross(fwd, up) / np.linalg.norm(np.cross(fwd, up))
    assert np.allclose(v[:3, :3] @ right, [1, 0, 0])


def test_object_matrix_follows_the_contract():
    mesh = Mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), np.zeros((3, 3)), np.zeros((1, 3)))
    o = SceneObject("o", 1, mesh, Material(), position=np.array([1.0, 0, 0]),
                    rotation=np.array([0.0, 90, 0]), scale=np.array([2.0, 2, 2]),
                    velocity=np.array([0.0, 1, 0]), angular_velocity=np.array([0.0, 0, 2]))
    t = 0.25
    p = np.array([1.0, 0, 0])
    expect = (np.array([1.0, 0.25, 0]) + rodrigues([0, 0, 1], 0.5)
              @ rodrigues([0, 1, 0], np.pi / 2) @ (2 * p))
    assert np.allclose((o.matrix(t) @ np.r_[p, 1])[:3], expect)


def test_object_matrix_kept_only_while_its_fields_hold():
    # M(t) is kept per t, and for an object that does not move as one matrix for every t;
    # edited fields (the viewer's panel, bench --speeds) give the matrix of the new values.
    mesh = Mesh(np.zeros((3, 3)), np.array([[0, 1, 2]]), np.zeros((3, 3)), np.zeros((1, 3)))
    o = SceneObject("o", 1, mesh, Material(), position=np.array([1.0, 2, 3]),
                    rotation=np.array([0.0, 90, 0]))
    still = o.matrix(0.0)
    np.testing.assert_array_equal(still[:3, 3], [1, 2, 3])
    for t in (0.25, -3.0, 1e5):
        np.testing.assert_array_equal(o.matrix(t), still)
    o.velocity = np.array([0.0, 4, 0])
    np.testing.assert_allclose(o.matrix(0.25)[:3, 3], [1, 3, 3], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(o.matrix(0.0), still)
    o.velocity[:] = 0.0                         # edited in place: still again
    o.position[0] = 5.0
    np.testing.assert_array_equal(o.matrix(0.25)[:3, 3], [5, 2, 3])
    o.angular_velocity = np.array([0.0, 0, 2])
    turned = o.matrix(0.25)
    np.testing.assert_allclose(turned[:3, :3], rodrigues([0, 0, 1], 0.5) @ still[:3, :3],
                               rtol=0, atol=1e-15)


def test_camera_pose_and_projection_of_known_points():
    spec = CameraSpec(position=np.array([0.0, 0, 5]), look_at=np.zeros(3), fov_y=90.0,
                      velocity=np.array([1.0, 0, 0]), angular_velocity=np.array([0, 0.5, 0]))
    eye, fwd, up = spec.pose(1.0)
    assert np.allclose(eye, [1, 0, 5])
    assert np.allclose(fwd, rodrigues([0, 1, 0], 0.5) @ [0, 0, -1])
    cam = Camera(CameraSpec(position=np.array([0.0, 0, 5]), look_at=np.zeros(3), fov_y=90.0),
                 200, 100)
    # fov 90: at depth 5 the top edge of the view is at y = 5; aspect 2: right edge at x = 10.
    win, depth = cam.project(0.0, np.array([[0.0, 0, 0], [10.0, 5, 0], [-5.0, -2.5, 0]]))
    assert np.allclose(win, [[100, 50], [200, 100], [50, 25]])
    assert np.allclose(depth, 5)
    # Rays through pixel centres land where project says.
    o, d = cam.rays(0.0, np.array([0, 199, 37]), np.array([0, 99, 60]))
    hit = o + d * (5 / -d[:, 2:3])
    w, _ = cam.project(0.0, hit)
    assert np.allclose(w, [[0.5, 99.5], [199.5, 0.5], [37.5, 39.5]])


def test_integer_inputs_are_not_garbage():
    # pyrr silently returns integer garbage for integer arrays; transforms converts first.
    assert np.allclose(tf.axis_angle(np.array([0, 1, 0])), rodrigues([0, 1, 0], 1.0))
    v = tf.look_at(np.array([0, 0, 5]), np.array([0, 0, -1]), np.array([0, 1, 0]))
    assert np.allclose(v @ [0, 0, 5, 1], [0, 0, 0, 1])
    assert np.allclose(tf.perspective(90, 2, 1, 10)[1, 1], 1.0)


def test_quaternions_one_order_scalar_and_batched():
    """(w, x, y, z) throughout: a quarter turn about z is (cos 45, 0, 0, sin 45); batches
    of quaternions give the single ones' matrices; T R S composes in that order; zero and
    non-finite quaternions normalise to the identity."""
    c = np.cos(np.pi / 4)
    qz = np.array([c, 0.0, 0.0, c])
    np.testing.assert_allclose(tf.quat_matrix(qz), rodrigues([0, 0, 1], np.pi / 2), atol=1e-15)
    rng = np.random.default_rng(7)
    q = tf.quat_normalised(rng.normal(size=(5, 4)))
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    batch = tf.quat_matrix(q)
    for k in range(5):
        np.testing.assert_array_equal(batch[k], tf.quat_matrix(q[k]))
        np.testing.assert_allclose(batch[k] @ batch[k].T, np.eye(3), atol=1e-14)
    m = tf.trs([1.0, 2.0, 3.0], qz, [2.0, 3.0, 4.0])
    want = tf.translate([1, 2, 3]) @ tf.homogeneous(tf.quat_matrix(qz)) @ tf.scale([2, 3, 4])
    np.testing.assert_allclose(m, want, atol=1e-15)
    assert tf.trs(np.zeros((4, 3)), q[:4], np.ones((4, 3))).shape == (4, 4, 4)
    bad = tf.quat_normalised([[0, 0, 0, 0], [np.inf, 0, 0, 0], [np.nan, 1, 0, 0], [0, 0, 0, 2]])
    np.testing.assert_array_equal(bad, [[1, 0, 0, 0], [1, 0, 0, 0], [1, 0, 0, 0], [0, 0, 0, 1]])
