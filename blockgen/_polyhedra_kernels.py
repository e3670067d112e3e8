"""Numba kernels behind :func:`rockmass.blockgen.blocks3d.cut_box`: many convex polyhedra cut by a
sequence of planes, their moments and their shared faces, in one flat layout (docs/blocks.md §8).

Flat layout (the ragged-array form of a tuple of :class:`~rockmass.blockgen.polyhedra.Polyhedron`):

- ``verts (n_vertices, 3) float64`` — face vertices, face after face (a corner shared by k faces is
  stored k times, as in ``Polyhedron.faces``);
- ``face_start (n_faces + 1,) int64`` — face f is ``verts[face_start[f]:face_start[f + 1]]``,
  counter-clockwise seen from outside;
- ``face_label (n_faces,) int64`` — its label (plane index, or negative for the box / walls);
- ``piece_start (n_pieces + 1,) int64`` — piece p has faces ``piece_start[p]:piece_start[p + 1]``.

While cutting, the kernel keeps the same data in growable pools where each face and each piece holds
its own start and count (a piece replaced by its lower part leaves garbage behind; the pools are
compacted when they fill up). The cutting rule is :func:`rockmass.blockgen.polyhedra.split`'s, step
for step: vertices with |s| ≤ tol are on the plane, a face part is kept only when it has a vertex
strictly on its side, the cap is the on-plane points in order of angle about n (stable), merged
within tol, and a cap of fewer than three points or of area ≤ tol² means no cut.

The link kernels (:func:`project_faces`, :func:`clip_convex_pairs`, :func:`disk_overlap`) work on
the cut faces of one plane in its (e1, e2) frame: shared polygons by Sutherland–Hodgman clipping of
one convex face by the other, and their overlap with a fracture disk.

Kept in one file with every jitted helper it calls (numba's cache misses edits in other files).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _plane_basis(nx, ny, nz):
    """e1, e2 of :func:`rockmass.blockgen.polyhedra.plane_basis`, as six floats."""
    if abs(nx) < 0.9:
        h = math.hypot(ny, nz)
        ax, ay, az = 0.0, -nz / h, ny / h
    else:
        h = math.hypot(nx, nz)
        ax, ay, az = nz / h, 0.0, -nx / h
    return ax, ay, az, ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax


@njit(cache=True)
def _grow_rows(a, n):
    out = np.empty((n, a.shape[1]), a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(cache=True)
def _grow(a, n):
    out = np.empty(n, a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(cache=True)
def _compact(verts, fv0, fvn, flab, pf0, pfn, n_pieces, need_v, need_f):
    """Copy the live faces and vertices, piece by piece, into new pools with room for ``need_v``
    more vertices and ``need_f`` more faces; returns the new pools and their fill counts."""
    live_f = 0
    live_v = 0
    for p in range(n_pieces):
        live_f += pfn[p]
        for f in range(pf0[p], pf0[p] + pfn[p]):
            live_v += fvn[f]
    cap_v = max(2 * (live_v + need_v), 64)
    cap_f = max(2 * (live_f + need_f), 16)
    nverts = np.empty((cap_v, 3), np.float64)
    nfv0 = np.empty(cap_f, np.int64)
    nfvn = np.empty(cap_f, np.int64)
    nflab = np.empty(cap_f, np.int64)
    nv = 0
    nf = 0
    for p in range(n_pieces):
        first = nf
        for f in range(pf0[p], pf0[p] + pfn[p]):
            nfv0[nf] = nv
            nfvn[nf] = fvn[f]
            nflab[nf] = flab[f]
            for v in range(fv0[f], fv0[f] + fvn[f]):
                nverts[nv, 0] = verts[v, 0]
                nverts[nv, 1] = verts[v, 1]
                nverts[nv, 2] = verts[v, 2]
                nv += 1
            nf += 1
        pf0[p] = first
    return nverts, nfv0, nfvn, nflab, nv, nf


@njit(cache=True)
def _clip_edge(verts, a, b, sa, sb, tol, keep, out, row):
    """One Sutherland–Hodgman step on edge a→b with signed distances sa, sb: write vertex a to
    ``out[row]`` if ``keep``, then the crossing point if the edge crosses the plane strictly
    (|s| > tol at both ends, opposite signs). Returns the next free row."""
    if keep:
        out[row, 0] = verts[a, 0]
        out[row, 1] = verts[a, 1]
        out[row, 2] = verts[a, 2]
        row += 1
    if (sa < -tol and sb > tol) or (sa > tol and sb < -tol):
        t = sa / (sa - sb)
        for c in range(3):
            out[row, c] = verts[a, c] + t * (verts[b, c] - verts[a, c])
        row += 1
    return row


@njit(cache=True)
def _cap_points(verts, fv0, fvn, pf0, pfn, p, nx, ny, nz, d, tol, s, on):
    """Signed distances ``s`` of piece p's face vertices (face order) and its on-plane points
    ``on`` in :func:`~rockmass.blockgen.polyhedra.split`'s order; returns (count, lowest, highest)."""
    lowest = np.inf
    highest = -np.inf
    k = 0
    for f in range(pf0[p], pf0[p] + pfn[p]):
        for v in range(fv0[f], fv0[f] + fvn[f]):
            sv = verts[v, 0] * nx + verts[v, 1] * ny + verts[v, 2] * nz - d
            s[k] = sv
            k += 1
            lowest = min(lowest, sv)
            highest = max(highest, sv)
    if highest <= tol or lowest >= -tol:
        return 0, lowest, highest
    n_on = 0
    k = 0
    for f in range(pf0[p], pf0[p] + pfn[p]):
        m = fvn[f]
        for i in range(m):
            a = fv0[f] + i
            b = fv0[f] + (i + 1) % m
            n_on = _clip_edge(verts, a, b, s[k + i], s[k + (i + 1) % m], tol, abs(s[k + i]) <= tol, on, n_on)
        k += m
    return n_on, lowest, highest


@njit(cache=True)
def _order_cap(on, n_on, nx, ny, nz, tol, uv, order, cap):
    """The cap polygon from the first ``n_on`` rows of ``on``: sorted by angle about n (stable),
    points within tol merged, written to ``cap``; returns its vertex count (0 if < 3 or area ≤ tol²)."""
    e1x, e1y, e1z, e2x, e2y, e2z = _plane_basis(nx, ny, nz)
    mu = 0.0
    mv = 0.0
    for i in range(n_on):
        uv[i, 0] = on[i, 0] * e1x + on[i, 1] * e1y + on[i, 2] * e1z
        uv[i, 1] = on[i, 0] * e2x + on[i, 1] * e2y + on[i, 2] * e2z
        mu += uv[i, 0]
        mv += uv[i, 1]
    mu /= n_on
    mv /= n_on
    for i in range(n_on):       # angle, then a stable insertion sort of the indices by it
        uv[i, 2] = math.atan2(uv[i, 1] - mv, uv[i, 0] - mu)
        order[i] = i
    for i in range(1, n_on):
        j = i
        while j > 0 and uv[order[j - 1], 2] > uv[order[j], 2]:
            order[j - 1], order[j] = order[j], order[j - 1]
            j -= 1
    m = 0
    for i in range(n_on):
        q = order[i]
        if m > 0:
            dx = on[q, 0] - cap[m - 1, 0]
            dy = on[q, 1] - cap[m - 1, 1]
            dz = on[q, 2] - cap[m - 1, 2]
            if math.sqrt(dx * dx + dy * dy + dz * dz) <= tol:
                continue
        cap[m, 0] = on[q, 0]
        cap[m, 1] = on[q, 1]
        cap[m, 2] = on[q, 2]
        m += 1
    if m > 1:
        dx = cap[m - 1, 0] - cap[0, 0]
        dy = cap[m - 1, 1] - cap[0, 1]
        dz = cap[m - 1, 2] - cap[0, 2]
        if math.sqrt(dx * dx + dy * dy + dz * dz) <= tol:
            m -= 1
    if m < 3:
        return 0
    ax = 0.0
    ay = 0.0
    az = 0.0
    for i in range(m):
        j = (i + 1) % m
        ax += cap[i, 1] * cap[j, 2] - cap[i, 2] * cap[j, 1]
        ay += cap[i, 2] * cap[j, 0] - cap[i, 0] * cap[j, 2]
        az += cap[i, 0] * cap[j, 1] - cap[i, 1] * cap[j, 0]
    if 0.5 * math.sqrt(ax * ax + ay * ay + az * az) <= tol * tol:
        return 0
    return m


@njit(cache=True)
def _cap_within(cap, m, nx, ny, nz, centre, radius):
    """Does the cap (counter-clockwise about n) come within ``radius`` of ``centre``, in the plane?
    Distance 0 inside the polygon, else the least distance to its edges."""
    if not math.isfinite(radius):
        return True
    e1x, e1y, e1z, e2x, e2y, e2z = _plane_basis(nx, ny, nz)
    cu = centre[0] * e1x + centre[1] * e1y + centre[2] * e1z
    cv = centre[0] * e2x + centre[1] * e2y + centre[2] * e2z
    inside = True
    best = np.inf
    for i in range(m):
        j = (i + 1) % m
        au = cap[i, 0] * e1x + cap[i, 1] * e1y + cap[i, 2] * e1z - cu
        av = cap[i, 0] * e2x + cap[i, 1] * e2y + cap[i, 2] * e2z - cv
        bu = cap[j, 0] * e1x + cap[j, 1] * e1y + cap[j, 2] * e1z - cu
        bv = cap[j, 0] * e2x + cap[j, 1] * e2y + cap[j, 2] * e2z - cv
        if au * bv - av * bu < 0.0:      # centre strictly right of edge a→b: outside
            inside = False
        eu = bu - au
        ev = bv - av
        ll = eu * eu + ev * ev
        t = 0.0 if ll == 0.0 else min(1.0, max(0.0, -(au * eu + av * ev) / ll))
        best = min(best, math.hypot(au + t * eu, av + t * ev))
    return inside or best < radius


@njit(cache=True)
def _write_part(verts, fv0, fvn, flab, pf0, pfn, p, s, tol, sign, cap, m, label, nv, nf):
    """Append piece p's part on side ``sign`` (−1: s ≤ tol kept, +1: s ≥ −tol kept) and the cap
    (reversed for +1) as new faces at (nv, nf); returns (first face, face count, nv, nf)."""
    first = nf
    k = 0
    for f in range(pf0[p], pf0[p] + pfn[p]):
        mf = fvn[f]
        start = nv
        strict = False
        for i in range(mf):
            a = fv0[f] + i
            b = fv0[f] + (i + 1) % mf
            sp = s[k + i]
            if sign * sp > tol:
                strict = True
            nv = _clip_edge(verts, a, b, sp, s[k + (i + 1) % mf], tol, sign * sp >= -tol, verts, nv)
        k += mf
        if strict and nv - start >= 3:
            fv0[nf] = start
            fvn[nf] = nv - start
            flab[nf] = flab[f]
            nf += 1
        else:
            nv = start
    fv0[nf] = nv
    fvn[nf] = m
    flab[nf] = label
    nf += 1
    for i in range(m):
        q = i if sign < 0 else m - 1 - i
        verts[nv, 0] = cap[q, 0]
        verts[nv, 1] = cap[q, 1]
        verts[nv, 2] = cap[q, 2]
        nv += 1
    return first, nf - first, nv, nf


@njit(cache=True)
def _piece_bounds(verts, fv0, fvn, pf0, pfn, p, lo, hi):
    for c in range(3):
        lo[p, c] = np.inf
        hi[p, c] = -np.inf
    for f in range(pf0[p], pf0[p] + pfn[p]):
        for v in range(fv0[f], fv0[f] + fvn[f]):
            for c in range(3):
                lo[p, c] = min(lo[p, c], verts[v, c])
                hi[p, c] = max(hi[p, c], verts[v, c])


@njit(cache=True)
def _reaches(verts, fv0, fvn, pf0, pfn, p, region_normal, region_offset, h0, h1, tol):
    """False when one half-space h0 ≤ h < h1 has every vertex of piece p at n·x ≥ d − tol."""
    for h in range(h0, h1):
        outside = True
        for f in range(pf0[p], pf0[p] + pfn[p]):
            for v in range(fv0[f], fv0[f] + fvn[f]):
                sv = (verts[v, 0] * region_normal[h, 0] + verts[v, 1] * region_normal[h, 1]
                      + verts[v, 2] * region_normal[h, 2])
                if not sv >= region_offset[h] - tol:
                    outside = False
                    break
            if not outside:
                break
        if outside:
            return False
    return True


@njit(cache=True)
def cut_by_planes(verts_in, face_start, face_label, piece_start, normal, offset, centre, radius,
                  region_normal, region_offset, region_start, first_label, tol):
    """Cut every piece by each plane in turn, as ``blocks3d._cut_by_plane`` does with ``split``.

    ``verts_in, face_start, face_label, piece_start``: the flat layout (module docstring).
    ``normal (n, 3)``, ``offset (n,)``, ``centre (n, 3)``, ``radius (n,)`` float64: the planes
    n·x = d (radius ``inf`` for a persistent plane); the cap of plane i is labelled
    ``first_label + i``. A plane cuts the pieces that existed before it whose bounding box it
    crosses by more than tol (and, for a disk, whose box comes within the radius of the centre and
    whose cap does); the lower part keeps the piece's index, the upper one is appended.
    ``region_normal (h, 3)``, ``region_offset (h,)`` float64 and ``region_start (n + 1,)`` int64:
    the half-spaces {n·x ≤ d} of a convex region (a tunnel) per plane, none for a fracture; plane i
    then cuts only pieces that can reach into its region (no half-space with every vertex of the
    piece at n·x ≥ d − tol; ``Tunnel.reaches``).

    Returns the flat layout of the result. No checks: unit normals, ``face_start`` and
    ``piece_start`` consistent, every face with at least three vertices.
    """
    n_pieces = piece_start.shape[0] - 1
    n_f = face_start.shape[0] - 1
    n_v = verts_in.shape[0]
    verts = _grow_rows(verts_in, max(2 * n_v, 64))
    fv0 = _grow(face_start[:-1].copy(), max(2 * n_f, 16))
    fvn = np.empty(fv0.shape[0], np.int64)
    fvn[:n_f] = face_start[1:] - face_start[:-1]
    flab = _grow(face_label.copy(), fv0.shape[0])
    pf0 = _grow(piece_start[:-1].copy(), max(2 * n_pieces, 16))
    pfn = np.empty(pf0.shape[0], np.int64)
    pfn[:n_pieces] = piece_start[1:] - piece_start[:-1]
    lo = np.empty((pf0.shape[0], 3), np.float64)
    hi = np.empty((pf0.shape[0], 3), np.float64)
    for p in range(n_pieces):
        _piece_bounds(verts, fv0, fvn, pf0, pfn, p, lo, hi)
    scratch = 64
    s = np.empty(scratch, np.float64)
    on = np.empty((scratch, 3), np.float64)
    uv = np.empty((scratch, 3), np.float64)
    order = np.empty(scratch, np.int64)
    cap = np.empty((scratch, 3), np.float64)
    for j in range(offset.shape[0]):
        nx, ny, nz = normal[j, 0], normal[j, 1], normal[j, 2]
        d = offset[j]
        r = radius[j]
        finite = math.isfinite(r)
        n_before = n_pieces
        for p in range(n_before):
            # bounding-box test: |centre·n − d| < half-extent·|n| − tol
            mid = ((lo[p, 0] + hi[p, 0]) / 2 * nx + (lo[p, 1] + hi[p, 1]) / 2 * ny
                   + (lo[p, 2] + hi[p, 2]) / 2 * nz)
            reach = ((hi[p, 0] - lo[p, 0]) / 2 * abs(nx) + (hi[p, 1] - lo[p, 1]) / 2 * abs(ny)
                     + (hi[p, 2] - lo[p, 2]) / 2 * abs(nz))
            if not abs(mid - d) < reach - tol:
                continue
            if finite:
                gap = 0.0
                for c in range(3):
                    g = max(0.0, max(lo[p, c] - centre[j, c], centre[j, c] - hi[p, c]))
                    gap += g * g
                if not math.sqrt(gap) < r:
                    continue
            if not _reaches(verts, fv0, fvn, pf0, pfn, p, region_normal, region_offset,
                            region_start[j], region_start[j + 1], tol):
                continue
            n_pv = 0
            for f in range(pf0[p], pf0[p] + pfn[p]):
                n_pv += fvn[f]
            if n_pv > s.shape[0]:
                scratch = 2 * n_pv
                s = np.empty(scratch, np.float64)
                on = np.empty((scratch, 3), np.float64)
                uv = np.empty((scratch, 3), np.float64)
                order = np.empty(scratch, np.int64)
                cap = np.empty((scratch, 3), np.float64)
            n_on, _, _ = _cap_points(verts, fv0, fvn, pf0, pfn, p, nx, ny, nz, d, tol, s, on)
            if n_on == 0:
                continue
            m = _order_cap(on, n_on, nx, ny, nz, tol, uv, order, cap)
            if m == 0 or not _cap_within(cap, m, nx, ny, nz, centre[j], r):
                continue
            need_v = 4 * (n_pv + pfn[p])
            need_f = 2 * (pfn[p] + 1)
            if n_v + need_v > verts.shape[0] or n_f + need_f > fv0.shape[0]:
                verts, fv0, fvn, flab, n_v, n_f = _compact(verts, fv0, fvn, flab, pf0, pfn, n_pieces,
                                                           need_v, need_f)
            if n_pieces + 1 > pf0.shape[0]:
                size = 2 * pf0.shape[0]
                pf0 = _grow(pf0, size)
                pfn = _grow(pfn, size)
                lo = _grow_rows(lo, size)
                hi = _grow_rows(hi, size)
            f_lo, n_lo, n_v, n_f = _write_part(verts, fv0, fvn, flab, pf0, pfn, p, s, tol, -1.0,
                                               cap, m, first_label + j, n_v, n_f)
            f_up, n_up, n_v, n_f = _write_part(verts, fv0, fvn, flab, pf0, pfn, p, s, tol, 1.0,
                                               cap, m, first_label + j, n_v, n_f)
            pf0[p] = f_lo
            pfn[p] = n_lo
            pf0[n_pieces] = f_up
            pfn[n_pieces] = n_up
            _piece_bounds(verts, fv0, fvn, pf0, pfn, p, lo, hi)
            _piece_bounds(verts, fv0, fvn, pf0, pfn, n_pieces, lo, hi)
            n_pieces += 1
    verts, fv0, fvn, flab, n_v, n_f = _compact(verts, fv0, fvn, flab, pf0, pfn, n_pieces, 0, 0)
    out_face_start = np.empty(n_f + 1, np.int64)
    out_face_start[:n_f] = fv0[:n_f]
    out_face_start[n_f] = n_v
    out_piece_start = np.empty(n_pieces + 1, np.int64)
    out_piece_start[:n_pieces] = pf0[:n_pieces]
    out_piece_start[n_pieces] = n_f
    return verts[:n_v].copy(), out_face_start, flab[:n_f].copy(), out_piece_start


@njit(cache=True)
def piece_moments(verts, face_start, piece_start, volume, first, second):
    """Volume, ∫x dV and ∫x xᵀ dV of every piece (``Polyhedron.moments``: fan tetrahedra from the
    first vertex of the piece's first face). Writes ``volume (n,)``, ``first (n, 3)`` and
    ``second (n, 3, 3)`` float64. No checks: the flat layout is consistent."""
    x = np.empty((4, 3), np.float64)
    for p in range(piece_start.shape[0] - 1):
        ref = face_start[piece_start[p]]
        vol = 0.0
        m1 = np.zeros(3)
        m2 = np.zeros((3, 3))
        for f in range(piece_start[p], piece_start[p + 1]):
            v0 = face_start[f]
            for k in range(v0 + 1, face_start[f + 1] - 1):
                for c in range(3):
                    x[0, c] = verts[ref, c]
                    x[1, c] = verts[v0, c]
                    x[2, c] = verts[k, c]
                    x[3, c] = verts[k + 1, c]
                ax, ay, az = x[1, 0] - x[0, 0], x[1, 1] - x[0, 1], x[1, 2] - x[0, 2]
                bx, by, bz = x[2, 0] - x[0, 0], x[2, 1] - x[0, 1], x[2, 2] - x[0, 2]
                cx, cy, cz = x[3, 0] - x[0, 0], x[3, 1] - x[0, 1], x[3, 2] - x[0, 2]
                v = (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / 6.0
                vol += v
                for a in range(3):
                    ta = x[0, a] + x[1, a] + x[2, a] + x[3, a]
                    m1[a] += v * ta
                    for b in range(3):
                        tb = x[0, b] + x[1, b] + x[2, b] + x[3, b]
                        acc = ta * tb
                        for q in range(4):
                            acc += x[q, a] * x[q, b]
                        m2[a, b] += v * acc
        volume[p] = vol
        for a in range(3):
            first[p, a] = m1[a] / 4.0
            for b in range(3):
                second[p, a, b] = m2[a, b] / 20.0


@njit(cache=True)
def _ccw_copy(uv, a, b, out):
    """Copy ring ``uv[a:b]`` into ``out``, reversed if it is clockwise; returns its length."""
    m = b - a
    twice = 0.0
    for i in range(m):
        j = (i + 1) % m
        twice += uv[a + i, 0] * uv[a + j, 1] - uv[a + j, 0] * uv[a + i, 1]
    for i in range(m):
        q = a + i if twice >= 0.0 else b - 1 - i
        out[i, 0] = uv[q, 0]
        out[i, 1] = uv[q, 1]
    return m


@njit(cache=True)
def _clip_by_ring(subject, ns, clip, nc, nxt):
    """Sutherland–Hodgman: ``subject[:ns]`` clipped by each edge of the counter-clockwise convex
    ``clip[:nc]``; ``nxt`` is a buffer as large as ``subject``. Returns (buffer, count), the buffer
    being ``subject`` or ``nxt``."""
    for e in range(nc):
        if ns == 0:
            break
        px, py = clip[e, 0], clip[e, 1]
        ex, ey = clip[(e + 1) % nc, 0] - px, clip[(e + 1) % nc, 1] - py
        m = 0
        for i in range(ns):
            cx, cy = subject[i, 0], subject[i, 1]
            h = i - 1 if i > 0 else ns - 1
            bx, by = subject[h, 0], subject[h, 1]
            side_c = ex * (cy - py) - ey * (cx - px)
            side_b = ex * (by - py) - ey * (bx - px)
            if (side_c >= 0.0) != (side_b >= 0.0):
                t = side_b / (side_b - side_c)
                nxt[m, 0] = bx + t * (cx - bx)
                nxt[m, 1] = by + t * (cy - by)
                m += 1
            if side_c >= 0.0:
                nxt[m, 0] = cx
                nxt[m, 1] = cy
                m += 1
        subject, nxt = nxt, subject
        ns = m
    return subject, ns


@njit(cache=True)
def _merge_close(poly, m, eps, out):
    """``poly[:m]`` with consecutive vertices closer than ``eps`` merged, written to ``out``;
    returns (count, shoelace area); count 0 and area 0 when fewer than three remain."""
    k = 0
    for i in range(m):
        if k > 0 and math.hypot(poly[i, 0] - out[k - 1, 0], poly[i, 1] - out[k - 1, 1]) <= eps:
            continue
        out[k, 0] = poly[i, 0]
        out[k, 1] = poly[i, 1]
        k += 1
    if k > 1 and math.hypot(out[k - 1, 0] - out[0, 0], out[k - 1, 1] - out[0, 1]) <= eps:
        k -= 1
    if k < 3:
        return 0, 0.0
    twice = 0.0
    for i in range(k):
        j = (i + 1) % k
        twice += out[i, 0] * out[j, 1] - out[j, 0] * out[i, 1]
    return k, 0.5 * twice


@njit(cache=True)
def _clip_buffers(ring_start, n_sides):
    """Three (size, 2) work arrays, large enough for any ring pair clipped once more by an
    ``n_sides``-gon."""
    longest = 3
    for r in range(ring_start.shape[0] - 1):
        longest = max(longest, ring_start[r + 1] - ring_start[r])
    size = 2 * max(longest, n_sides) + 2
    return np.empty((size, 2), np.float64), np.empty((size, 2), np.float64), np.empty((size, 2), np.float64)


@njit(cache=True)
def _ring_pair(uv, ring_start, a, b, subject, clip, nxt):
    """Ring a clipped by ring b (both made counter-clockwise): (buffer, count)."""
    ns = _ccw_copy(uv, ring_start[a], ring_start[a + 1], subject)
    nc = _ccw_copy(uv, ring_start[b], ring_start[b + 1], clip)
    return _clip_by_ring(subject, ns, clip, nc, nxt)


@njit(cache=True)
def clip_convex_pairs(uv, ring_start, pair_a, pair_b, eps, area):
    """Area of the intersection of convex rings a and b for every pair (ring a clipped by each edge
    of ring b, both taken counter-clockwise; consecutive vertices closer than ``eps`` merged).

    ``uv (v, 2)`` float64 and ``ring_start (r + 1,)`` int64: the rings; ``pair_a, pair_b (k,)``
    int64; writes ``area (k,)``. No checks: rings convex, with at least three vertices.
    """
    subject, clip, nxt = _clip_buffers(ring_start, 0)
    for k in range(pair_a.shape[0]):
        poly, m = _ring_pair(uv, ring_start, pair_a[k], pair_b[k], subject, clip, nxt)
        _, area[k] = _merge_close(poly, m, eps, clip)


@njit(cache=True)
def disk_overlap(uv, ring_start, pair_a, pair_b, centre, radius, n_sides, eps, real):
    """Fractured area of the intersection of rings a and b on a disk: all of it when every vertex
    lies within ``radius[k]`` of ``centre[k]`` (exact, both convex), else its overlap with the
    inscribed regular ``n_sides``-gon of the disk (vertices at angles 2πi/n_sides).

    Arguments as :func:`clip_convex_pairs`, plus ``centre (k, 2)``, ``radius (k,)`` float64; writes
    ``real (k,)``. No checks: rings convex, with at least three vertices.
    """
    subject, clip, nxt = _clip_buffers(ring_start, n_sides)
    shared = np.empty_like(subject)
    for k in range(pair_a.shape[0]):
        poly, m = _ring_pair(uv, ring_start, pair_a[k], pair_b[k], subject, clip, nxt)
        m, real[k] = _merge_close(poly, m, eps, shared)
        cu, cv, r = centre[k, 0], centre[k, 1], radius[k]
        inside = True
        for i in range(m):
            if math.hypot(shared[i, 0] - cu, shared[i, 1] - cv) > r:
                inside = False
        if inside:
            continue
        for i in range(n_sides):
            angle = 2.0 * math.pi * i / n_sides
            clip[i, 0] = cu + r * math.cos(angle)
            clip[i, 1] = cv + r * math.sin(angle)
        poly, m = _clip_by_ring(shared, m, clip, n_sides, nxt)
        _, real[k] = _merge_close(poly, m, eps, subject)


@njit(cache=True)
def project_faces(verts, face_start, faces, e1, e2, ring_start, uv, lo, hi):
    """In-plane coordinates of the given faces: face ``faces[r]`` becomes ring r, written to
    ``uv[ring_start[r]:ring_start[r + 1]]`` as (x·e1[r], x·e2[r]), with its bounding box in
    ``lo[r], hi[r]``. ``e1, e2 (r, 3)`` float64. No checks: ``ring_start`` holds the face sizes."""
    for r in range(faces.shape[0]):
        f = faces[r]
        for c in range(2):
            lo[r, c] = np.inf
            hi[r, c] = -np.inf
        for i in range(face_start[f + 1] - face_start[f]):
            v = face_start[f] + i
            q = ring_start[r] + i
            uv[q, 0] = verts[v, 0] * e1[r, 0] + verts[v, 1] * e1[r, 1] + verts[v, 2] * e1[r, 2]
            uv[q, 1] = verts[v, 0] * e2[r, 0] + verts[v, 1] * e2[r, 1] + verts[v, 2] * e2[r, 2]
            for c in range(2):
                lo[r, c] = min(lo[r, c], uv[q, c])
                hi[r, c] = max(hi[r, c], uv[q, c])
