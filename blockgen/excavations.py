"""Excavation outlines: circle, horseshoe, arched cavern, rectangle and any polygon, as named stages.

Each constructor returns an :class:`Excavation` (a stage name and a counter-clockwise outline in
metres). Curved parts are polygons; the approximation is stated so that tests can check it.

The parameters of each shape are declared once, on a spec type (:class:`CircleSpec`,
:class:`HorseshoeSpec`, :class:`ArchedCavernSpec`, :class:`RectangleSpec`, :class:`PolygonSpec`,
each with its ``shape`` tag): the constructors validate through it, and a ``[[blocks.excavations]]``
table is one of them (``spec.to_excavation()`` gives the outline).

Circle approximation
--------------------
A circle of radius r is the regular n-gon *inscribed* in it (vertices on the circle), n = ``n_sides``
(default 36, one side per 10°). Its perimeter is 2 n r sin(π/n), short of 2πr by the relative error
1 − (n/π) sin(π/n) ≈ π²/(6n²) (0.127 % for n = 36); its area is ½ n r² sin(2π/n). Arcs of the
horseshoe and the arched cavern use the same rule with one side per ``360/n_sides`` degrees of arc.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from ..dfn.polygon import signed_area
from ..dfn.specs import Float, Int, field_error, spec

__all__ = ["Excavation", "circle", "horseshoe", "arched_cavern", "rectangle", "polygon_excavation",
           "DEFAULT_CIRCLE_SIDES", "circle_perimeter_m", "CircleSpec", "HorseshoeSpec",
           "ArchedCavernSpec", "RectangleSpec", "PolygonSpec", "ExcavationSpec"]

DEFAULT_CIRCLE_SIDES = 36

_Coord = Annotated[Float, Field(ge=-1e7, le=1e7)]
_Point = Annotated[tuple[_Coord, _Coord], Field(strict=False)]
_Length = Annotated[Float, Field(gt=0, le=1e6)]
_StageName = Annotated[str, Field(strict=True, min_length=1, max_length=64, description=(
    "excavation stage name, unique; stages are removed in the order of the tables"))]
_ArcSides = Annotated[Int, Field(ge=8, le=4096, description="sides of the polygon that stands for the arcs")]


@dataclass(frozen=True)
class Excavation:
    """One excavation stage: ``name`` and its outline ``xy_m`` ((k, 2) float64, counter-clockwise,
    open ring). Stages are removed by the solver in the order given to :func:`build`."""

    name: str
    xy_m: np.ndarray

    def __post_init__(self):
        xy = _as_ring(self.xy_m, f"excavation {self.name!r}.xy_m")
        object.__setattr__(self, "xy_m", xy)

    def polygon(self):
        import shapely

        return shapely.Polygon(self.xy_m)


def _as_ring(xy, name: str) -> np.ndarray:
    try:
        xy = np.array(xy, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an (k, 2) array of numbers") from exc
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"{name} must have shape (k, 2), got {xy.shape}")
    if not np.isfinite(xy).all():
        raise ValueError(f"{name} has non-finite coordinates")
    if len(xy) > 1 and np.array_equal(xy[0], xy[-1]):
        xy = xy[:-1]
    if len(xy) < 3:
        raise ValueError(f"{name} needs at least 3 distinct vertices, got {len(xy)}")
    import shapely

    poly = shapely.Polygon(xy)
    if not poly.is_valid or poly.area <= 0:
        raise ValueError(f"{name} is a degenerate or self-intersecting polygon "
                         f"({shapely.is_valid_reason(poly)}, area {poly.area:g})")
    if signed_area(xy) < 0:
        xy = xy[::-1].copy()
    xy.setflags(write=False)
    return xy


def _arc(cx, cy, r, a0, a1, n_sides):
    """Points on an arc from angle a0 to a1 (radians, counter-clockwise): an even number k of
    equal inscribed chords, k >= (a1 - a0) / (2π / n_sides)."""
    k = max(2, int(math.ceil(abs(a1 - a0) / (2 * math.pi / n_sides) - 1e-9)))
    k += k % 2  # even: the crown of a symmetric arch is a vertex
    t = np.linspace(a0, a1, k + 1)
    return np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)])


def _shape(name: str):
    return Annotated[Literal[name], Field(description=f"excavation shape: \"{name}\"")]


@spec
class CircleSpec:
    """A circular opening (:func:`circle`)."""

    name: _StageName
    center_xy_m: Annotated[_Point, Field(description="centre")]
    radius_m: Annotated[_Length, Field(description="radius")]
    n_sides: _ArcSides = DEFAULT_CIRCLE_SIDES
    shape: _shape("circle") = "circle"

    def to_excavation(self) -> Excavation:
        r, n = self.radius_m, self.n_sides
        cx, cy = self.center_xy_m
        t = 2 * math.pi * np.arange(n) / n
        return Excavation(self.name, np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t)]))


@spec
class HorseshoeSpec:
    """A horseshoe opening (:func:`horseshoe`)."""

    name: _StageName
    center_xy_m: Annotated[_Point, Field(description="middle of the invert")]
    span_m: Annotated[_Length, Field(description="width")]
    wall_height_m: Annotated[_Length, Field(
        description="height of the vertical walls below the semicircular roof")]
    n_sides: _ArcSides = DEFAULT_CIRCLE_SIDES
    shape: _shape("horseshoe") = "horseshoe"

    def to_excavation(self) -> Excavation:
        cx, y0 = self.center_xy_m
        r = self.span_m / 2
        roof = _arc(cx, y0 + self.wall_height_m, r, 0.0, math.pi, self.n_sides)
        return Excavation(self.name, np.vstack([[[cx - r, y0], [cx + r, y0]], roof]))


@spec
class ArchedCavernSpec:
    """An arched cavern (:func:`arched_cavern`)."""

    name: _StageName
    center_xy_m: Annotated[_Point, Field(description="middle of the floor")]
    span_m: Annotated[_Length, Field(description="width")]
    wall_height_m: Annotated[_Length, Field(description="height of the vertical walls")]
    arch_rise_m: Annotated[_Length, Field(description="rise of the roof arch above the walls, <= span_m / 2")]
    n_sides: _ArcSides = DEFAULT_CIRCLE_SIDES
    shape: _shape("arched_cavern") = "arched_cavern"

    @model_validator(mode="after")
    def _rise(self) -> ArchedCavernSpec:
        if self.arch_rise_m > self.span_m / 2:
            raise field_error(self, "arch_rise_m", f"must be <= span_m / 2 ({self.span_m / 2:g}), "
                              f"got {self.arch_rise_m:g}", self.arch_rise_m)
        return self

    def to_excavation(self) -> Excavation:
        s, h, f = self.span_m, self.wall_height_m, self.arch_rise_m
        cx, y0 = self.center_xy_m
        radius = (s * s / 4 + f * f) / (2 * f)
        cy = y0 + h + f - radius
        half = math.asin((s / 2) / radius)
        roof = _arc(cx, cy, radius, math.pi / 2 - half, math.pi / 2 + half, self.n_sides)
        xy = np.vstack([[[cx - s / 2, y0], [cx + s / 2, y0], [cx + s / 2, y0 + h]], roof[1:-1],
                        [[cx - s / 2, y0 + h]]])
        return Excavation(self.name, xy)


@spec
class RectangleSpec:
    """A rectangular opening (:func:`rectangle`)."""

    name: _StageName
    center_xy_m: Annotated[_Point, Field(description="centre")]
    width_m: Annotated[_Length, Field(description="width")]
    height_m: Annotated[_Length, Field(description="height")]
    shape: _shape("rectangle") = "rectangle"

    def to_excavation(self) -> Excavation:
        w, h = self.width_m, self.height_m
        cx, cy = self.center_xy_m
        return Excavation(self.name, np.array([[cx - w / 2, cy - h / 2], [cx + w / 2, cy - h / 2],
                                               [cx + w / 2, cy + h / 2], [cx - w / 2, cy + h / 2]]))


@spec
class PolygonSpec:
    """Any simple polygon (:func:`polygon_excavation`)."""

    name: _StageName
    xy_m: Annotated[tuple[_Point, ...], Field(strict=False, min_length=3, max_length=10000,
                                              description="outline vertices")]
    shape: _shape("polygon") = "polygon"

    def to_excavation(self) -> Excavation:
        return Excavation(self.name, self.xy_m)


#: one ``[[blocks.excavations]]`` table, told apart by ``shape``
ExcavationSpec = Annotated[CircleSpec | HorseshoeSpec | ArchedCavernSpec | RectangleSpec | PolygonSpec,
                           Field(discriminator="shape")]


def circle_perimeter_m(radius_m: float, n_sides: int = DEFAULT_CIRCLE_SIDES) -> float:
    """Perimeter 2 n r sin(π/n) of the inscribed n-gon that stands for a circle.

    >>> round(circle_perimeter_m(1.0, 36) / (2 * math.pi), 5)
    0.99873
    """
    return 2.0 * n_sides * radius_m * math.sin(math.pi / n_sides)


def circle(center_xy_m, radius_m, name="tunnel", n_sides=DEFAULT_CIRCLE_SIDES) -> Excavation:
    """Circular opening: the inscribed regular ``n_sides``-gon (see the module Notes).

    >>> e = circle((0, 0), 1.0, n_sides=8)
    >>> e.xy_m.shape
    (8, 2)
    """
    return CircleSpec(name=name, center_xy_m=center_xy_m, radius_m=radius_m, n_sides=n_sides).to_excavation()


def horseshoe(center_xy_m, span_m, wall_height_m, name="tunnel",
              n_sides=DEFAULT_CIRCLE_SIDES) -> Excavation:
    """Horseshoe opening: flat invert of width ``span_m`` at ``center_xy_m[1]``, vertical walls of
    height ``wall_height_m`` and a semicircular roof of radius span/2.

    >>> horseshoe((0, 0), 2.0, 1.0, n_sides=8).xy_m.shape
    (7, 2)
    """
    return HorseshoeSpec(name=name, center_xy_m=center_xy_m, span_m=span_m, wall_height_m=wall_height_m,
                         n_sides=n_sides).to_excavation()


def arched_cavern(center_xy_m, span_m, wall_height_m, arch_rise_m, name="cavern",
                  n_sides=DEFAULT_CIRCLE_SIDES) -> Excavation:
    """Arched cavern: floor of width ``span_m`` at ``center_xy_m[1]``, vertical walls of height
    ``wall_height_m``, and a circular arch of rise ``arch_rise_m`` (<= span/2) over the span; the
    arch radius is R = (s²/4 + f²) / (2f).

    >>> e = arched_cavern((0, 0), 20.0, 10.0, 5.0)
    >>> round(float(e.xy_m[:, 1].max()), 6)
    15.0
    """
    return ArchedCavernSpec(name=name, center_xy_m=center_xy_m, span_m=span_m, wall_height_m=wall_height_m,
                            arch_rise_m=arch_rise_m, n_sides=n_sides).to_excavation()


def rectangle(center_xy_m, width_m, height_m, name="excavation") -> Excavation:
    """Rectangular opening centred on ``center_xy_m``.

    >>> rectangle((0, 0), 2, 1).polygon().area
    2.0
    """
    return RectangleSpec(name=name, center_xy_m=center_xy_m, width_m=width_m,
                         height_m=height_m).to_excavation()


def polygon_excavation(xy_m, name="excavation") -> Excavation:
    """Any simple polygon (vertices in metres, either orientation)."""
    return Excavation(name, xy_m)
