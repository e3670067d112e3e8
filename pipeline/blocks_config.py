"""``[blocks]``: the block-model section (:func:`rockmass.blockgen.build`), strict and range-checked.

Example::

    [blocks]
    seed = 0
    dangling = "glued"            # or "joint", "drop"
    [blocks.domain]
    width_m = 1.22
    height_m = 0.61
    [[blocks.sets]]
    angle_deg = 45
    spacing_m = 0.05
    [[blocks.excavations]]
    shape = "circle"
    name = "tunnel"
    center_xy_m = [0.61, 0.305]
    radius_m = 0.076

``[[blocks.sets]]`` tables are :class:`rockmass.blockgen.JointSet` itself (fields, ranges, rules and
descriptions declared there once).

``[blocks.cracks]`` (``size_m``, ``pattern`` = "voronoi" or "triangular", ...) subdivides intact
blocks by potential cracks: the table is :class:`rockmass.blockgen.Cracks` itself.

``[blocks.dfn_section]`` (``section``, ``realization``) takes the traces of a ``[[dfn.sections]]``
plane of the same file's ``[dfn]`` section (:class:`DfnSectionConfig`).

``[blocks.two_sets]`` (``alpha_deg``, ``theta_deg``, ``spacing_m``) is the seed-000 parametrisation:
set 1 at α from the horizontal, set 2 at α + θ. The section is the ``blocks`` field of
:class:`rockmass.config.RockmassConfig` (what ``rockmass blocks`` loads, so one file can hold several
stages); :class:`BlocksDocument` is a top level with the ``[blocks]`` section only.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from .blockgen.cracks import Cracks
from .blockgen.excavations import ExcavationSpec
from .blockgen.joints import JointSet
from .strict import ConfigFile, StrictModel, config_file, field_problem

__all__ = ["BlocksConfig", "BlocksDocument", "DomainSection", "JointSetConfig", "TwoSetsConfig",
           "DfnSectionConfig"]

Coord = Annotated[float, Field(ge=-1e7, le=1e7)]
Point = Annotated[tuple[Coord, Coord], Field(strict=False)]
Length = Annotated[float, Field(gt=0, le=1e6)]
Name = Annotated[str, Field(min_length=1, max_length=64)]


class DomainSection(StrictModel):
    """``[blocks.domain]``: a ``width_m`` × ``height_m`` rectangle with its lower-left corner at
    ``origin_xy_m`` (default (0, 0)), or any simple polygon ``polygon_xy_m`` (3 to 10⁴ vertices)."""

    width_m: Annotated[Length | None, Field(description="width of the rectangular domain")] = None
    height_m: Annotated[Length | None, Field(description="height of the rectangular domain")] = None
    origin_xy_m: Annotated[Point, Field(
        description="lower-left corner of the rectangle")] = (0.0, 0.0)
    polygon_xy_m: Annotated[list[Point] | None, Field(
        min_length=3, max_length=10000,
        description="outline of a polygonal domain (instead of the rectangle)")] = None

    @model_validator(mode="after")
    def _one_form(self):
        rect = self.width_m is not None or self.height_m is not None
        if rect and self.polygon_xy_m is not None:
            raise field_problem(self, "polygon_xy_m", "give either width_m and height_m or "
                                "polygon_xy_m, not both", self.polygon_xy_m)
        if not rect and self.polygon_xy_m is None:
            raise field_problem(self, "width_m", "give width_m and height_m (or polygon_xy_m)", None)
        if rect and (self.width_m is None or self.height_m is None):
            missing = "height_m" if self.height_m is None else "width_m"
            raise field_problem(self, missing, "required with the other side of the rectangle", None)
        return self

    def xy_m(self) -> list[tuple[float, float]]:
        if self.polygon_xy_m is not None:
            return [tuple(p) for p in self.polygon_xy_m]
        x, y = self.origin_xy_m
        return [(x, y), (x + self.width_m, y), (x + self.width_m, y + self.height_m),
                (x, y + self.height_m)]


#: ``[[blocks.sets]]`` is :class:`rockmass.blockgen.JointSet` itself: its fields, ranges, rules and
#: descriptions are declared there once.
JointSetConfig = JointSet


class TwoSetsConfig(StrictModel):
    """``[blocks.two_sets]``: the two sets of Jiang et al. (docs/sources.md §1), set 1 at
    ``alpha_deg`` from the horizontal and set 2 at ``alpha_deg + theta_deg`` (0 < θ <= 90), spacings
    ``spacing_m = [s1, s2]``."""

    alpha_deg: Annotated[float, Field(ge=0, lt=180, description="angle α of set 1 from the horizontal")]
    theta_deg: Annotated[float, Field(gt=0, le=90, description="angle θ from set 1 to set 2")]
    spacing_m: Annotated[tuple[Length, Length], Field(strict=False, description="spacings [set 1, set 2]")]
    trace_length_m: Annotated[Length | None, Field(
        description="joint length along a line, both sets; none: persistent")] = None
    gap_length_m: Annotated[Length | None, Field(
        description="rock-bridge length between the joints of a line, both sets")] = None

    def to_joint_sets(self):
        from .blockgen import JointSet

        extra = {"trace_length_m": self.trace_length_m, "gap_length_m": self.gap_length_m}
        return [JointSet(self.alpha_deg, self.spacing_m[0], name="set 1 (alpha)", **extra),
                JointSet(self.alpha_deg + self.theta_deg, self.spacing_m[1],
                         name="set 2 (alpha + theta)", **extra)]


class DfnSectionConfig(StrictModel):
    """``[blocks.dfn_section]``: cut the blocks by the traces of a DFN plane section.

    The traces are generated on one ``[[dfn.sections]]`` plane of the same file's ``[dfn]`` section
    (its sets, seed and ``max_fractures``), directly on the plane
    (:func:`rockmass.dfn.section.generate_section`: the same Poisson disk model and statistics as
    the volume realization, drawn on the plane), realization ``realization``. The block coordinates
    are the plane frame (u, v) of that section; without ``[blocks.domain]`` the domain is the
    section's ``window_uv_m``.

    Parameters
    ----------
    section : str
        ``name`` of a ``[[dfn.sections]]`` entry.
    realization : int, default 0
        Realization index (0 <= realization < dfn.realizations).
    """

    section: Name
    realization: int = Field(0, ge=0, le=10000)


class BlocksConfig(StrictModel):
    """``[blocks]``: domain, joint sets and/or traces, excavation stages (in removal order).

    Parameters
    ----------
    domain : DomainSection, optional
        Required unless ``dfn_section`` gives the domain (its window).
    sets : list of JointSet, default []
        ``[[blocks.sets]]``: joint sets (:class:`rockmass.blockgen.JointSet`), at most 32.
    two_sets : TwoSetsConfig, optional
        Appended after ``sets``.
    traces : str, optional
        Trace file (GeoJSON / CSV, :func:`rockmass.dfn.read_traces`), relative to the config file.
    dfn_section : DfnSectionConfig, optional
        Traces of a ``[[dfn.sections]]`` plane of this file's ``[dfn]`` section (not with ``traces``).
    excavations : list, default []
        Stages (``shape`` = circle, horseshoe, arched_cavern, rectangle, polygon), unique names.
    dangling : {"glued", "joint", "drop"}, default "glued"
        Joint or trace ends in intact rock: extended to the next line as a glued contact or as a
        joint, or dropped.
    seed : int, default 0
        Root seed of the random joint offsets, spacings and cracks (0 <= seed < 2**63).
    rounding_m, min_edge_m : float, optional
        Solver corner rounding d and minimum edge (defaults: 1 % of the median edge, 2d).
    merge_slivers, convex, snap_edges : bool, default true
        Merge slivers, split concave blocks, collapse edges shorter than the minimum edge.
    cracks : Cracks, optional
        ``[blocks.cracks]``: subdivide intact blocks by potential cracks (needs ``convex``).
    """

    domain: DomainSection | None = None
    sets: Annotated[list[JointSet], Field(max_length=32)] = Field(default_factory=list)
    two_sets: TwoSetsConfig | None = None
    traces: ConfigFile | None = None
    dfn_section: DfnSectionConfig | None = None
    excavations: Annotated[list[ExcavationSpec], Field(max_length=64)] = Field(default_factory=list)
    dangling: Literal["glued", "joint", "drop"] = "glued"
    seed: int = Field(0, ge=0, lt=2 ** 63)
    rounding_m: Length | None = None
    min_edge_m: Length | None = None
    merge_slivers: bool = True
    convex: bool = True
    snap_edges: bool = True
    cracks: Cracks | None = None

    @model_validator(mode="after")
    def _something_cuts(self):
        if self.domain is None and self.dfn_section is None:
            raise field_problem(self, "domain", "required: give [blocks.domain] (or take the window of "
                                "a DFN section with [blocks.dfn_section])", None)
        if self.traces is not None and self.dfn_section is not None:
            raise field_problem(self, "dfn_section", "give traces or dfn_section, not both",
                                self.dfn_section.section)
        if (not self.sets and self.two_sets is None and self.traces is None and not self.excavations
                and self.cracks is None and self.dfn_section is None):
            raise field_problem(self, "sets", "nothing cuts the domain: give sets, two_sets, traces "
                                "or excavations", [])
        names = [e.name for e in self.excavations]
        if len(set(names)) != len(names):
            raise field_problem(self, "excavations", f"stage names must be unique, got {names}", names)
        if self.cracks is not None and not self.convex:
            raise field_problem(self, "cracks", "potential cracks subdivide convex blocks: set "
                                "convex = true (or remove [blocks.cracks])", None)
        if self.cracks is not None and self.cracks.within_m is not None and not self.excavations:
            raise field_problem(self, "cracks", "within_m is measured from the excavations, but "
                                "there are none (remove within_m or add [[blocks.excavations]])",
                                self.cracks.within_m)
        return self

    def joint_sets(self):
        sets = list(self.sets)
        if self.two_sets is not None:
            sets += self.two_sets.to_joint_sets()
        return sets

    def traces_path(self, config_path) -> Path | None:
        return config_file(config_path, self.traces)


class BlocksDocument(StrictModel):
    """Top level of a ``rockmass blocks`` config: the ``[blocks]`` section only."""

    blocks: BlocksConfig
