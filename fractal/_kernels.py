"""Numba kernels of the fractal stage: cell traversal of segments, polygons, and box counting.

All kernels take plain C-contiguous arrays of one dtype (float64 coordinates, int64 indices and
counts, uint8 masks, uint64 bit rows), write into arrays the caller allocated and do no checks.
They live in one file because numba's on-disk cache does not see edits to jitted helpers in other
files.

Bit rows (raster box counting and the thick-line test)
------------------------------------------------------
A mask is packed 64 pixels to a word (``rockmass.fractal.image._pack_rows``: bit c of a row is bit
c % 64 of word c // 64), so a row operation — OR with another row,
a shift by some columns, a population count — handles 64 pixels at once (the thick-line test,
``image._line_counts``, does the same in numpy). The raster count grows the
OR window of each box size from the previous one, and reads every grid offset off it; its cost does
not depend on how many pixels are traces, nor much on the number of offsets.

The cell rule (shared by rasterisation and exact vector counting)
-----------------------------------------------------------------
Coordinates are in *box units*: box (i, j) is the half-open square [i, i+1) x [j, j+1). A segment is
split at every grid line it crosses; each piece of positive length (longer than ``_PIECE_EPS`` box
units) marks the box that contains the piece's midpoint, ``(floor(mx), floor(my))``. So a segment marks
exactly the boxes it passes through; a pass through a box corner marks nothing extra (diagonals and
anti-diagonals are treated alike); a piece running along a grid line is given to the box above / to
the right. A coordinate equal to the far edge of the grid is given to the last box. With
``strict=True`` pieces lying on a grid line mark nothing: that is the rule for polygon *boundaries*,
whose interior cells are found from cell centres instead.

Compile time
------------
The helpers used by every count have one explicit signature each (compiled, or read from numba's
cache, on import), so a literal argument (``strict=True`` at one call, ``False`` at another) does
not compile them twice; the kernels use plain loops, not numba's sort, ``np.round`` or
``reshape``, whose implementations add seconds of compilation to a first run. The rare paths
(Bresenham lines, grids too large for a mark array) are kernels of their own behind the Python
dispatchers :func:`rasterize_segments` and :func:`count_crossed_boxes`: compiled only when used.
"""

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

_PIECE_EPS = 1e-9  # pieces shorter than this (box units) are corner touches, not crossings

_F8, _I8 = types.float64, types.int64
_SEG = types.Array(types.float64, 2, "C", readonly=True)  # read-only: writable arrays convert
_MARKS = types.uint8[:, ::1]
_IDS = types.int64[::1]


@njit(types.UniTuple(_F8, 2)(_F8, _F8), cache=True)
def _first_crossing(p0, dp):
    """Parameter t of the first grid line crossed along one axis, and the step between lines.

    The segment is p0 + t * dp, t in [0, 1]; grid lines are at the integers. Returns (inf, inf)
    when the segment runs parallel to the lines.
    """
    if dp > 0.0:
        return (np.floor(p0) + 1.0 - p0) / dp, 1.0 / dp
    if dp < 0.0:
        return (np.ceil(p0) - 1.0 - p0) / dp, -1.0 / dp
    return np.inf, np.inf


@njit(_I8(_F8, _F8, _F8, _F8, _I8, _I8, types.boolean, _IDS), cache=True)
def _segment_cells(x0, y0, x1, y1, nbx, nby, strict, ids):
    """Write the ids ``j * nbx + i`` of the cells crossed by one segment (box units) into ``ids``.

    Returns the number written; consecutive pieces lie in distinct cells, so there are no repeats
    within one segment. No checks: endpoints in [0, nbx] x [0, nby], and ``ids`` holds at least
    ``_cell_bound`` entries.
    """
    dx = x1 - x0
    dy = y1 - y0
    length = np.sqrt(dx * dx + dy * dy)
    if length <= 0.0:
        return 0
    tx0, dtx = _first_crossing(x0, dx)
    ty0, dty = _first_crossing(y0, dy)
    tx = tx0
    ty = ty0
    kx = 0  # grid lines crossed so far; t of the next one is tx0 + kx * dtx (no summed round-off)
    ky = 0
    n = 0
    t = 0.0
    while t < 1.0:
        tn = min(tx, ty, 1.0)
        if (tn - t) * length > _PIECE_EPS:
            tm = 0.5 * (t + tn)
            mx = x0 + tm * dx
            my = y0 + tm * dy
            fx = np.floor(mx)
            fy = np.floor(my)
            if not (strict and (mx == fx or my == fy)):
                i = min(max(int(fx), 0), nbx - 1)
                j = min(max(int(fy), 0), nby - 1)
                ids[n] = j * nbx + i
                n += 1
        if tn == tx:
            kx += 1
            tx = tx0 + kx * dtx
        if tn == ty:
            ky += 1
            ty = ty0 + ky * dty
        t = tn
    return n


@njit(_I8(_SEG, _F8), cache=True)
def _cell_bound(seg, scale):
    """Upper bound on the cells one segment of ``seg`` (n, 4) crosses at 1/scale box size."""
    bound = 0
    for k in range(seg.shape[0]):
        b = int(np.ceil(abs(seg[k, 2] - seg[k, 0]) * scale) + np.ceil(abs(seg[k, 3] - seg[k, 1]) * scale)) + 3
        bound = max(bound, b)
    return bound


@njit(_I8(_F8, _F8, _F8, _F8, _I8, _I8, _MARKS, types.boolean, _IDS), cache=True)
def _mark_segment(x0, y0, x1, y1, nbx, nby, marks, strict, scratch):
    """Mark the cells crossed by one segment in ``marks`` (nby, nbx) uint8; return cells newly marked."""
    n = _segment_cells(x0, y0, x1, y1, nbx, nby, strict, scratch)
    cols = marks.shape[1]  # the id is a flat index into the C-ordered marks
    new = 0
    for m in range(n):
        r = scratch[m] // cols
        c = scratch[m] - r * cols
        if marks[r, c] == 0:
            marks[r, c] = 1
            new += 1
    return new


@njit(cache=True)
def _mark_bresenham(x0, y0, x1, y1, nbx, nby, marks):
    """Mark an 8-connected Bresenham line between the cells holding the two endpoints."""
    i0 = min(max(int(np.floor(x0)), 0), nbx - 1)
    j0 = min(max(int(np.floor(y0)), 0), nby - 1)
    i1 = min(max(int(np.floor(x1)), 0), nbx - 1)
    j1 = min(max(int(np.floor(y1)), 0), nby - 1)
    di = abs(i1 - i0)
    dj = -abs(j1 - j0)
    si = 1 if i0 < i1 else -1
    sj = 1 if j0 < j1 else -1
    err = di + dj
    new = 0
    while True:
        if marks[j0, i0] == 0:
            marks[j0, i0] = 1
            new += 1
        if i0 == i1 and j0 == j1:
            break
        e2 = 2 * err
        if e2 >= dj:
            err += dj
            i0 += si
        if e2 <= di:
            err += di
            j0 += sj
    return new


def rasterize_segments(seg, nbx, nby, marks, bresenham):
    """Mark the cells of all segments ``seg`` (n, 4) float64 in box units; return cells marked.

    A Python dispatcher over two kernels, so that a run compiles only the line rule it uses."""
    if bresenham:
        return _rasterize_bresenham(seg, nbx, nby, marks)
    return _rasterize_supercover(seg, nbx, nby, marks)


@njit(cache=True)
def _rasterize_supercover(seg, nbx, nby, marks):
    """:func:`rasterize_segments` with the cell rule (every cell a segment passes through)."""
    scratch = np.empty(_cell_bound(seg, 1.0), dtype=np.int64)
    total = 0
    for k in range(seg.shape[0]):
        total += _mark_segment(seg[k, 0], seg[k, 1], seg[k, 2], seg[k, 3], nbx, nby, marks,
                               False, scratch)
    return total


@njit(cache=True)
def _rasterize_bresenham(seg, nbx, nby, marks):
    """:func:`rasterize_segments` with 8-connected Bresenham lines."""
    total = 0
    for k in range(seg.shape[0]):
        total += _mark_bresenham(seg[k, 0], seg[k, 1], seg[k, 2], seg[k, 3], nbx, nby, marks)
    return total


@njit(types.boolean(_F8, _F8, _SEG), cache=True)
def _point_in_ring(px, py, ring):
    """Even-odd rule: is (px, py) inside the closed ring (k, 2) (first vertex not repeated)?"""
    inside = False
    k = ring.shape[0]
    j = k - 1
    for i in range(k):
        xi = ring[i, 0]
        yi = ring[i, 1]
        xj = ring[j, 0]
        yj = ring[j, 1]
        if (yi > py) != (yj > py):
            xc = xi + (py - yi) * (xj - xi) / (yj - yi)
            if px < xc:
                inside = not inside
        j = i
    return inside


@njit(cache=True)
def mark_polygon_cells(ring, nbx, nby, marks):
    """Mark the cells whose interior meets the polygon ``ring`` (k, 2) float64, box units.

    A cell meets the polygon's interior iff its centre is inside, or the boundary passes through the
    cell's open interior (``strict`` traversal of every edge). Returns the number of cells marked.
    """
    k = ring.shape[0]
    xmin = ring[0, 0]
    xmax = ring[0, 0]
    ymin = ring[0, 1]
    ymax = ring[0, 1]
    for i in range(k):
        xmin = min(xmin, ring[i, 0])
        xmax = max(xmax, ring[i, 0])
        ymin = min(ymin, ring[i, 1])
        ymax = max(ymax, ring[i, 1])
    edges = np.empty((k, 4), dtype=np.float64)
    for i in range(k):
        j = (i + 1) % k
        edges[i, 0] = ring[i, 0]
        edges[i, 1] = ring[i, 1]
        edges[i, 2] = ring[j, 0]
        edges[i, 3] = ring[j, 1]
    scratch = np.empty(_cell_bound(edges, 1.0), dtype=np.int64)
    total = 0
    for i in range(k):
        total += _mark_segment(edges[i, 0], edges[i, 1], edges[i, 2], edges[i, 3], nbx, nby, marks,
                               True, scratch)
    j0 = max(int(np.floor(ymin)), 0)
    j1 = min(int(np.ceil(ymax)), nby)
    i0 = max(int(np.floor(xmin)), 0)
    i1 = min(int(np.ceil(xmax)), nbx)
    for j in range(j0, j1):
        for i in range(i0, i1):
            if marks[j, i] == 0 and _point_in_ring(i + 0.5, j + 0.5, ring):
                marks[j, i] = 1
                total += 1
    return total


@njit(_I8(_MARKS, _I8, _I8), cache=True)
def fold_and_count(marks, nbx, nby):
    """Fold a shifted grid onto the torus and count marked boxes.

    ``marks`` (rows, cols) uint8 holds the boxes of a grid shifted against the frame; when it has
    one row (column) more than ``nby`` (``nbx``), that last partial row is the other part of the
    partial first row, so it is OR-ed into row 0 (column 0). Returns the marked boxes of the
    ``nby x nbx`` torus grid. Modifies ``marks``.
    """
    if marks.shape[0] > nby:
        for i in range(marks.shape[1]):
            if marks[nby, i]:
                marks[0, i] = 1
    if marks.shape[1] > nbx:
        for j in range(marks.shape[0]):
            if marks[j, nbx]:
                marks[j, 0] = 1
    total = 0
    for j in range(nby):
        for i in range(nbx):
            if marks[j, i]:
                total += 1
    return total


@intrinsic
def _popcount(typingctx, word):
    """Set bits of a uint64 as an int64 (LLVM ``ctpop``: one instruction where the CPU has one)."""
    if not (isinstance(word, types.Integer) and word.bitwidth == 64 and not word.signed):
        return None

    def codegen(context, builder, signature, args):
        return builder.ctpop(args[0])

    return types.int64(types.uint64), codegen


@njit(cache=True)
def _grow_window(src, dst, n, b, row):
    """``dst`` = the cyclic OR window of side a + b from ``src``, that of side a >= b.

    A window of side a at (r, c) is the OR of pixels (r .. r + a - 1 mod n, c .. c + a - 1). Its
    union with the windows at (r + b, c), (r, c + b) and (r + b, c + b) is the window of side
    a + b when b <= a: rows first (whole words), then columns (a shift of b bits across words).
    ``row`` is scratch of one row's words.
    """
    nw = src.shape[1]
    q = b >> 6
    p = np.uint64(b & 63)
    back = np.uint64(63 - (b & 63))  # << (64 - p) written as (<< 1) << back: defined for p = 0
    one = np.uint64(1)
    inner = nw - q - 1  # words whose source words both lie inside the row
    for r in range(n):
        r2 = r + b
        if r2 >= n:
            r2 -= n
        for w in range(nw):
            row[w] = src[r, w] | src[r2, w]
        for w in range(inner):
            dst[r, w] = row[w] | (row[w + q] >> p) | ((row[w + q + 1] << one) << back)
        for w in range(max(inner, 0), nw):
            dst[r, w] = row[w] | (row[w + q] >> p) if w + q < nw else row[w]


@njit(cache=True)
def count_occupied_boxes(bits, sizes, order, off_r, off_c, counts):
    """Count occupied boxes of a square mask (n, n) for every size and grid offset.

    bits : (n, nw) uint64 bit rows of the mask with its first columns repeated after the last, up
    to ``width = n + max(s - 1)`` over the sizes that give at least 2 boxes a side
    (``image._pack_rows``), so that a box wrapping round the right edge is one run of bits;
    overwritten (it becomes the OR window).
    sizes : (n_sizes,) int64 box sides in pixels, each dividing n.
    order : (n_sizes,) int64 the indices that sort ``sizes`` ascending (``np.argsort``, given by
    the caller: numba's own sort would add about 2 s of compilation).
    off_r, off_c : (n_sizes, n_offsets) int64 shifts of the box grid in pixels (0 <= off < size).
    A shifted grid is applied cyclically (the frame is a torus): box (a, b) covers rows
    [a*s - off_r, (a+1)*s - off_r) modulo n, so every grid has exactly (n/s)^2 whole boxes and no
    ring of partial boxes at the frame's edge.
    counts : (n_sizes, n_offsets) int64, written.

    One pass over the sizes in ascending order grows the OR window of side s (the window of the
    previous size widened by b <= its side, 64 pixels per operation); a box of side s is occupied
    iff the window at its top-left pixel is set. The boxes of one grid are every s-th window row
    and column from ((s - off) mod s), so each (size, offset) costs (n/s) rows of masked
    population counts, whatever the image holds. No checks: sizes divide n, offsets in range.
    """
    n = bits.shape[0]
    nw = bits.shape[1]
    full = n >> 6
    rest = np.uint64(n & 63)
    pixels = 0  # trace pixels: bits before column n
    for r in range(n):
        for w in range(full):
            pixels += _popcount(bits[r, w])
        if rest:
            pixels += _popcount(bits[r, full] & ((np.uint64(1) << rest) - np.uint64(1)))
    win = bits
    spare = np.empty((n, nw), dtype=np.uint64)
    row = np.empty(nw, dtype=np.uint64)
    lattice = np.empty(nw, dtype=np.uint64)
    side = 1
    for a in order:
        s = sizes[a]
        m = n // s
        if s == 1 or m == 1:
            value = pixels if s == 1 else min(pixels, 1)
            for b in range(off_r.shape[1]):
                counts[a, b] = value
            continue
        while side < s:
            step = min(side, s - side)
            _grow_window(win, spare, n, step, row)
            win, spare = spare, win
            side += step
        for b in range(off_r.shape[1]):
            r0 = (s - off_r[a, b]) % s
            c0 = (s - off_c[a, b]) % s
            for w in range(nw):
                lattice[w] = 0
            for j in range(m):
                c = c0 + j * s
                lattice[c >> 6] |= np.uint64(1) << np.uint64(c & 63)
            used = ((c0 + (m - 1) * s) >> 6) + 1
            total = 0
            for i in range(m):
                r = r0 + i * s
                for w in range(used):
                    total += _popcount(win[r, w] & lattice[w])
            counts[a, b] = total
    return counts


def count_crossed_boxes(seg, side, sizes, offsets, max_mark_cells, counts, n_boxes):
    """Exact vector box counting: boxes of side ``sizes[a]`` crossed by the segments.

    seg : (n, 4) float64 segments relative to the frame origin (frame units, e.g. metres), inside
    [0, side]^2. offsets : (n_offsets, 2) float64 grid shifts as fractions of a box, in [0, 1).
    counts, n_boxes : (n_sizes, n_offsets) int64, written: boxes crossed, and boxes in the covering
    grid. When the size divides the side (to 1e-9) a shifted grid is applied cyclically, as in
    ``count_occupied_boxes``; otherwise the grid covers the frame with partial boxes at the far
    edges. Grids of at most ``max_mark_cells`` boxes use a mark array; larger ones collect the box
    ids of every piece and count distinct ids after a sort, so any box size works.
    No checks: sizes > 0, segments inside the frame.

    A Python dispatcher: :func:`_count_marked_boxes` counts the grids that fit a mark array and
    leaves the others at -1 for :func:`_count_distinct_boxes`, compiled only when a grid needs it.
    """
    _count_marked_boxes(seg, side, sizes, offsets, max_mark_cells, counts, n_boxes)
    if (counts < 0).any():
        _count_distinct_boxes(seg, side, sizes, offsets, max_mark_cells, counts)
    return counts


@njit(types.UniTuple(_I8, 4)(_F8, _F8, _F8, _F8), cache=True)
def _shifted_grid(side, d, ox, oy):
    """Boxes per axis (nbx, nby) of the grid of side ``d`` shifted by (ox, oy) that covers
    [0, side]^2, and the boxes per axis that count (nbx_eff, nby_eff): a cyclic grid (``d``
    divides ``side`` to 1e-9) folds its extra column and row onto the first."""
    whole = side / d
    nearest = round(whole)  # round half to even, as np.round
    cyclic = abs(whole - nearest) <= 1e-9 * whole
    nbx = max(int(np.ceil((side + ox) / d - 1e-9)), 1)
    nby = max(int(np.ceil((side + oy) / d - 1e-9)), 1)
    nbx_eff = min(nbx, nearest) if cyclic else nbx
    nby_eff = min(nby, nearest) if cyclic else nby
    return nbx, nby, nbx_eff, nby_eff


@njit(cache=True)
def _count_marked_boxes(seg, side, sizes, offsets, max_mark_cells, counts, n_boxes):
    """:func:`count_crossed_boxes` on the grids of at most ``max_mark_cells`` boxes (a mark
    array); the counts of larger grids are set to -1."""
    for a in range(sizes.shape[0]):
        d = sizes[a]
        scratch = np.empty(_cell_bound(seg, 1.0 / d), dtype=np.int64)
        for b in range(offsets.shape[0]):
            ox = offsets[b, 0] * d
            oy = offsets[b, 1] * d
            nbx, nby, nbx_eff, nby_eff = _shifted_grid(side, d, ox, oy)
            n_boxes[a, b] = nbx_eff * nby_eff
            if nbx * nby <= max_mark_cells:
                marks = np.zeros((nby, nbx), dtype=np.uint8)
                for k in range(seg.shape[0]):
                    _mark_segment((seg[k, 0] + ox) / d, (seg[k, 1] + oy) / d,
                                  (seg[k, 2] + ox) / d, (seg[k, 3] + oy) / d,
                                  nbx, nby, marks, False, scratch)
                counts[a, b] = fold_and_count(marks, nbx_eff, nby_eff)
            else:
                counts[a, b] = -1
    return counts


@njit(cache=True)
def _count_distinct_boxes(seg, side, sizes, offsets, max_mark_cells, counts):
    """:func:`count_crossed_boxes` on the grids of more than ``max_mark_cells`` boxes."""
    for a in range(sizes.shape[0]):
        d = sizes[a]
        scratch = np.empty(_cell_bound(seg, 1.0 / d), dtype=np.int64)
        for b in range(offsets.shape[0]):
            ox = offsets[b, 0] * d
            oy = offsets[b, 1] * d
            nbx, nby, nbx_eff, nby_eff = _shifted_grid(side, d, ox, oy)
            if nbx * nby > max_mark_cells:
                counts[a, b] = _count_distinct_cells(seg, d, ox, oy, nbx, nby, nbx_eff, nby_eff,
                                                     scratch)
    return counts


@njit(cache=True)
def _count_distinct_cells(seg, d, ox, oy, nbx, nby, nbx_eff, nby_eff, scratch):
    """Distinct boxes crossed on a grid too large for a mark array (ids collected, then sorted).

    Boxes in column ``nbx_eff`` (row ``nby_eff``) of a cyclic grid fold onto column (row) 0.
    """
    total_bound = 0
    for k in range(seg.shape[0]):
        total_bound += int(np.ceil(abs(seg[k, 2] - seg[k, 0]) / d)
                           + np.ceil(abs(seg[k, 3] - seg[k, 1]) / d)) + 3
    ids = np.empty(total_bound, dtype=np.int64)
    n = 0
    for k in range(seg.shape[0]):
        m = _segment_cells((seg[k, 0] + ox) / d, (seg[k, 1] + oy) / d,
                           (seg[k, 2] + ox) / d, (seg[k, 3] + oy) / d, nbx, nby, False, scratch)
        for q in range(m):
            i = scratch[q] % nbx
            j = scratch[q] // nbx
            if i >= nbx_eff:
                i = 0
            if j >= nby_eff:
                j = 0
            ids[n] = j * nbx_eff + i
            n += 1
    if n == 0:
        return 0
    s = _sorted_ids(ids[:n])
    distinct = 1
    for m in range(1, n):
        if s[m] != s[m - 1]:
            distinct += 1
    return distinct


@njit(cache=True)
def _sorted_ids(ids):
    """``ids`` sorted ascending, in a new array (a bottom-up merge sort in plain loops: numba's
    ``np.sort`` adds about a second of compilation; ``solver._kernels._stable_argsort`` is the
    same merge as an argsort of floats — each kernel file stands alone)."""
    n = ids.shape[0]
    a = np.empty(n, np.int64)
    b = np.empty(n, np.int64)
    for k in range(n):
        a[k] = ids[k]
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i = lo
            j = mid
            for k in range(lo, hi):
                if j >= hi or (i < mid and a[i] <= a[j]):
                    b[k] = a[i]
                    i += 1
                else:
                    b[k] = a[j]
                    j += 1
        a, b = b, a
        width *= 2
    return a
