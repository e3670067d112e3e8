"""A 3D block model from its parameters: persistent joint sets and/or a DFN realization, tunnels,
keyblocks and block shapes (docs/blocks.md §§8–10).

The parameter types (:class:`JointSet3D`, :class:`TunnelSpec`, :class:`Blocks3DSettings`) are
declared once, with their ranges and descriptions, and serve both Python calls and the
``[blocks3d]`` config section (:func:`rockmass.dfn.specs.spec`). :func:`build3d` cuts the box, finds
the in-situ blocks, analyses the keyblocks around the tunnels and measures every block.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Literal, Optional

import numpy as np
from pydantic import Field, model_validator

from ..dfn.orientation import normal_from_dip
from ..dfn.specs import Float, Int, field_error, spec
from .block_shapes import BlockShapes, block_shapes
from .blocks3d import BlockSet3D, Planes, cut_box, disk_planes, persistent_set_planes
from .keyblocks import Keyblock, keyblocks
from .openings3d import Tunnel, circle_section, horseshoe_section, rectangle_section

__all__ = ["JointSet3D", "TunnelSpec", "Blocks3DSettings", "Model3D", "build3d"]

Coord = Annotated[Float, Field(ge=-1e7, le=1e7)]
Point3 = tuple[Coord, Coord, Coord]
Friction = Annotated[Float, Field(ge=0, lt=90)]
Cohesion = Annotated[Float, Field(ge=0, le=1e11)]
Length = Annotated[Float, Field(gt=0, le=1e5)]


@spec
class JointSet3D:
    """A persistent joint set: parallel planes of one orientation at a constant spacing."""

    dip_deg: Annotated[Float, Field(ge=0, le=90, description="dip of the planes")]
    dip_direction_deg: Annotated[Float, Field(ge=0, lt=360, description=(
        "dip direction, clockwise from North"))]
    spacing_m: Annotated[Length, Field(description="spacing normal to the planes")]
    origin_m: Annotated[Point3, Field(description="a point one plane passes through")] = (0.0, 0.0, 0.0)
    name: Annotated[str, Field(max_length=64, description="label in outputs")] = ""
    friction_deg: Annotated[Friction, Field(description="friction angle φ of the joints")] = 30.0
    cohesion_pa: Annotated[Cohesion, Field(description="cohesion c of the joints")] = 0.0


@spec
class TunnelSpec:
    """A straight tunnel along a horizontal axis: circle (``radius_m``), horseshoe (``width_m``,
    ``wall_height_m``) or rectangle (``width_m``, ``height_m``); the section's origin (the centre of
    a circle, the middle of the invert otherwise) lies at ``centre_m``."""

    shape: Annotated[Literal["circle", "horseshoe", "rectangle"], Field(description="cross-section")]
    centre_m: Annotated[Point3, Field(description="origin of the section on the axis")]
    trend_deg: Annotated[Float, Field(ge=0, lt=360, description="azimuth of the axis")] = 0.0
    name: Annotated[str, Field(max_length=64, description="label in outputs")] = "tunnel"
    radius_m: Annotated[Optional[Length], Field(description="circle radius")] = None
    width_m: Annotated[Optional[Length], Field(description="horseshoe or rectangle width")] = None
    wall_height_m: Annotated[Optional[Length], Field(description="horseshoe wall height")] = None
    height_m: Annotated[Optional[Length], Field(description="rectangle height")] = None
    n_sides: Annotated[Int, Field(ge=8, le=720, description=(
        "edges of a circle, or of a horseshoe's roof arc (half as many)"))] = 24

    @model_validator(mode="after")
    def _dimensions_of_the_shape(self):
        need = {"circle": ("radius_m",), "horseshoe": ("width_m", "wall_height_m"),
                "rectangle": ("width_m", "height_m")}[self.shape]
        for name in need:
            if getattr(self, name) is None:
                raise field_error(self, name, f"a {self.shape} tunnel needs {name}", None)
        return self

    def tunnel(self) -> Tunnel:
        """The :class:`~rockmass.blockgen.openings3d.Tunnel` this spec describes."""
        if self.shape == "circle":
            section = circle_section(self.radius_m, self.n_sides)
        elif self.shape == "horseshoe":
            section = horseshoe_section(self.width_m, self.wall_height_m, max(self.n_sides // 2, 4))
        else:
            section = rectangle_section(self.width_m, self.height_m)
        return Tunnel(section, centre_m=tuple(self.centre_m), trend_deg=self.trend_deg)


@spec
class Blocks3DSettings:
    """A box of rock cut by persistent joint sets and/or the disks of a DFN realization, around
    tunnels; strength and weight for the keyblock analysis."""

    box_min_m: Annotated[Point3, Field(description="lowest corner of the model box")]
    box_max_m: Annotated[Point3, Field(description="highest corner of the model box")]
    sets: Annotated[tuple[JointSet3D, ...], Field(max_length=20, description="persistent joint sets")] = ()
    tunnels: Annotated[tuple[TunnelSpec, ...], Field(max_length=20, description="tunnels")] = ()
    dfn_realization: Annotated[Optional[Int], Field(ge=0, description=(
        "cut by this realization of the [dfn] sets of the same file (none: no DFN)"))] = None
    dfn_friction_deg: Annotated[Friction, Field(description="friction angle of DFN fractures")] = 30.0
    dfn_cohesion_pa: Annotated[Cohesion, Field(description="cohesion of DFN fractures")] = 0.0
    density_kg_m3: Annotated[Float, Field(gt=0, le=1e5, description="rock density ρ")] = 2700.0
    gravity_m_s2: Annotated[Float, Field(gt=0, le=100, description="gravity g (acting along −z)")] = 9.81

    @model_validator(mode="after")
    def _box_has_volume(self):
        if not all(hi > lo for lo, hi in zip(self.box_min_m, self.box_max_m)):
            raise field_error(self, "box_max_m", f"must exceed box_min_m {list(self.box_min_m)} on "
                              f"every axis, got {list(self.box_max_m)}", self.box_max_m)
        return self


@dataclass(frozen=True)
class Model3D:
    """What :func:`build3d` returns: the cut ``blocks``, the ``keyblocks`` table, the ``shapes`` of
    the in-situ blocks and the fracture ``strength`` used (label → (φ°, c Pa))."""

    blocks: BlockSet3D
    keyblocks: tuple[Keyblock, ...]
    shapes: BlockShapes
    strength: dict


def build3d(settings: Blocks3DSettings, network=None) -> Model3D:
    """Cut, group, analyse and measure (docs/blocks.md §§8–10).

    ``network`` is the :class:`rockmass.dfn.DiskNetwork` to cut by (after the persistent sets);
    its fractures are labelled 0 .. n − 1 and the sets n, n + 1, …
    """
    box = np.array([settings.box_min_m, settings.box_max_m], float)
    planes: list[Planes] = []
    strength: dict[int, tuple[float, float]] = {}
    first_set = 0
    if network is not None:
        planes.append(disk_planes(network))
        first_set = len(network.radius_m)
        strength.update({i: (settings.dfn_friction_deg, settings.dfn_cohesion_pa) for i in range(first_set)})
    for k, joint_set in enumerate(settings.sets):
        normal = normal_from_dip(joint_set.dip_deg, joint_set.dip_direction_deg)
        planes.append(persistent_set_planes(box, normal, joint_set.spacing_m, joint_set.origin_m,
                                            label=first_set + k))
        strength[first_set + k] = (joint_set.friction_deg, joint_set.cohesion_pa)
    blocks = cut_box(box, *planes, tunnels=tuple(t.tunnel() for t in settings.tunnels))
    table = tuple(keyblocks(blocks, strength, settings.density_kg_m3, settings.gravity_m_s2))
    return Model3D(blocks, table, block_shapes(blocks), strength)
