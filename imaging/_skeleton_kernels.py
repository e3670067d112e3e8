"""Numba kernels of :mod:`rockmass.imaging.skeleton_graph`: walk skeleton branches
(:func:`~rockmass.imaging.skeleton_graph.build_graph`) and measure their end directions
(:func:`~rockmass.imaging.skeleton_graph.end_directions`).

Kept apart from its wrapper (the project's kernel rule: kernels take plain arrays, write into caller-allocated
outputs and return the counts written; the wrapper validates and slices).
"""

from __future__ import annotations

import numba
import numpy as np

_DR = np.array([-1, -1, -1, 0, 0, 1, 1, 1], dtype=np.int64)
_DC = np.array([-1, 0, 1, -1, 1, -1, 0, 1], dtype=np.int64)


# the helpers have one explicit signature each: called with literal arguments (0, -1) they would
# otherwise compile once per combination of literal and variable arguments
@numba.njit(numba.int64(numba.int64[:, ::1], numba.int64, numba.int64, numba.int64), cache=True)
def _push(out_rc, n_v, r, c):
    """Append pixel (r, c) as vertex ``n_v`` of ``out_rc``; return the new vertex count."""
    out_rc[n_v, 0] = r
    out_rc[n_v, 1] = c
    return n_v + 1


@numba.njit(numba.int64(numba.int64[::1], numba.int64[::1], numba.int64[::1], numba.int64,
                        numba.int64, numba.int64, numba.int64), cache=True)
def _close(out_offsets, out_src, out_dst, n_b, n_v, src, dst):
    """End branch ``n_b`` (nodes ``src`` -> ``dst``) at vertex count ``n_v``; return the new branch count."""
    out_src[n_b] = src
    out_dst[n_b] = dst
    out_offsets[n_b + 1] = n_v
    return n_b + 1


@numba.njit(cache=True)
def _walk_branches(skel, node_id, visited, out_rc, out_offsets, out_src, out_dst):
    """Trace every branch of a one-pixel skeleton between nodes; return (n_branches, n_vertices).

    ``skel`` (H, W) uint8 is zero-padded by one pixel on every side; ``node_id`` (H, W) int64 is the
    node of each node pixel (ends and junction clusters) and -1 elsewhere; ``visited`` (H, W) uint8
    starts at zero. Branch i's pixels (node pixel, interior pixels, node pixel), as padded (row, col),
    go to ``out_rc[out_offsets[i]:out_offsets[i + 1]]`` with end nodes ``out_src[i]``, ``out_dst[i]``.
    Interior pixels have exactly two skeleton neighbours (else they would be nodes), so each walk is
    forced. Cycles without a node get ``src = dst = -1`` (the wrapper makes a node for them).

    No checks: the caller guarantees the padding, the shapes, and output arrays of at least
    3 * (number of skeleton pixels) + 2 rows (vertices) and 8 * (skeleton pixels) + 1 (branches).
    """
    h, w = skel.shape
    n_b = 0
    n_v = 0
    out_offsets[0] = 0
    for r in range(1, h - 1):
        for c in range(1, w - 1):
            a = node_id[r, c]
            if a < 0:
                continue
            for k in range(8):
                r1 = r + _DR[k]
                c1 = c + _DC[k]
                if skel[r1, c1] == 0:
                    continue
                b = node_id[r1, c1]
                if b >= 0:
                    # node pixel next to a node pixel of another node: a one-step branch, once
                    if b != a and (r1 * w + c1) > (r * w + c):
                        n_v = _push(out_rc, n_v, r, c)
                        n_v = _push(out_rc, n_v, r1, c1)
                        n_b = _close(out_offsets, out_src, out_dst, n_b, n_v, a, b)
                    continue
                if visited[r1, c1]:
                    continue
                n_v = _push(out_rc, n_v, r, c)
                pr, pc = r, c
                cr, cc = r1, c1
                end = -1
                while True:
                    visited[cr, cc] = 1
                    n_v = _push(out_rc, n_v, cr, cc)
                    nr, nc = -1, -1
                    for j in range(8):
                        qr = cr + _DR[j]
                        qc = cc + _DC[j]
                        if skel[qr, qc] == 0 or (qr == pr and qc == pc):
                            continue
                        if node_id[qr, qc] >= 0:
                            if nr < 0 or node_id[nr, nc] < 0:
                                # a node ends the branch, unless it is the start pixel's cluster
                                # seen right after leaving it
                                if not (node_id[qr, qc] == a and pr == r and pc == c):
                                    nr, nc = qr, qc
                            continue
                        if visited[qr, qc] == 0:
                            nr, nc = qr, qc
                    if nr < 0:
                        break
                    if node_id[nr, nc] >= 0:
                        n_v = _push(out_rc, n_v, nr, nc)
                        end = node_id[nr, nc]
                        break
                    pr, pc = cr, cc
                    cr, cc = nr, nc
                if end < 0:
                    end = a  # an interior chain that returns to its start cluster
                    n_v = _push(out_rc, n_v, r, c)
                n_b = _close(out_offsets, out_src, out_dst, n_b, n_v, a, end)
    # closed loops with no node at all
    for r in range(1, h - 1):
        for c in range(1, w - 1):
            if skel[r, c] == 0 or node_id[r, c] >= 0 or visited[r, c]:
                continue
            sr, sc = r, c
            pr, pc = -10, -10
            cr, cc = r, c
            while True:
                visited[cr, cc] = 1
                n_v = _push(out_rc, n_v, cr, cc)
                nr, nc = -1, -1
                for j in range(8):
                    qr = cr + _DR[j]
                    qc = cc + _DC[j]
                    if skel[qr, qc] == 0 or (qr == pr and qc == pc) or visited[qr, qc]:
                        continue
                    nr, nc = qr, qc
                    break
                if nr < 0:
                    break
                pr, pc = cr, cc
                cr, cc = nr, nc
            n_v = _push(out_rc, n_v, sr, sc)
            n_b = _close(out_offsets, out_src, out_dst, n_b, n_v, -1, -1)
    return n_b, n_v


@numba.njit(numba.void(numba.float64[:, ::1], numba.int64[::1], numba.float64, numba.float64,
                       numba.float64[:, :, ::1]), cache=True)
def _end_directions(rc, offsets, skip_px, reach_px, out):
    """Unit direction into every chain ``rc[offsets[i]:offsets[i + 1]]`` from its first point
    (``out[i, 0]``) and from its last (``out[i, 1]``), between arc lengths skip and reach.

    The arithmetic of :func:`rockmass.imaging.skeleton_graph._direction`, step for step (the arc
    summed from the end in chain order, the first vertex at or beyond each arc length), so the
    two agree to the bit. ``out`` starts at zero: chains of one point or no length keep it.
    """
    longest = 1
    for i in range(offsets.size - 1):
        longest = max(longest, offsets[i + 1] - offsets[i])
    arc = np.empty(longest)
    for i in range(offsets.size - 1):
        lo, hi = offsets[i], offsets[i + 1]
        k = hi - lo
        if k < 2:
            continue
        for side in range(2):
            step = -1 if side == 1 else 1
            first = hi - 1 if side == 1 else lo
            arc[0] = 0.0
            for j in range(1, k):
                a = first + step * j
                b = a - step
                arc[j] = arc[j - 1] + np.hypot(rc[a, 0] - rc[b, 0], rc[a, 1] - rc[b, 1])
            reach = min(reach_px, arc[k - 1])
            skip = min(skip_px, reach / 3.0)
            near = 0
            while near < k - 1 and arc[near] < skip:  # skip <= arc[k - 1]: the bound is a guard
                near += 1
            far = 0
            while far < k - 1 and arc[far] < reach:
                far += 1
            p = first + step * near
            q = first + step * far
            if rc[p, 0] == rc[q, 0] and rc[p, 1] == rc[q, 1]:
                p = first
            d0 = rc[q, 0] - rc[p, 0]
            d1 = rc[q, 1] - rc[p, 1]
            norm = np.hypot(d0, d1)
            if norm > 0:
                out[i, side, 0] = d0 / norm
                out[i, side, 1] = d1 / norm
