"""Every geometric tolerance of :mod:`rockmass.blockgen`, each tied to the model size and explained.

Block geometry is computed in float64 by GEOS (through shapely) and numpy. Absolute tolerances would
be wrong for a 1 m shake-table model and a 500 m cavern at once, so every length tolerance here is a
fraction of the model size ``L`` (the diagonal of the domain's bounding box) or of the solver's
corner rounding ``d`` (docs/blocks.md §6: ``d`` ≈ 1 % of a typical edge, minimum edge ``2d``).

============================  ==========================  ==========================================
name                          value                       why
============================  ==========================  ==========================================
``grid_m``                    ``2^⌊log2(1e-12·L)⌋``       the snap-rounding grid of the noding: every
                                                          node lies on it, so intersections closer
                                                          than it are one node. Far above float64
                                                          round-off (~1e-16 · L), and small enough
                                                          that snapping the domain outline changes
                                                          its area by < 1e-11 relative (the area
                                                          balance criterion is 1e-9). A power of two,
                                                          so on-grid inputs (0.25, 1.0) stay exact.
``snap_m``                    ``1e-9 · L``                convex cuts overhang the edge they end on by
                                                          16 · snap_m, so that noding always meets
                                                          that edge (the overhang is a dangle that
                                                          polygonisation drops); 1000 grid cells,
                                                          far below any physical length.
``label_m``                   ``1e-7 · L``                an edge midpoint within this distance of a
                                                          source line (joint, trace, boundary) came
                                                          from it; wider than ``snap_m`` because GEOS
                                                          moves noded points by up to ~1e-12 · L.
``reflex_sin``                ``1e-9``                    a vertex is reflex (concave) when the sine of
                                                          its turn is below ``-reflex_sin``: collinear
                                                          vertices left by noding (turn 0) stay convex.
``reflex_m``                  ``8 · grid_m``              ... and it lies more than ``reflex_m`` inside
                                                          the chord of its two neighbours.
                                                          Snap-rounding puts every node on the grid,
                                                          up to grid·√2/2 off the line it lies on, so
                                                          a collinear T-junction (a crack or cut
                                                          ending on an edge) can turn by a sine of
                                                          ~grid / edge — above ``reflex_sin`` for
                                                          edges shorter than 1000 grid cells —
                                                          while sitting < 2 grid cells off the line.
``rounding_m``                ``0.01 ·`` median edge      the solver's corner rounding ``d``
                              (or given)                  (docs/blocks.md §6, UDEC's default ratio).
                                                          With potential cracks of size ``s`` the
                                                          typical edge is at most ``0.5 · s`` (the
                                                          median edge of a Voronoi subdivision of
                                                          cells of area s²; a regular hexagon of
                                                          that area has side 0.62 s), since the
                                                          solver's blocks are then the sub-blocks.
``min_edge_m``                ``2 · rounding_m``          the solver needs every edge >= 2d; a convex
                                                          cut ending nearer than this to a vertex is
                                                          snapped onto the vertex, and shorter edges
                                                          that remain are listed in the quality report.
``sliver_width_m``            ``min_edge_m``              a block whose mean width ``2·area/perimeter``
                                                          is below the minimum edge cannot hold a
                                                          rounded corner: it is merged (see
                                                          :mod:`rockmass.blockgen.builder`).
``area_balance_rtol``         ``1e-9``                    |Σ block area − domain area| / domain area
                                                          accepted as exact (the Accuracy criterion).
============================  ==========================  ==========================================
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

__all__ = ["Tolerances", "model_tolerances", "ROUNDING_FRACTION", "SNAP_FRACTION", "GRID_FRACTION", "LABEL_FRACTION",
           "REFLEX_SIN", "AREA_BALANCE_RTOL", "CRACK_EDGE_FRACTION", "REFLEX_GRID_CELLS"]

#: d / typical edge (docs/blocks.md §6).
ROUNDING_FRACTION = 0.01
#: snap distance / model size.
SNAP_FRACTION = 1e-9
#: noding grid / model size (rounded down to a power of two).
GRID_FRACTION = 1e-12
#: labelling distance / model size.
LABEL_FRACTION = 1e-7
#: sine of the turn below which (negated) a vertex is reflex.
REFLEX_SIN = 1e-9
#: typical edge / potential-crack size (an upper bound used for the rounding d with cracks).
CRACK_EDGE_FRACTION = 0.5
#: reflex height tolerance / noding grid.
REFLEX_GRID_CELLS = 8
#: relative area balance accepted as exact.
AREA_BALANCE_RTOL = 1e-9


@dataclass(frozen=True)
class Tolerances:
    """Resolved tolerances of one model, in metres (see the module table for each reason)."""

    model_size_m: float
    grid_m: float
    snap_m: float
    label_m: float
    rounding_m: float
    min_edge_m: float
    sliver_width_m: float
    reflex_sin: float = REFLEX_SIN
    reflex_m: float = 0.0
    area_balance_rtol: float = AREA_BALANCE_RTOL

    def to_dict(self) -> dict:
        return asdict(self)


def model_tolerances(model_size_m: float, typical_edge_m: float, rounding_m: float | None = None,
                     min_edge_m: float | None = None) -> Tolerances:
    """Tolerances for a model of size ``model_size_m`` whose typical edge is ``typical_edge_m``.

    Parameters
    ----------
    model_size_m : float
        Diagonal of the domain's bounding box, > 0.
    typical_edge_m : float
        A typical block edge (the median edge of the cut blocks), > 0.
    rounding_m : float, optional
        Corner rounding d; default ``ROUNDING_FRACTION · typical_edge_m``.
    min_edge_m : float, optional
        Minimum edge; default ``2 · rounding_m``.

    Examples
    --------
    >>> t = model_tolerances(10.0, 0.5)
    >>> round(t.rounding_m, 6), round(t.min_edge_m, 6), t.snap_m
    (0.005, 0.01, 1e-08)
    """
    d = ROUNDING_FRACTION * typical_edge_m if rounding_m is None else float(rounding_m)
    e = 2.0 * d if min_edge_m is None else float(min_edge_m)
    grid = 2.0 ** math.floor(math.log2(GRID_FRACTION * model_size_m))
    return Tolerances(model_size_m=float(model_size_m), grid_m=grid, snap_m=SNAP_FRACTION * model_size_m,
                      label_m=LABEL_FRACTION * model_size_m, rounding_m=d, min_edge_m=e,
                      sliver_width_m=e, reflex_m=REFLEX_GRID_CELLS * grid)
