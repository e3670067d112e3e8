"""Straight tunnels for 3D block models: a convex cross-section swept along a horizontal axis.

Frame (docs/design.md §3.2: x East, y North, z up). A tunnel of trend t (degrees clockwise from
North) has axis a = (sin t, cos t, 0); its cross-section is drawn in (u, v) with u = (cos t, −sin t, 0)
horizontal (to the right looking along the axis) and v = z up, the origin at ``centre_m``. The
section must be convex and counter-clockwise in (u, v) (a circle as a regular polygon, a horseshoe of
vertical walls under a circular roof, a rectangle); its edge k with outward normal (m_u, m_v) is the
wall plane n_k = m_u u + m_v v, n_k · x = n_k · (centre + p_k), p_k a vertex of the edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .blocks3d import Planes
from .excavations import CircleSpec, HorseshoeSpec, RectangleSpec

__all__ = ["Tunnel", "circle_section", "horseshoe_section", "rectangle_section"]


def circle_section(radius_m: float, n_sides: int = 24) -> np.ndarray:
    """A regular ``n_sides``-gon inscribed in the circle of ``radius_m`` about the origin,
    counter-clockwise: the outline of the 2D circular excavation (:class:`CircleSpec`)."""
    return CircleSpec(name="section", center_xy_m=(0.0, 0.0), radius_m=radius_m,
                      n_sides=n_sides).to_excavation().xy_m


def horseshoe_section(width_m: float, wall_height_m: float, n_arc: int = 12) -> np.ndarray:
    """Flat invert of ``width_m`` at v = 0, vertical walls of ``wall_height_m``, a semicircular roof
    of radius width/2 drawn with ``n_arc`` edges, counter-clockwise: the outline of the 2D horseshoe
    excavation (:class:`HorseshoeSpec`, whose ``n_sides`` is that of the full circle)."""
    return HorseshoeSpec(name="section", center_xy_m=(0.0, 0.0), span_m=width_m,
                         wall_height_m=wall_height_m, n_sides=2 * n_arc).to_excavation().xy_m


def rectangle_section(width_m: float, height_m: float) -> np.ndarray:
    """A ``width_m`` × ``height_m`` rectangle standing on the origin (the middle of its floor),
    counter-clockwise: the outline of the 2D rectangular excavation (:class:`RectangleSpec`)."""
    return RectangleSpec(name="section", center_xy_m=(0.0, height_m / 2), width_m=width_m,
                         height_m=height_m).to_excavation().xy_m


@dataclass(frozen=True)
class Tunnel:
    """A straight tunnel through the model: ``section_uv_m (k, 2)`` convex counter-clockwise,
    ``centre_m`` (3,) the section origin on the axis, ``trend_deg`` the axis azimuth."""

    section_uv_m: np.ndarray
    centre_m: tuple[float, float, float]
    trend_deg: float = 0.0

    def __post_init__(self):
        uv = np.asarray(self.section_uv_m, float)
        if uv.ndim != 2 or uv.shape[1] != 2 or len(uv) < 3:
            raise ValueError(f"section_uv_m must be (k >= 3, 2) vertices, got shape {uv.shape}")
        edge = np.roll(uv, -1, axis=0) - uv
        turn = edge[:, 0] * np.roll(edge, -1, axis=0)[:, 1] - edge[:, 1] * np.roll(edge, -1, axis=0)[:, 0]
        if (turn <= 0).any():
            raise ValueError("section_uv_m must be convex and counter-clockwise")
        object.__setattr__(self, "section_uv_m", uv)

    def frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(a, u, v): the axis and the section's right and up directions."""
        t = math.radians(self.trend_deg)
        return (np.array([math.sin(t), math.cos(t), 0.0]), np.array([math.cos(t), -math.sin(t), 0.0]),
                np.array([0.0, 0.0, 1.0]))

    @cached_property
    def halfspaces(self) -> tuple[np.ndarray, np.ndarray]:
        """Outward wall normals ``(k, 3)`` and offsets ``(k,)``: the tunnel is {x : n_k·x ≤ d_k}."""
        _, u, v = self.frame()
        uv = self.section_uv_m
        edge = np.roll(uv, -1, axis=0) - uv
        m = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / np.linalg.norm(edge, axis=1)[:, None]
        normal = m[:, :1] * u + m[:, 1:] * v
        points = np.asarray(self.centre_m, float) + uv[:, :1] * u + uv[:, 1:] * v
        return normal, np.einsum("ij,ij->i", normal, points)

    def wall_planes(self, label: int) -> Planes:
        """The wall planes as persistent cutting planes carrying ``label`` (negative)."""
        normal, offset = self.halfspaces
        k = len(offset)
        return Planes(normal, offset, np.full(k, label, np.int64), np.zeros((k, 3)), np.full(k, np.inf))

    def contains(self, points: np.ndarray, tol_m: float) -> bool:
        """Do all ``points`` lie inside the tunnel (within ``tol_m``)?"""
        normal, offset = self.halfspaces
        return bool((points @ normal.T <= offset + tol_m).all())

    def reaches(self, points: np.ndarray, tol_m: float) -> bool:
        """Can the convex hull of ``points`` reach into the tunnel? False when one wall plane has
        every point outside it (a separating plane); True otherwise (conservative)."""
        normal, offset = self.halfspaces
        return not (points @ normal.T >= offset - tol_m).all(axis=0).any()
