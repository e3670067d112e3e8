"""The quality report of a block model: what the builder changed, what it made, and the tolerances.

:func:`rockmass.blockgen.build` lists every change it makes (nothing is moved silently) and measures
the result; :class:`BlockQuality` holds that report as typed fields, and
:meth:`BlockQuality.to_dict` gives the JSON form written in ``blocks.json`` (key order and values as
the builder records them; the steps it did not run are left out: ``convex_rounds`` and
``concave_blocks_left`` without the convex decomposition, ``cracks`` without potential cracks,
``edges_snapped`` without short-edge snapping).
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass, fields

from .tolerances import Tolerances

__all__ = ["BlockQuality"]


@dataclass(frozen=True)
class BlockQuality:
    """The quality report of a :class:`~rockmass.blockgen.BlockModel` (JSON-ready values).

    Attributes
    ----------
    dangling : dict
        The dangling-end rule (``rule``) and its counts and lengths.
    slivers_merged, convex_splits : tuple of dict
        Each sliver merge and each concave block cut into convex pieces.
    snapped_cuts, convex_failures : int
        Convex-decomposition cuts snapped to a vertex, and cuts that could not be made.
    nodes_merged : dict
        Nodes joined by an edge shorter than ``snap_m`` (``rule``, ``count``).
    n_blocks, n_contacts : int
    n_blocks_by_region, n_contacts_by_kind : dict of str to int
    area_m2, aspect_ratio : dict of str to float
        Summary statistics over the blocks (min, median, max, mean; median, max).
    smallest_edge_m : float
    tiny_edges : dict
        Edges shorter than ``min_edge_m`` that remain (count, rule, blocks).
    area_balance : dict
        Domain, block, excavated and rock areas (m²) and the relative error.
    n_traces_used : int
        Traces that cut the domain.
    tolerances : Tolerances
        The tolerances the model was built with (:mod:`rockmass.blockgen.tolerances`).
    convex_rounds, concave_blocks_left : int or None
        Rounds of the convex decomposition and blocks still concave; None when it did not run.
    cracks : dict or None
        The potential-crack subdivision; None without one.
    edges_snapped : dict or None
        Short edges collapsed (:mod:`rockmass.blockgen.snapping`); None when snapping was off.
    """

    dangling: dict
    slivers_merged: tuple
    convex_splits: tuple
    snapped_cuts: int
    convex_failures: int
    nodes_merged: dict
    n_blocks: int
    n_blocks_by_region: dict
    n_contacts: int
    n_contacts_by_kind: dict
    area_m2: dict
    aspect_ratio: dict
    smallest_edge_m: float
    tiny_edges: dict
    area_balance: dict
    n_traces_used: int
    tolerances: Tolerances
    convex_rounds: int | None = None
    concave_blocks_left: int | None = None
    cracks: dict | None = None
    edges_snapped: dict | None = None

    def __post_init__(self):
        object.__setattr__(self, "slivers_merged", tuple(self.slivers_merged))
        object.__setattr__(self, "convex_splits", tuple(self.convex_splits))
        if isinstance(self.tolerances, Mapping):
            object.__setattr__(self, "tolerances", Tolerances(**self.tolerances))

    # the JSON key order: the builder's steps, then the measures of the result
    _STEPS = ("dangling", "slivers_merged", "convex_splits", "snapped_cuts", "convex_failures",
              "nodes_merged", "convex_rounds", "concave_blocks_left", "cracks", "edges_snapped")

    def to_dict(self) -> dict:
        """The report as plain JSON types (a new structure), in the builder's order; steps not run
        are left out."""
        out = {}
        for name in self._STEPS + tuple(f.name for f in fields(self) if f.name not in self._STEPS):
            value = getattr(self, name)
            if value is None:
                continue
            if isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, Tolerances):
                value = value.to_dict()
            out[name] = value
        return copy.deepcopy(out)

    @classmethod
    def from_dict(cls, data: Mapping) -> BlockQuality:
        """Read :meth:`to_dict` output (a ``blocks.json`` ``quality``).

        Raises
        ------
        TypeError
            A required entry is missing, or an entry is not one of the report's (named).
        """
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise TypeError(f"quality: unknown entries {unknown}")
        return cls(**data)
