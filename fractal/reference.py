"""Reference fractals with exact box-counting dimensions, for tests, benchmarks and users' checks.

Each pixel fractal is exact only on its own base grid (side b**level) with base-matched box sizes
(powers of b), where the box count is exactly N = m**k and D = log m / log b to machine precision
(docs/fractal.md §7, eq. (7.1)). Drawn into a 360 grid (:func:`embed`) they come out 0.04–0.17 low: that is the
raster method's error, which the benchmark shows. The triadic Koch curve is a polyline and is never
raster-exact.

=====================  ==========  =======================  ====================
generator              base grid   rule                     D
=====================  ==========  =======================  ====================
sierpinski_triangle    2**level    (i & j) == 0             log 3 / log 2
sierpinski_carpet      3**level    no digit pair (1, 1)     log 8 / log 3
cantor_dust            3**level    no base-3 digit 1        log 4 / log 3
vicsek                 3**level    digit pairs in a cross   log 5 / log 3
koch_curve             polyline    4 pieces of 1/3          log 4 / log 3
straight_line          segment     one segment              1 (exact at 0/45/90°)
filled_square          any         all pixels               2
=====================  ==========  =======================  ====================
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["EXACT_DIMENSIONS", "sierpinski_triangle", "sierpinski_carpet", "cantor_dust",
           "vicsek", "koch_curve", "straight_line", "filled_square", "polyline_segments",
           "embed"]

EXACT_DIMENSIONS = {
    "sierpinski_triangle": math.log(3) / math.log(2),
    "sierpinski_carpet": math.log(8) / math.log(3),
    "cantor_dust": math.log(4) / math.log(3),
    "vicsek": math.log(5) / math.log(3),
    "koch_curve": math.log(4) / math.log(3),
    "filled_square": 2.0,
    "line": 1.0,
}


def _check_level(level, maximum):
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or not 0 <= level <= maximum:
        raise ValueError(f"level must be an integer in [0, {maximum}], got {level!r}")
    return int(level)


def _base3_digit_rule(level: int, allowed) -> np.ndarray:
    """Pixels of a 3**level grid whose base-3 digit pairs (row digit, column digit) are all allowed."""
    n = 3**level
    idx = np.arange(n)
    keep = np.ones((n, n), dtype=bool)
    table = np.zeros((3, 3), dtype=bool)
    for r, c in allowed:
        table[r, c] = True
    for k in range(level):
        digit = (idx // 3**k) % 3
        keep &= table[digit[:, None], digit[None, :]]
    return keep.astype(np.uint8)


def sierpinski_triangle(level: int) -> np.ndarray:
    """Sierpinski triangle on a ``2**level`` grid: pixel (i, j) is set iff ``i & j == 0``.

    D = log 3 / log 2 = 1.58496.

    Examples
    --------
    >>> int(sierpinski_triangle(3).sum()) == 3**3
    True
    """
    n = 2**_check_level(level, 14)
    i = np.arange(n)
    return ((i[:, None] & i[None, :]) == 0).astype(np.uint8)


def sierpinski_carpet(level: int) -> np.ndarray:
    """Sierpinski carpet on a ``3**level`` grid (the centre ninth removed at every scale).

    D = log 8 / log 3 = 1.89279.
    """
    allowed = [(r, c) for r in range(3) for c in range(3) if (r, c) != (1, 1)]
    return _base3_digit_rule(_check_level(level, 9), allowed)


def cantor_dust(level: int) -> np.ndarray:
    """Cantor dust on a ``3**level`` grid: the four corner ninths kept at every scale.

    D = log 4 / log 3 = 1.26186.
    """
    return _base3_digit_rule(_check_level(level, 9), [(0, 0), (0, 2), (2, 0), (2, 2)])


def vicsek(level: int) -> np.ndarray:
    """Vicsek fractal (cross form) on a ``3**level`` grid: centre and four edge ninths kept.

    D = log 5 / log 3 = 1.46497.
    """
    return _base3_digit_rule(_check_level(level, 9), [(1, 1), (0, 1), (1, 0), (1, 2), (2, 1)])


def koch_curve(level: int) -> np.ndarray:
    """Triadic Koch curve from (0, 0) to (1, 0) as a polyline ``(4**level + 1, 2) float64``.

    Every segment is replaced by four of a third of its length, the middle two forming an
    equilateral bump. D = log 4 / log 3 = 1.26186.

    Examples
    --------
    >>> koch_curve(1).round(4).tolist()
    [[0.0, 0.0], [0.3333, 0.0], [0.5, 0.2887], [0.6667, 0.0], [1.0, 0.0]]
    """
    level = _check_level(level, 10)
    pts = np.array([[0.0, 0.0], [1.0, 0.0]])
    c, s = math.cos(math.pi / 3), math.sin(math.pi / 3)
    for _ in range(level):
        a, b = pts[:-1], pts[1:]
        d = (b - a) / 3.0
        p1 = a + d
        p3 = a + 2.0 * d
        p2 = p1 + np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]])
        new = np.empty((4 * a.shape[0] + 1, 2))
        new[0:-1:4] = a
        new[1::4] = p1
        new[2::4] = p2
        new[3::4] = p3
        new[-1] = pts[-1]
        pts = new
    return pts


def straight_line(angle_deg: float = 0.0, length_m: float = 1.0) -> np.ndarray:
    """One straight segment through the origin at ``angle_deg`` (counter-clockwise from +x).

    Returns ``(1, 4) float64`` (x0, y0, x1, y1). Its box count is exactly N/s boxes at every
    divisor size s of the grid, hence D = 1 to machine precision, when the angle is a multiple of
    45°; at other angles the segment also crosses box rows, and D is 1 only as the boxes shrink.

    Examples
    --------
    >>> straight_line(90.0, 2.0).round(12).tolist()
    [[-0.0, -1.0, 0.0, 1.0]]
    """
    if not (np.isfinite(angle_deg) and np.isfinite(length_m) and length_m > 0):
        raise ValueError(f"angle_deg must be finite and length_m > 0, got {angle_deg}, {length_m}")
    a = math.radians(angle_deg)
    direction = np.array([math.cos(a), math.sin(a)])
    direction[np.abs(direction) < 1e-15] = 0.0  # exact axes at multiples of 90°
    half = 0.5 * length_m * direction
    return np.concatenate([-half, half])[None, :]


def filled_square(n: int = 360) -> np.ndarray:
    """An ``n x n`` image with every pixel set (D = 2)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    return np.ones((n, n), dtype=np.uint8)


def polyline_segments(polyline) -> np.ndarray:
    """Consecutive vertex pairs of a polyline as segments ``(k - 1, 4)``: x0, y0, x1, y1."""
    p = np.asarray(polyline, dtype=np.float64)
    return np.hstack([p[:-1], p[1:]])


def embed(pattern, grid: int = 360) -> np.ndarray:
    """Draw a base-grid pixel fractal into a ``grid x grid`` image by nearest-neighbour scaling.

    Pixel (r, c) of the result takes ``pattern[floor(r * n / grid), floor(c * n / grid)]``, n the
    pattern's side. This is how a fractal drawn at one resolution reaches the 360 grid, and its
    counted D shows the raster method's error away from the base grid.
    """
    p = np.asarray(pattern)
    if p.ndim != 2 or p.shape[0] != p.shape[1]:
        raise ValueError(f"pattern must be a square 2-D array, got shape {p.shape}")
    idx = (np.arange(grid) * p.shape[0]) // grid
    return np.ascontiguousarray(p[idx[:, None], idx[None, :]], dtype=np.uint8)
