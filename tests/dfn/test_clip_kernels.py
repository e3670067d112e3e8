"""The clipping kernels: one compiled signature for read-only and writable inputs alike."""

from __future__ import annotations

import numpy as np
import pytest


def _disks(n: int, seed: int):
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-5.0, 5.0, (n, 3))
    normal = rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    e1 = np.cross(normal, [0.3, 0.5, 0.8])
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return centre, e1, np.cross(normal, e1), rng.uniform(0.5, 6.0, n)


def test_clipped_areas_take_read_only_arrays_with_one_signature():
    from rockmass.dfn import _clip_kernels as K

    centre, e1, e2, radius = _disks(50, 1)
    lo, hi = np.array([-4.0, -3.0, -4.0]), np.array([4.0, 3.0, 2.0])
    writable = np.empty(50)
    K.clipped_polygon_areas(centre, e1, e2, radius, lo, hi, np.int64(24), writable)
    for a in (centre, e1, e2, radius, lo, hi):
        a.flags.writeable = False
    read_only = np.empty(50)
    K.clipped_polygon_areas(centre, e1, e2, radius, lo, hi, np.int64(24), read_only)
    assert np.array_equal(writable, read_only)
    assert np.all(read_only <= np.pi * radius ** 2)
    for kernel in (K.clipped_polygon_areas, K.clip_polygons, K._clip_box, K._clip_axis,
                   K._same_vertex):
        assert len(kernel.signatures) == 1, kernel.__name__


def test_a_disk_inside_the_box_keeps_its_polygon_area():
    from rockmass.dfn import _clip_kernels as K

    m = 32
    out = np.empty(1)
    K.clipped_polygon_areas(np.zeros((1, 3)), np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]),
                            np.array([1.0]), np.full(3, -2.0), np.full(3, 2.0), np.int64(m), out)
    assert out[0] == pytest.approx(0.5 * m * np.sin(2 * np.pi / m), rel=1e-12)
