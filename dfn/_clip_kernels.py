"""Numba kernel: area of regular polygons (disk approximations) clipped by an axis-aligned box.

Private to :mod:`rockmass.dfn.network`, which validates, selects the disks that the box cuts and
applies the polygon-to-disk area correction. Imported lazily (numba is heavy).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _clip_axis(src, n_src, dst, axis, value, keep_below):
    """Sutherland-Hodgman step: clip the polygon src[:n_src] by x_axis <= value (or >= value).

    Writes the result into dst and returns its vertex count (at most n_src + 1 for a convex polygon).
    """
    n_out = 0
    if n_src == 0:
        return 0
    for k in range(n_src):
        a0 = src[k, 0]
        a1 = src[k, 1]
        a2 = src[k, 2]
        j = k + 1 if k + 1 < n_src else 0
        b0 = src[j, 0]
        b1 = src[j, 1]
        b2 = src[j, 2]
        da = src[k, axis] - value
        db = src[j, axis] - value
        if not keep_below:
            da = -da
            db = -db
        a_in = da <= 0.0
        b_in = db <= 0.0
        if a_in:
            dst[n_out, 0] = a0
            dst[n_out, 1] = a1
            dst[n_out, 2] = a2
            n_out += 1
        if a_in != b_in:
            t = da / (da - db)
            dst[n_out, 0] = a0 + t * (b0 - a0)
            dst[n_out, 1] = a1 + t * (b1 - a1)
            dst[n_out, 2] = a2 + t * (b2 - a2)
            dst[n_out, axis] = value  # exact on the plane
            n_out += 1
    return n_out


@njit(cache=True)
def clipped_polygon_areas(centre, e1, e2, radius, box_lo, box_hi, n_vertices, out):
    """Area of each regular n-gon inscribed in a disk, clipped by the box [box_lo, box_hi].

    centre, e1, e2 : (n, 3) float64 -- disk centres and two orthonormal in-plane unit vectors.
    radius : (n,) float64. box_lo, box_hi : (3,) float64. n_vertices : int64 >= 3. out : (n,) float64.

    No checks: the caller guarantees finite inputs, unit orthogonal e1/e2, box_lo < box_hi.
    """
    cap = n_vertices + 8
    buf_a = np.empty((cap, 3))
    buf_b = np.empty((cap, 3))
    step = 2.0 * np.pi / n_vertices
    cos_t = np.cos(np.arange(n_vertices) * step)
    sin_t = np.sin(np.arange(n_vertices) * step)
    for i in range(centre.shape[0]):
        r = radius[i]
        for k in range(n_vertices):
            for c in range(3):
                buf_a[k, c] = centre[i, c] + r * (cos_t[k] * e1[i, c] + sin_t[k] * e2[i, c])
        n = n_vertices
        src = buf_a
        dst = buf_b
        for axis in range(3):
            n = _clip_axis(src, n, dst, axis, box_lo[axis], False)
            src, dst = dst, src
            n = _clip_axis(src, n, dst, axis, box_hi[axis], True)
            src, dst = dst, src
        # area = |sum of cross products| / 2 (vector area of a planar polygon)
        sx = 0.0
        sy = 0.0
        sz = 0.0
        for k in range(n):
            j = k + 1 if k + 1 < n else 0
            ax = src[k, 0] - centre[i, 0]
            ay = src[k, 1] - centre[i, 1]
            az = src[k, 2] - centre[i, 2]
            bx = src[j, 0] - centre[i, 0]
            by = src[j, 1] - centre[i, 1]
            bz = src[j, 2] - centre[i, 2]
            sx += ay * bz - az * by
            sy += az * bx - ax * bz
            sz += ax * by - ay * bx
        out[i] = 0.5 * np.sqrt(sx * sx + sy * sy + sz * sz)
