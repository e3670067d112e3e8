"""Choose blocks and domain edges: sides of the domain, regions, boxes, explicit lists.

A block is on a side when one of its edges lies on the domain outline and that edge's outward
normal points to the side (left: n_x < −cos 45°, right: n_x > cos 45°, bottom / top likewise in y),
which works for any domain polygon, not only rectangles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .settings import SIDES

__all__ = ["DomainEdges", "domain_edges", "select_blocks", "block_at_point",
           "require_point_in_domain"]

_SIDE_COS = np.cos(np.pi / 4)


@dataclass(frozen=True)
class DomainEdges:
    """Block edges on the domain outline: ``block``, end points ``p0``, ``p1`` (m), outward unit
    normal ``normal`` and ``side`` (index into :data:`SIDES`, -1 if the normal is diagonal)."""

    block: np.ndarray
    p0: np.ndarray
    p1: np.ndarray
    normal: np.ndarray
    side: np.ndarray

    def on(self, sides) -> np.ndarray:
        wanted = [SIDES.index(s) for s in sides]
        return np.isin(self.side, wanted)


def domain_edges(model, tol_m: float) -> DomainEdges:
    """Edges of blocks that lie on the domain outline (both ends within ``tol_m`` of it)."""
    import shapely

    ring = shapely.LinearRing(model.domain_xy_m)
    candidates = np.unique(model.contact_blocks[model.contact_blocks[:, 1] < 0, 0])
    blocks, p0, p1 = [], [], []
    for b in candidates:
        poly = model.polygon(int(b))
        blocks.append(np.full(len(poly), b))
        p0.append(poly)
        p1.append(np.roll(poly, -1, axis=0))
    if not blocks:
        empty = np.empty((0, 2))
        return DomainEdges(np.empty(0, np.int64), empty, empty, empty, np.empty(0, np.int64))
    block = np.concatenate(blocks)
    p0 = np.concatenate(p0)
    p1 = np.concatenate(p1)
    mid = 0.5 * (p0 + p1)
    d = np.maximum.reduce([shapely.distance(shapely.points(p0), ring),
                           shapely.distance(shapely.points(p1), ring),
                           shapely.distance(shapely.points(mid), ring)])
    keep = d <= tol_m
    block, p0, p1 = block[keep], p0[keep], p1[keep]
    e = p1 - p0
    normal = np.column_stack([e[:, 1], -e[:, 0]]) / np.hypot(e[:, 0], e[:, 1])[:, None]
    side = np.full(len(block), -1, np.int64)
    side[normal[:, 0] < -_SIDE_COS] = SIDES.index("left")
    side[normal[:, 0] > _SIDE_COS] = SIDES.index("right")
    side[normal[:, 1] < -_SIDE_COS] = SIDES.index("bottom")
    side[normal[:, 1] > _SIDE_COS] = SIDES.index("top")
    return DomainEdges(block.astype(np.int64), p0, p1, normal, side)


def select_blocks(model, where: str, edges: DomainEdges, parent=None) -> np.ndarray:
    """Indices of the blocks chosen by a selector string (see :class:`~rockmass.solver.Fix`).
    ``parent``: for a model whose deformable blocks were zoned, the original block of each piece
    (``blocks:i`` then names original blocks and selects all their pieces)."""
    where = where.strip()
    if where in SIDES:
        return np.unique(edges.block[edges.on([where])])
    kind, _, arg = where.partition(":")
    try:
        if kind == "region":
            return np.flatnonzero(model.region == int(arg))
        if kind == "box":
            x0, y0, x1, y1 = (float(v) for v in arg.split(","))
            c = model.centroid_xy_m
            return np.flatnonzero((c[:, 0] >= x0) & (c[:, 0] <= x1) & (c[:, 1] >= y0) & (c[:, 1] <= y1))
        if kind == "blocks":
            ids = np.array([int(v) for v in arg.split(",") if v.strip()], np.int64)
            n = model.n_blocks if parent is None else int(parent.max()) + 1
            if ((ids < 0) | (ids >= n)).any():
                raise ValueError(f"block indices must be in [0, {n}), got {where!r}")
            return np.unique(ids) if parent is None else np.flatnonzero(np.isin(parent, ids))
    except ValueError as exc:
        raise ValueError(f"selector {where!r}: {exc}") from exc
    raise ValueError(f"selector {where!r}: expected one of {SIDES}, 'region:K', 'box:x0,y0,x1,y1' "
                     "or 'blocks:i,j,...'")


def block_at_point(model, xy) -> int:
    """The block containing the point (the nearest block if none contains it)."""
    import shapely

    polys = model.to_shapely()
    point = shapely.Point(float(xy[0]), float(xy[1]))
    inside = np.flatnonzero(shapely.contains(polys, point))
    if len(inside):
        return int(inside[0])
    return int(np.argmin(shapely.distance(polys, point)))


def require_point_in_domain(model, name: str, xy) -> None:
    """A monitor's point must lie in the model's domain: a point far outside would silently
    follow the nearest block (:func:`block_at_point`). Raises ValueError naming the monitor, the
    distance outside and the domain's extent."""
    import shapely

    domain = shapely.Polygon(model.domain_xy_m)
    point = shapely.Point(float(xy[0]), float(xy[1]))
    if not domain.covers(point):
        lo, hi = model.domain_xy_m.min(axis=0), model.domain_xy_m.max(axis=0)
        raise ValueError(f"monitor {name!r}: point_xy_m ({xy[0]:g}, {xy[1]:g}) lies "
                         f"{domain.exterior.distance(point):.3g} m outside the model domain "
                         f"(x {lo[0]:g}..{hi[0]:g}, y {lo[1]:g}..{hi[1]:g} m)")
