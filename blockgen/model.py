"""The block model handed to the DEM: blocks and contacts as structures of arrays.

Blocks are convex polygons (counter-clockwise, open rings) stored as one vertex array with offsets
(block ``i`` owns ``xy_m[offsets[i]:offsets[i + 1]]``). Contacts join two adjacent blocks along their
shared boundary; a contact with the domain boundary has ``blocks[:, 1] == -1``. Each contact has a
``kind`` (index into :data:`CONTACT_KINDS`) and a ``source``: the joint-set index for ``joint``, the
trace index for ``trace``, the excavation stage (region) for ``excavation``, the set / trace index
extended for ``glued`` (``-2`` = :data:`SOURCE_CONVEX_CUT` for a convex-decomposition cut, ``-3`` =
:data:`SOURCE_CRACK` for a potential crack of the sub-block subdivision,
:mod:`rockmass.blockgen.cracks`), ``-1`` for ``domain``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from .quality import BlockQuality

__all__ = ["BlockModel", "CONTACT_KINDS", "KIND_JOINT", "KIND_TRACE", "KIND_GLUED",
           "KIND_EXCAVATION", "KIND_DOMAIN", "SOURCE_CONVEX_CUT", "SOURCE_CRACK",
           "polygon_properties"]

CONTACT_KINDS = ("joint", "trace", "glued", "excavation", "domain")
KIND_JOINT, KIND_TRACE, KIND_GLUED, KIND_EXCAVATION, KIND_DOMAIN = range(5)
SOURCE_CONVEX_CUT = -2
SOURCE_CRACK = -3


def polygon_properties(xy_m: np.ndarray, offsets: np.ndarray):
    """Area, centroid and second moments about the centroid of ragged CCW polygons.

    Returns
    -------
    area_m2 : (n,) ; centroid_xy_m : (n, 2) ; second_moment_m4 : (n, 3) with columns
    I_xx = ∫(y−ȳ)² dA, I_yy = ∫(x−x̄)² dA, I_xy = ∫(x−x̄)(y−ȳ) dA (shoelace forms, Bourke 1988).

    >>> a, c, i = polygon_properties(np.array([[0., 0], [2, 0], [2, 1], [0, 1]]), np.array([0, 4]))
    >>> a.tolist(), c.tolist(), np.round(i, 6).tolist()
    ([2.0], [[1.0, 0.5]], [[0.166667, 0.666667, 0.0]])
    """
    n = len(offsets) - 1
    block = np.repeat(np.arange(n), np.diff(offsets))
    nxt = np.arange(len(xy_m)) + 1
    nxt[offsets[1:] - 1] = offsets[:-1]
    # shift each polygon by its first vertex for accuracy far from the origin
    origin = xy_m[offsets[:-1]][block]
    p = xy_m - origin
    q = xy_m[nxt] - origin
    cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
    area = 0.5 * np.bincount(block, cross, n)
    cx = np.bincount(block, (p[:, 0] + q[:, 0]) * cross, n) / (6 * area)
    cy = np.bincount(block, (p[:, 1] + q[:, 1]) * cross, n) / (6 * area)
    ixx = np.bincount(block, (p[:, 1] ** 2 + p[:, 1] * q[:, 1] + q[:, 1] ** 2) * cross, n) / 12
    iyy = np.bincount(block, (p[:, 0] ** 2 + p[:, 0] * q[:, 0] + q[:, 0] ** 2) * cross, n) / 12
    ixy = np.bincount(block, (p[:, 0] * q[:, 1] + 2 * p[:, 0] * p[:, 1] + 2 * q[:, 0] * q[:, 1]
                              + q[:, 0] * p[:, 1]) * cross, n) / 24
    moments = np.column_stack([ixx - area * cy ** 2, iyy - area * cx ** 2, ixy - area * cx * cy])
    centroid = np.column_stack([cx, cy]) + xy_m[offsets[:-1]]
    return area, centroid, moments


def _frozen(a, dtype):
    a = np.array(a, dtype=dtype)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class BlockModel:
    """A 2D block model (unit thickness), structure of arrays.

    Attributes
    ----------
    xy_m : (n_vertices, 2) float64
        Block vertices, counter-clockwise per block, open rings.
    offsets : (n_blocks + 1,) int64
        Block ``i`` has vertices ``xy_m[offsets[i]:offsets[i+1]]``.
    region : (n_blocks,) int64
        0 for the rock mass that stays, k >= 1 for the blocks of excavation stage k.
    region_names : tuple of str
        ``region_names[k]``: ``"rock"`` then the excavation stage names in removal order.
    contact_blocks : (n_contacts, 2) int64
        The two blocks of each contact (second ``-1`` on the domain boundary).
    contact_length_m : (n_contacts,) float64
        Shared boundary length.
    contact_kind : (n_contacts,) int64
        Index into :data:`CONTACT_KINDS`.
    contact_source : (n_contacts,) int64
        Joint set / trace / stage index (see the module docstring).
    set_names : tuple of str
        Names of the joint sets (``contact_source`` of ``joint`` contacts indexes it).
    domain_xy_m : (k, 2) float64
        The domain outline.
    quality : BlockQuality or None
        The quality report (:class:`~rockmass.blockgen.quality.BlockQuality`): counts, areas,
        aspect ratios, smallest edge, every merge and convex split, the area balance and the
        tolerances used; ``quality.to_dict()`` is its JSON form. A mapping given here is read with
        ``BlockQuality.from_dict`` (an empty one is None). None for a model not made by the builder.
    area_m2, centroid_xy_m, second_moment_m4
        Derived per block (see :func:`polygon_properties`).
    """

    xy_m: np.ndarray
    offsets: np.ndarray
    region: np.ndarray
    region_names: tuple
    contact_blocks: np.ndarray
    contact_length_m: np.ndarray
    contact_kind: np.ndarray
    contact_source: np.ndarray
    set_names: tuple
    domain_xy_m: np.ndarray
    quality: BlockQuality | None = None
    area_m2: np.ndarray = field(init=False)
    centroid_xy_m: np.ndarray = field(init=False)
    second_moment_m4: np.ndarray = field(init=False)

    def __post_init__(self):
        for name, dtype in (("xy_m", np.float64), ("offsets", np.int64), ("region", np.int64),
                            ("contact_blocks", np.int64), ("contact_length_m", np.float64),
                            ("contact_kind", np.int64), ("contact_source", np.int64),
                            ("domain_xy_m", np.float64)):
            object.__setattr__(self, name, _frozen(getattr(self, name), dtype))
        object.__setattr__(self, "region_names", tuple(self.region_names))
        object.__setattr__(self, "set_names", tuple(self.set_names))
        if isinstance(self.quality, Mapping):
            object.__setattr__(self, "quality",
                               BlockQuality.from_dict(self.quality) if self.quality else None)
        if self.xy_m.ndim != 2 or self.xy_m.shape[1] != 2:
            raise ValueError(f"xy_m must have shape (n_vertices, 2), got {self.xy_m.shape}")
        if self.offsets[0] != 0 or self.offsets[-1] != len(self.xy_m) or (np.diff(self.offsets) < 3).any():
            raise ValueError("offsets must start at 0, end at n_vertices, with >= 3 vertices a block")
        if len(self.region) != self.n_blocks:
            raise ValueError(f"region must have n_blocks = {self.n_blocks} entries")
        if self.contact_blocks.ndim != 2 or self.contact_blocks.shape[1:] != (2,):
            raise ValueError("contact_blocks must have shape (n_contacts, 2)")
        area, centroid, moments = polygon_properties(self.xy_m, self.offsets)
        object.__setattr__(self, "area_m2", _frozen(area, np.float64))
        object.__setattr__(self, "centroid_xy_m", _frozen(centroid, np.float64))
        object.__setattr__(self, "second_moment_m4", _frozen(moments, np.float64))

    @property
    def n_blocks(self) -> int:
        return len(self.offsets) - 1

    @property
    def n_contacts(self) -> int:
        return len(self.contact_length_m)

    def polygon(self, i: int) -> np.ndarray:
        """Vertices of block ``i`` ((k, 2), counter-clockwise)."""
        return self.xy_m[self.offsets[i]:self.offsets[i + 1]]

    def to_shapely(self) -> np.ndarray:
        """The blocks as an array of shapely Polygons."""
        import shapely

        return np.array([shapely.Polygon(self.polygon(i)) for i in range(self.n_blocks)],
                        dtype=object)

    def excavated(self, stage: int | None = None) -> np.ndarray:
        """Mask of blocks removed by excavation stage ``stage`` (any stage when None)."""
        return self.region > 0 if stage is None else self.region == stage

    def __repr__(self) -> str:
        return (f"BlockModel({self.n_blocks} blocks, {self.n_contacts} contacts, regions "
                f"{list(self.region_names)})")
