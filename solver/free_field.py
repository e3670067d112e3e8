"""Free-field boundaries: the 1D columns beside the model's lateral sides (docs/dem.md §14.2).

A model cut out of a rock mass that a plane wave crosses from below must not reflect the wave at
its lateral sides, nor let them move as free surfaces. Following seed 001 (Kiran & Juneja 2022,
eqs. 14–16) and Itasca's free field, each lateral side is coupled to a column that moves as the
rock mass far from the model would: a 1D column solved alongside the model and driven by the same
input. The side edges carry

    F = −ρC_p (v_n − v_n^ff) A − ρC_s (v_t − v_t^ff) A + F^ff,    F^ff = σ^ff·n A,      (14.4)

the dashpots absorbing what the model scatters and F^ff the column's stress. σ^ff is the in-situ
stress (constant boundary forces, :func:`rockmass.solver.loading.apply_boundary_stress`, so the
model starts in equilibrium) plus the column's dynamic shear stress; the column starts at rest
in each dynamic stage.

The column of a side is the chain of the blocks along it, bottom to top: element i has the mass
ρh_i per unit width of a block of height h_i on the side, and is joined to the element above by the
rock mass between their centres, 1/k = h_i/(2G_i) + h_(i+1)/(2G_(i+1)) for horizontal motion (M
for vertical), G_i and M_i the equivalent-continuum moduli of block i's joints along the side
(:func:`rockmass.solver.loading.rock_mass_compliance`, docs/dem.md §14.1). For blocks stacked on
horizontal joints k_s this is k_s; for a slab of w × s bricks, whose laterally uniform shear also
slides the vertical joints, 1/k = 1/k_s + s/(k_s w). Each degree of freedom of an element is free,
fixed or prescribed as its block's is (the base input drives the column's foot); a free foot or
top on a quiet side gets that side's dashpot. The column is elastic: its joints neither slip nor
open, and a vertical stress change in it puts no horizontal stress on the model (rigid blocks have
no Poisson effect).
"""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from .loading import boundary_edge_table, boundary_impedance, rock_mass_compliance
from .settings import FreeField

__all__ = ["free_field_columns", "set_free_field"]

def _column(engine, ff: FreeField, side: str, first: int) -> tuple[np.ndarray, np.ndarray]:
    """(edge rows (F, 9), element rows (E, ``K.N_FF_COLUMNS``)) of one side's column, elements
    numbered from ``first``."""
    table = boundary_edge_table(engine, ff, (side,))
    edges = engine.edges
    on = np.flatnonzero(edges.on((side,)))
    ys = np.column_stack([edges.p0[on, 1], edges.p1[on, 1]])
    blocks = table[:, 0].astype(np.int64)
    order = np.unique(blocks)
    lo = np.array([ys[blocks == b].min() for b in order])
    hi = np.array([ys[blocks == b].max() for b in order])
    rank = np.argsort(0.5 * (lo + hi), kind="stable")
    order, lo, hi = order[rank], lo[rank], hi[rank]
    height = hi - lo
    normal = table[:, 3:5].mean(axis=0)
    normal /= np.hypot(*normal)
    rho = engine.settings.material.density_kg_m3
    elem = np.zeros((len(order), K.N_FF_COLUMNS))
    elem[:, K.FF_M] = rho * height
    elem[:, K.FF_ABOVE] = -1.0
    along = np.tile([-normal[1], normal[0]], (len(order), 1))  # the side's direction
    inv = rock_mass_compliance(engine, order, along) * height[:, None]  # (h/M, h/G) per element
    link = 0.5 * (inv[:-1] + inv[1:])  # centre to centre
    if (link <= 0).any():
        i = int(np.flatnonzero((link <= 0).any(axis=1))[0])
        raise ValueError(f"free field on {side!r}: the rock between blocks {int(order[i])} and "
                         f"{int(order[i + 1])} is rigid (no joint); give material.bulk_modulus_pa "
                         "and shear_modulus_pa")
    elem[:-1, K.FF_KX] = 1.0 / link[:, 1]
    elem[:-1, K.FF_KY] = 1.0 / link[:, 0]
    elem[:-1, K.FF_ABOVE] = first + np.arange(1, len(order))
    for d in range(2):
        elem[:, K.FF_MODE_X + d] = engine.mode[order, d]
        elem[:, K.FF_IN_X + d] = engine.dof_input[order, d]
    _quiet_ends(engine, order, elem)
    place = {int(b): first + i for i, b in enumerate(order)}
    return np.column_stack([table, [place[int(b)] for b in blocks]]), elem


def _quiet_ends(engine, order: np.ndarray, elem: np.ndarray) -> None:
    """Dashpots (per unit width) on a column's foot and top where the model's bottom or top is
    quiet: ρC_s for the horizontal motion, ρC_p for the vertical, from the impedance rule of the
    quiet boundary at the end block's edge on that side."""
    quiet = engine.settings.quiet
    if quiet is None:
        return
    edges = engine.edges
    for side, i in (("bottom", 0), ("top", len(order) - 1)):
        if side not in quiet.sides:
            continue
        on = np.flatnonzero(edges.on((side,)) & (edges.block == order[i]))
        if not len(on):
            continue
        zp, zs = boundary_impedance(engine, quiet, edges.block[on], edges.normal[on], quiet.sides)
        length = np.hypot(*(edges.p1[on] - edges.p0[on]).T)
        width = length.sum()
        elem[i, K.FF_CX] = float(length @ zs) / width
        elem[i, K.FF_CY] = float(length @ zp) / width


def free_field_columns(engine, ff: FreeField) -> tuple[np.ndarray, np.ndarray]:
    """(edges (F, 9), elements (E, ``K.N_FF_COLUMNS``)) of every free-field side for the kernel
    :func:`rockmass.solver._kernels.free_field_step`; the degrees of freedom of the present stage
    (``engine.mode``) decide which elements are driven."""
    edge_rows, elem_rows = [], []
    first = 0
    for side in ff.sides:
        edges, elem = _column(engine, ff, side, first)
        edge_rows.append(edges)
        elem_rows.append(elem)
        first += len(elem)
    return (np.ascontiguousarray(np.vstack(edge_rows)),
            np.ascontiguousarray(np.vstack(elem_rows)))


def set_free_field(engine, ff: FreeField | None) -> None:
    """Set up the free-field columns of a stage at rest (``ff`` None: none, as in static stages)."""
    if ff is None:
        engine.ff_edges = np.zeros((0, 9))
        engine.ff_elem = np.zeros((0, K.N_FF_COLUMNS))
    else:
        engine.ff_edges, engine.ff_elem = free_field_columns(engine, ff)
    engine.ff_state = np.zeros((len(engine.ff_elem), 4))
