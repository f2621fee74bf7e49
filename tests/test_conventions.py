"""world/conventions.py: the one row flip, in its index and its array form."""
import numpy as np

from world.conventions import flip_row, to_image


def test_row_flip_index_and_array_forms_agree():
    a = np.arange(5 * 3 * 2).reshape(5, 3, 2)
    img = to_image(a)
    for k in range(5):
        np.testing.assert_array_equal(img[k], a[flip_row(k, 5)])
    assert flip_row(0, 5) == 4 and flip_row(4, 5) == 0
    np.testing.assert_array_equal(to_image(img), a)               # its own inverse
    np.testing.assert_array_equal(flip_row(flip_row(np.arange(7), 7), 7), np.arange(7))
    assert img.flags.c_contiguous
