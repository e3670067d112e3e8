"""Plane polygon measures shared by every stage: the shoelace area of a vertex ring.

This is the one implementation of the polygon area formula in rockmass. ``dfn`` sits at the bottom
of the stages' dependency direction (imaging, blockgen, solver and the pipeline all import it), so
each of them can call it; ``fractal`` imports nothing of ours and measures its face polygons with
shapely instead (docs/fractal.md §3).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["polygon_area", "signed_area"]


def signed_area(xy: ArrayLike) -> float:
    r"""Signed area of a polygon ring by the shoelace formula, > 0 when counter-clockwise.

    Parameters
    ----------
    xy : (k, 2) array_like of float
        Ring vertices (x, y), open (the closing edge from the last vertex back to the first is
        implied); a closing vertex equal to the first adds a zero-length edge and changes nothing.

    Returns
    -------
    float
        :math:`A = \tfrac12 \sum_i (x_i y_{i+1} - x_{i+1} y_i)` in the square of the input unit,
        indices cyclic (docs/fractures.md §1, eq. (1.3)). Fewer than 3 vertices give 0.

    Notes
    -----
    The coordinates are taken relative to the first vertex before the products are formed: the
    formula is translation-invariant, and far from the origin (UTM eastings of ~10⁵–10⁶ m) the raw
    products would cancel to a few significant digits.

    Examples
    --------
    >>> signed_area([[0, 0], [2, 0], [2, 1], [0, 1]])
    2.0
    >>> signed_area([[0, 0], [0, 1], [2, 1], [2, 0]])   # clockwise
    -2.0
    >>> signed_area([[500000.0, 4e6], [500001.0, 4e6], [500000.0, 4e6 + 1.0]])
    0.5
    """
    ring = np.asarray(xy, dtype=np.float64)
    if ring.shape[0] < 3:
        return 0.0
    x, y = ring[:, 0] - ring[0, 0], ring[:, 1] - ring[0, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def polygon_area(xy: ArrayLike) -> float:
    """Unsigned area of a polygon ring, ``abs(signed_area(xy))``.

    Examples
    --------
    >>> polygon_area([[0, 0], [0, 3], [4, 0]])
    6.0
    """
    return abs(signed_area(xy))
