"""Parents (scene format v1.2): M(t) = M_parent(t) @ M_own(t), motion inherited, and every
mistake in `parent` one SceneError naming the object."""
import numpy as np
import pytest

from world import transforms as tf
from world.errors import SceneError

from conftest import scene_from

HEAD = """
[camera]
position = [0.0, 0.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_y = 45.0
shutter = 0.04
"""


def test_child_matrix_is_parent_times_own(tmp_path):
    sc = scene_from(tmp_path, HEAD + """
        [[objects]]
        name = "cart"
        mesh = { box = [1.0, 0.5, 0.5] }
        position = [-1.0, 0.0, 0.0]
        velocity = [2.0, 0.0, 0.0]
        rotation = [0.0, 30.0, 0.0]

        [[objects]]
        name = "rider"
        parent = "cart"
        mesh = { box = [0.2, 0.6, 0.2] }
        position = [0.0, 0.5, 0.0]
        angular_velocity = [0.0, 0.0, 3.0]

        [[objects]]
        name = "flag"
        parent = "rider"
        mesh = { box = [0.1, 0.1, 0.1] }
        position = [0.0, 0.4, 0.0]
    """)
    cart, rider, flag = sc.objects
    for t in (0.0, 0.37, -1.2):
        cart_m = tf.translate([-1.0 + 2.0 * t, 0, 0]) @ tf.homogeneous(
            tf.euler_xyz_degrees([0, 30, 0]))
        rider_own = tf.translate([0, 0.5, 0]) @ tf.homogeneous(tf.axis_angle([0, 0, 3.0 * t]))
        np.testing.assert_allclose(rider.matrix(t), cart_m @ rider_own, atol=1e-12)
        np.testing.assert_allclose(flag.matrix(t), cart_m @ rider_own @ tf.translate([0, 0.4, 0]),
                                   atol=1e-12)
    # The flag has no motion of its own; it moves because something above it moves.
    assert not flag.own_moving and flag.moving and rider.moving


def test_still_parent_keeps_child_still(tmp_path):
    sc = scene_from(tmp_path, HEAD + """
        [[objects]]
        name = "table"
        mesh = { box = [1.0, 0.1, 1.0] }
        position = [0.0, -1.0, 0.0]

        [[objects]]
        name = "cup"
        parent = "table"
        mesh = { box = [0.1, 0.1, 0.1] }
        position = [0.2, 0.1, 0.0]
    """)
    table, cup = sc.objects
    assert not cup.moving
    np.testing.assert_allclose(cup.matrix(3.0)[:3, 3], [0.2, -0.9, 0.0], atol=1e-12)


@pytest.mark.parametrize("entries, message", [
    ("""
        [[objects]]
        name = "a"
        parent = "b"
        mesh = { box = [1.0, 1.0, 1.0] }

        [[objects]]
        name = "b"
        mesh = { box = [1.0, 1.0, 1.0] }
     """, "objects[1] (a).parent: expected the name of an earlier object"),
    ("""
        [[objects]]
        name = "a"
        mesh = { box = [1.0, 1.0, 1.0] }

        [[objects]]
        name = "a"
        mesh = { box = [1.0, 1.0, 1.0] }

        [[objects]]
        name = "c"
        parent = "a"
        mesh = { box = [1.0, 1.0, 1.0] }
     """, "objects[3] (c).parent: 'a' names 2 earlier objects"),
    ("""
        [[objects]]
        name = "a"
        parent = "a"
        mesh = { box = [1.0, 1.0, 1.0] }
     """, "objects[1] (a).parent: expected the name of an earlier object"),
    ("""
        [[objects]]
        name = "a"
        parent = 3
        mesh = { box = [1.0, 1.0, 1.0] }
     """, "objects[1] (a).parent: expected a string"),
])
def test_parent_mistakes(tmp_path, entries, message):
    with pytest.raises(SceneError) as e:
        scene_from(tmp_path, HEAD + entries)
    assert message in str(e.value)
    assert "\n" not in str(e.value)
