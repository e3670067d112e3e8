"""The invariants every block model must satisfy, computed independently of the builder.

:func:`check_model` recomputes from the block polygons alone (with shapely): the area balance
against the domain, pairwise overlaps, that every interior edge is shared by exactly two blocks with
the same length, and convexity (a vertex is reflex when it turns clockwise by more than
``REFLEX_SIN`` and lies more than ``reflex_m`` = 8 noding-grid cells inside the chord of its
neighbours, :mod:`rockmass.blockgen.tolerances`). The builder's tests and the CLI use it; a model that fails is a bug.
"""

from __future__ import annotations

import numpy as np
import shapely

from .convex import reflex_vertices
from .tolerances import AREA_BALANCE_RTOL, REFLEX_SIN, model_tolerances

__all__ = ["check_model"]


def check_model(model) -> dict:
    """Invariants of ``model`` (a :class:`~rockmass.blockgen.BlockModel`).

    Returns
    -------
    dict
        ``area_balance_rel`` (|Σ area − domain area| / domain area), ``max_overlap_m2`` (largest
        pairwise intersection area), ``n_concave`` (blocks with a reflex vertex),
        ``max_contact_length_mismatch_m`` (|contact length − length of the two blocks' common
        boundary|, over interior contacts summed per block pair), and ``ok``.
    """
    polys = model.to_shapely()
    domain = shapely.Polygon(model.domain_xy_m)
    area_rel = abs(float(shapely.area(polys).sum()) - domain.area) / domain.area
    tree = shapely.STRtree(polys)
    i, j = tree.query(polys, predicate="intersects")
    sel = i < j
    i, j = i[sel], j[sel]
    overlap = shapely.area(shapely.intersection(polys[i], polys[j]))
    common = shapely.length(shapely.intersection(shapely.boundary(polys[i]), shapely.boundary(polys[j])))
    # contact lengths per block pair
    interior = model.contact_blocks[:, 1] >= 0
    a = model.contact_blocks[interior].min(axis=1)
    b = model.contact_blocks[interior].max(axis=1)
    pair_len = {}
    for p, q, length in zip(a.tolist(), b.tolist(), model.contact_length_m[interior].tolist()):
        pair_len[(p, q)] = pair_len.get((p, q), 0.0) + length
    mismatch = 0.0
    for p, q, c in zip(i.tolist(), j.tolist(), common.tolist()):
        mismatch = max(mismatch, abs(pair_len.pop((p, q), 0.0) - c))
    for length in pair_len.values():  # contacts between blocks that do not touch
        mismatch = max(mismatch, length)
    # reflex beyond round-off: the sine rule and the height above the noding grid's reach
    lo, hi = model.domain_xy_m.min(axis=0), model.domain_xy_m.max(axis=0)
    reflex_m = model_tolerances(float(np.hypot(*(hi - lo))), 1.0).reflex_m
    n_concave = sum(1 for k in range(model.n_blocks)
                    if len(reflex_vertices(model.polygon(k), REFLEX_SIN, reflex_m)))
    scale = float(np.sqrt(domain.area))
    ok = (area_rel <= AREA_BALANCE_RTOL and float(overlap.max(initial=0.0)) <= 1e-9 * domain.area
          and mismatch <= 1e-9 * scale and n_concave == 0)
    return {"area_balance_rel": area_rel, "max_overlap_m2": float(overlap.max(initial=0.0)),
            "n_concave": int(n_concave), "max_contact_length_mismatch_m": float(mismatch),
            "ok": bool(ok)}
