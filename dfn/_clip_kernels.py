"""Numba kernels: regular polygons (disk approximations) clipped by an axis-aligned box.

:func:`clipped_polygon_areas` gives their areas, for :mod:`rockmass.dfn.network`, which validates,
selects the disks that the box cuts and applies the polygon-to-disk area correction;
:func:`clip_polygons` gives the clipped polygons themselves, for ``fractures.vtu``
(:mod:`rockmass.dfn.network_io`). Private; imported lazily (numba is heavy).

Each kernel has one explicit signature (compiled, or read from numba's cache, when this module is
imported): C-contiguous float64 arrays, the inputs typed read-only so that read-only and writable
arrays share the one compiled version. Plain loops only: whole-array assignment and array
expressions pull numba's broadcasting and error-message machinery into the compile (seconds).
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

_F1 = types.float64[::1]
_F2 = types.float64[:, ::1]
_F3 = types.float64[:, :, ::1]
_I1 = types.int64[::1]
_F1R = types.Array(types.float64, 1, "C", readonly=True)
_F2R = types.Array(types.float64, 2, "C", readonly=True)
_F3R = types.Array(types.float64, 3, "C", readonly=True)


@njit(types.int64(_F2, types.int64, _F2, types.int64, types.float64, types.boolean), cache=True)
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


@njit(types.int64(_F2, _F2, types.int64, _F1R, _F1R), cache=True)
def _clip_box(buf_a, buf_b, n, box_lo, box_hi):
    """Clip the convex polygon buf_a[:n] by the six planes of the box; return its vertex count.

    The result is in buf_a again (six passes swap the buffers an even number of times); buf_b is
    scratch. Both need room for n + 6 vertices (each plane adds at most one to a convex polygon).
    """
    src = buf_a
    dst = buf_b
    for axis in range(3):
        n = _clip_axis(src, n, dst, axis, box_lo[axis], False)
        src, dst = dst, src
        n = _clip_axis(src, n, dst, axis, box_hi[axis], True)
        src, dst = dst, src
    return n


@njit(types.boolean(types.float64, types.float64, types.float64, types.float64, types.float64,
                    types.float64, types.float64), cache=True)
def _same_vertex(ax, ay, az, bx, by, bz, tol):
    """Whether the points a and b differ by at most tol on every axis."""
    return abs(ax - bx) <= tol and abs(ay - by) <= tol and abs(az - bz) <= tol


@njit(types.void(_F3R, _F1R, _F1R, _F1R, _F3, _I1), cache=True)
def clip_polygons(polygons, box_lo, box_hi, tol, out, counts):
    """Clip convex planar polygons by the box [box_lo, box_hi]; write the parts that remain.

    polygons : (n, m, 3) float64 -- the polygons' vertices in order. box_lo, box_hi : (3,) float64.
    tol : (n,) float64 -- a vertex closer than tol[i] (on every axis) to the one written before it
    is the same vertex (a polygon vertex on or just off a face of the box, met again as the
    crossing point): it is written once, so no edge written is shorter than about tol[i].
    out : (n, m + 6, 3) float64 -- receives the clipped polygon i in out[i, :counts[i]].
    counts : (n,) int64 -- receives the vertex counts: 0 when less than a triangle is left (the
    polygon is outside the box or only touches it).

    No checks: the caller guarantees finite input, m >= 3, tol >= 0 and box_lo < box_hi.
    """
    m = polygons.shape[1]
    buf_a = np.empty((m + 6, 3))
    buf_b = np.empty((m + 6, 3))
    for i in range(polygons.shape[0]):
        for j in range(m):
            for c in range(3):
                buf_a[j, c] = polygons[i, j, c]
        n = _clip_box(buf_a, buf_b, m, box_lo, box_hi)
        k = 0
        for j in range(n):
            if k == 0 or not _same_vertex(buf_a[j, 0], buf_a[j, 1], buf_a[j, 2], out[i, k - 1, 0],
                                          out[i, k - 1, 1], out[i, k - 1, 2], tol[i]):
                for c in range(3):
                    out[i, k, c] = buf_a[j, c]
                k += 1
        while k > 1 and _same_vertex(out[i, k - 1, 0], out[i, k - 1, 1], out[i, k - 1, 2],
                                     out[i, 0, 0], out[i, 0, 1], out[i, 0, 2], tol[i]):
            k -= 1  # the ring closes on itself
        counts[i] = k if k >= 3 else 0


@njit(types.void(_F2R, _F2R, _F2R, _F1R, _F1R, _F1R, types.int64, _F1), cache=True)
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
    cos_t = np.empty(n_vertices)
    sin_t = np.empty(n_vertices)
    for k in range(n_vertices):
        cos_t[k] = np.cos(k * step)
        sin_t[k] = np.sin(k * step)
    for i in range(centre.shape[0]):
        r = radius[i]
        for k in range(n_vertices):
            for c in range(3):
                buf_a[k, c] = centre[i, c] + r * (cos_t[k] * e1[i, c] + sin_t[k] * e2[i, c])
        n = _clip_box(buf_a, buf_b, n_vertices, box_lo, box_hi)
        src = buf_a
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
