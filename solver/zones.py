"""Deformable blocks: triangular zones, their constitutive models and a zoned body's state.

A deformable block is meshed into constant-strain triangles whose corners are *nodes* (UDEC's
gridpoints) with lumped masses; the nodes move by the central-difference scheme of the rigid blocks
and the zones turn their motion into stress through a constitutive model: linear elastic,
elastic–perfectly-plastic Mohr–Coulomb with a tension cut-off and dilation, or generalised
Hoek–Brown (docs/dem.md §16). The kernels are :func:`rockmass.solver._kernels.zone_forces` and
:func:`~rockmass.solver._kernels.zone_nodes_step`.

Public names
------------
:class:`Elastic`, :class:`MohrCoulomb`, :class:`HoekBrown`
    The constitutive models (frozen, validated like every solver parameter; stresses compression
    positive, as the user gives them).
:func:`mesh_polygon`
    Nodes and triangles of a polygon (with holes) at a zone size.
:class:`Zones`
    A zoned body on its own: boundary conditions, initial stress, relaxation to equilibrium; the
    verification problems of docs/dem.md §16.7 run on it.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal, Optional, Union

import numpy as np
from pydantic import Field, model_validator

from ..dfn.specs import Float, field_error, spec

__all__ = ["Elastic", "MohrCoulomb", "HoekBrown", "ZoneModel", "mesh_polygon", "Zones",
           "material_table"]

Modulus = Annotated[Float, Field(gt=0, le=1e13)]
Strength = Annotated[Float, Field(ge=0, le=1e11)]
Angle = Annotated[Float, Field(ge=0, lt=90)]


@spec
class Elastic:
    """Linear elastic zones: bulk modulus K and shear modulus G (Pa)."""

    bulk_modulus_pa: Annotated[Modulus, Field(description="bulk modulus K")]
    shear_modulus_pa: Annotated[Modulus, Field(description="shear modulus G")]
    model: Annotated[Literal["elastic"], Field(description="zone model: \"elastic\"")] = "elastic"

    @classmethod
    def from_young(cls, young_pa: float, poisson: float, **kw) -> "Elastic":
        """K = E/(3(1 − 2ν)), G = E/(2(1 + ν))."""
        return cls(young_pa / (3 * (1 - 2 * poisson)), young_pa / (2 * (1 + poisson)), **kw)


@spec
class MohrCoulomb:
    """Elastic–perfectly-plastic Mohr–Coulomb zones with a tension cut-off and dilation
    (docs/dem.md §16.3). The tensile strength may not exceed the apex of the shear envelope,
    c/tan φ."""

    bulk_modulus_pa: Annotated[Modulus, Field(description="bulk modulus K")]
    shear_modulus_pa: Annotated[Modulus, Field(description="shear modulus G")]
    cohesion_pa: Annotated[Strength, Field(description="cohesion c")]
    friction_deg: Annotated[Angle, Field(description="friction angle φ")]
    dilation_deg: Annotated[Angle, Field(description="dilation angle ψ (≤ φ)")] = 0.0
    tension_pa: Annotated[Strength, Field(description=(
        "tensile strength σ_t (at most c/tan φ)"))] = 0.0
    model: Annotated[Literal["mohr_coulomb"], Field(
        description="zone model: \"mohr_coulomb\"")] = "mohr_coulomb"

    @model_validator(mode="after")
    def _consistent(self):
        if self.dilation_deg > self.friction_deg:
            raise field_error(self, "dilation_deg", f"must not exceed friction_deg "
                              f"({self.friction_deg}), got {self.dilation_deg}", self.dilation_deg)
        if self.friction_deg > 0:
            apex = self.cohesion_pa / math.tan(math.radians(self.friction_deg))
            if self.tension_pa > apex * (1 + 1e-12):
                raise field_error(self, "tension_pa", f"must not exceed c/tan φ = {apex:.6g} Pa "
                                  f"(the apex of the shear envelope), got {self.tension_pa}",
                                  self.tension_pa)
        return self


@spec
class HoekBrown:
    """Generalised Hoek–Brown zones, σ₁' = σ₃' + σ_ci (m_b σ₃'/σ_ci + s)^a, with m_b, s and a from
    GSI, m_i and the disturbance D (Hoek, Carranza-Torres & Corkum 2002; docs/dem.md §16.4), and a
    constant dilation angle."""

    bulk_modulus_pa: Annotated[Modulus, Field(description="bulk modulus K")]
    shear_modulus_pa: Annotated[Modulus, Field(description="shear modulus G")]
    sigma_ci_pa: Annotated[Float, Field(gt=0, le=1e11, description=(
        "uniaxial compressive strength of the intact rock σ_ci"))]
    gsi: Annotated[Float, Field(ge=5, le=100, description="geological strength index GSI")]
    mi: Annotated[Float, Field(gt=0, le=50, description="intact-rock constant m_i")]
    disturbance: Annotated[Float, Field(ge=0, le=1, description="disturbance factor D")] = 0.0
    dilation_deg: Annotated[Angle, Field(description="dilation angle ψ")] = 0.0
    model: Annotated[Literal["hoek_brown"], Field(
        description="zone model: \"hoek_brown\"")] = "hoek_brown"

    @property
    def mb(self) -> float:
        """m_b = m_i exp((GSI − 100)/(28 − 14D))."""
        return self.mi * math.exp((self.gsi - 100) / (28 - 14 * self.disturbance))

    @property
    def s(self) -> float:
        """s = exp((GSI − 100)/(9 − 3D))."""
        return math.exp((self.gsi - 100) / (9 - 3 * self.disturbance))

    @property
    def a(self) -> float:
        """a = 1/2 + (e^(−GSI/15) − e^(−20/3))/6."""
        return 0.5 + (math.exp(-self.gsi / 15) - math.exp(-20 / 3)) / 6


ZoneModel = Annotated[Union[Elastic, MohrCoulomb, HoekBrown], Field(discriminator="model")]


def _n(angle_deg: float) -> float:
    """N = (1 + sin x)/(1 − sin x)."""
    s = math.sin(math.radians(angle_deg))
    return (1 + s) / (1 - s)


def material_table(models: list, mixed: Optional[list] = None) -> np.ndarray:
    """Rows of the kernels' zone-material table (columns ``ZM_*`` of :mod:`._kernels`).
    ``mixed``: per model, the nodal mixed discretisation (docs/dem.md §16.2) on or off; None
    entries (or no list): on for the plastic models."""
    from . import _kernels as K

    table = np.zeros((len(models), K.N_ZM_COLUMNS))
    mixed = [None] * len(models) if mixed is None else list(mixed)
    for row, m, mix in zip(table, models, mixed):
        row[K.ZM_MIXED] = float(not isinstance(m, Elastic) if mix is None else bool(mix))
        row[K.ZM_K], row[K.ZM_G] = m.bulk_modulus_pa, m.shear_modulus_pa
        if isinstance(m, Elastic):
            row[K.ZM_MODEL] = K.ZMODEL_ELASTIC
        elif isinstance(m, MohrCoulomb):
            row[K.ZM_MODEL] = K.ZMODEL_MC
            row[K.ZM_NPHI], row[K.ZM_NPSI] = _n(m.friction_deg), _n(m.dilation_deg)
            row[K.ZM_COH], row[K.ZM_TEN] = m.cohesion_pa, m.tension_pa
        elif isinstance(m, HoekBrown):
            row[K.ZM_MODEL] = K.ZMODEL_HB
            row[K.ZM_NPSI] = _n(m.dilation_deg)
            row[K.ZM_SIGCI], row[K.ZM_MB], row[K.ZM_S], row[K.ZM_A] = m.sigma_ci_pa, m.mb, m.s, m.a
        else:  # pragma: no cover - the types are checked where models are read
            raise TypeError(f"unknown zone model {m!r}")
    return table


def mesh_polygon(shell: np.ndarray, zone_size: float, holes: tuple = ()) -> tuple[np.ndarray, np.ndarray]:
    """Triangular zones of a polygon at about ``zone_size``: nodes every ≤ h along the boundary,
    a triangular lattice of spacing h inside (kept ≥ h/2 from the boundary), their Delaunay
    triangulation (scipy) without the triangles outside. Every boundary edge of the polygon is a
    chain of zone edges (checked; an edge the triangulation skipped is split and the mesh redone).

    Returns (nodes (N, 2), triangles (Z, 3), counter-clockwise).
    """
    from scipy.spatial import Delaunay
    from shapely import contains_xy, distance, points
    from shapely.geometry import Polygon

    shell = np.asarray(shell, float)
    rings = [shell] + [np.asarray(h, float) for h in holes]
    poly = Polygon(shell, [np.asarray(h, float) for h in holes])
    if not poly.is_valid or poly.area <= 0:
        raise ValueError("mesh_polygon: the polygon is not valid (self-intersecting or empty)")
    h = float(zone_size)
    boundary = []
    for ring in rings:
        ring = ring[:-1] if np.allclose(ring[0], ring[-1]) else ring
        for p, q in zip(ring, np.roll(ring, -1, axis=0)):
            n = max(1, math.ceil(np.hypot(*(q - p)) / h))
            t = np.arange(n)[:, None] / n
            boundary.append(p + t * (q - p))
    boundary = np.vstack(boundary)
    x0, y0, x1, y1 = poly.bounds
    dy = h * math.sqrt(3) / 2
    rows = np.arange(y0 + dy / 2, y1, dy)
    lattice = [np.column_stack([np.arange(x0 + (i % 2) * h / 2, x1, h), np.full(
        len(np.arange(x0 + (i % 2) * h / 2, x1, h)), y)]) for i, y in enumerate(rows)]
    inner = np.vstack(lattice) if lattice else np.empty((0, 2))
    if len(inner):
        keep = contains_xy(poly, inner[:, 0], inner[:, 1])
        inner = inner[keep]
        inner = inner[distance(poly.exterior.union(poly.boundary), points(inner)) > 0.5 * h]
    nodes = np.vstack([boundary, inner])
    tri = Delaunay(nodes).simplices.astype(np.int64)
    c = nodes[tri].mean(axis=1)
    a2 = _twice_areas(nodes, tri)
    keep = contains_xy(poly, c[:, 0], c[:, 1]) & (np.abs(a2) > 1e-9 * h * h)
    tri = tri[keep]
    flip = _twice_areas(nodes, tri) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    covered = 0.5 * _twice_areas(nodes, tri).sum()
    if abs(covered - poly.area) > 1e-9 * poly.area:
        raise ValueError(f"mesh_polygon: zones cover {covered:.9g} of {poly.area:.9g} m² (the "
                         "zone size may be too large for the polygon's features)")
    return nodes, tri


def lumped_masses(nodes: np.ndarray, tri: np.ndarray, density: float) -> np.ndarray:
    """Node masses (per metre of thickness): each zone gives ρA/3 to each of its nodes."""
    mass = np.zeros(len(nodes))
    np.add.at(mass, np.asarray(tri).ravel(), np.repeat(density * triangle_areas(nodes, tri) / 3, 3))
    return mass


def triangle_areas(nodes: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Signed areas of the triangles (positive counter-clockwise)."""
    return 0.5 * _twice_areas(nodes, tri)


def _twice_areas(nodes: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p, q, r = nodes[tri[:, 0]], nodes[tri[:, 1]], nodes[tri[:, 2]]
    return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (r[:, 0] - p[:, 0]) * (q[:, 1] - p[:, 1])


def stiffness_rows(nodes: np.ndarray, tri: np.ndarray, bulk: np.ndarray,
                   shear: np.ndarray) -> np.ndarray:
    """Gershgorin row sums of the assembled stiffness, per node: max over its two degrees of
    freedom of Σ_j |K_ij| with K = Σ_zones A Bᵀ D B (plane strain; docs/dem.md §16.6). The stable
    step of node i on its own is 2√(m_i / R_i)."""
    n = len(nodes)
    p, q, r = nodes[tri[:, 0]], nodes[tri[:, 1]], nodes[tri[:, 2]]
    a2 = _twice_areas(nodes, tri)
    gx = np.stack([q[:, 1] - r[:, 1], r[:, 1] - p[:, 1], p[:, 1] - q[:, 1]], 1) / a2[:, None]
    gy = np.stack([r[:, 0] - q[:, 0], p[:, 0] - r[:, 0], q[:, 0] - p[:, 0]], 1) / a2[:, None]
    area = 0.5 * np.abs(a2)
    a1 = bulk + 4 * shear / 3
    a2m = bulk - 2 * shear / 3
    rows = np.zeros((n, 2))
    for i in range(3):
        for j in range(3):
            # 2×2 block K_ij = A [[a1 gx_i gx_j + G gy_i gy_j, a2 gx_i gy_j + G gy_i gx_j],
            #                     [a2 gy_i gx_j + G gx_i gy_j, a1 gy_i gy_j + G gx_i gx_j]]
            kxx = area * (a1 * gx[:, i] * gx[:, j] + shear * gy[:, i] * gy[:, j])
            kxy = area * (a2m * gx[:, i] * gy[:, j] + shear * gy[:, i] * gx[:, j])
            kyx = area * (a2m * gy[:, i] * gx[:, j] + shear * gx[:, i] * gy[:, j])
            kyy = area * (a1 * gy[:, i] * gy[:, j] + shear * gx[:, i] * gx[:, j])
            np.add.at(rows[:, 0], tri[:, i], np.abs(kxx) + np.abs(kxy))
            np.add.at(rows[:, 1], tri[:, i], np.abs(kyx) + np.abs(kyy))
    return rows.max(axis=1)


class Zones:
    """A zoned body on its own (no joints): nodes, zones, one constitutive model per zone.

    Parameters
    ----------
    nodes : (N, 2) array
        Node positions (m).
    triangles : (Z, 3) int array
        Zones, counter-clockwise.
    models : a model, or a sequence of models with ``zone_model`` (Z,) indices into it
    density : float
        ρ (kg/m³); node masses are lumped, ρA/3 from each zone.
    mixed : bool or None
        Nodal mixed discretisation of the volumetric strain (docs/dem.md §16.2) for every zone;
        None: for the zones of plastic models.
    """

    def __init__(self, nodes, triangles, models, density: float = 2700.0,
                 zone_model: Optional[np.ndarray] = None, mixed: Optional[bool] = None):
        from . import _kernels as K

        self._K = K
        models = list(models) if isinstance(models, (list, tuple)) else [models]
        self.models = models
        self.x0 = np.ascontiguousarray(nodes, float).copy()
        self.xy = self.x0.copy()
        self.tri = np.ascontiguousarray(triangles, np.int64)
        a2 = _twice_areas(self.x0, self.tri)
        if (a2 <= 0).any():
            raise ValueError(f"{int((a2 <= 0).sum())} zones are not counter-clockwise or are flat")
        self.area0 = 0.5 * a2
        nz, nn = len(self.tri), len(self.x0)
        self.zmat = (np.zeros(nz, np.int64) if zone_model is None
                     else np.ascontiguousarray(zone_model, np.int64))
        self.mtab = material_table(models, [mixed] * len(models))
        self.mixed = bool(self.mtab[:, K.ZM_MIXED].any())
        self.density = float(density)
        self.mass = lumped_masses(self.x0, self.tri, density)
        self.vel = np.zeros((nn, 2))
        self.sig = np.zeros((nz, K.N_ZS_COLUMNS))
        self.strain = np.zeros((nz, 3))
        self.eps_p = np.zeros(nz)
        self.state = np.zeros(nz, np.int64)
        self.mode = np.zeros((nn, 2), np.int64)
        self.presc = np.zeros((nn, 2))
        self.fext = np.zeros((nn, 2))
        self.E = np.zeros(K.N_ENERGY)
        self.rows = stiffness_rows(self.x0, self.tri, self.mtab[self.zmat, K.ZM_K],
                                   self.mtab[self.zmat, K.ZM_G])

    # --- set-up -----------------------------------------------------------------------------

    def fix(self, nodes, x: bool = True, y: bool = True) -> None:
        """Fix the x and/or y motion of ``nodes`` (indices or a boolean mask)."""
        if x:
            self.mode[nodes, 0] = 1
        if y:
            self.mode[nodes, 1] = 1

    def prescribe(self, nodes, velocity) -> None:
        """Move ``nodes`` at a prescribed ``velocity`` ((2,) or (n, 2), m per step of a static
        relaxation, m/s in true time)."""
        self.mode[nodes] = 2
        self.presc[nodes] = velocity

    def set_stress(self, sxx: float, syy: float, szz: float, sxy: float = 0.0) -> None:
        """Uniform initial stress in every zone (compression positive, Pa)."""
        K = self._K
        self.sig[:, K.ZS_XX], self.sig[:, K.ZS_YY] = -sxx, -syy
        self.sig[:, K.ZS_ZZ], self.sig[:, K.ZS_XY] = -szz, -sxy

    # --- stepping ---------------------------------------------------------------------------

    def relax(self, gravity=(0.0, 0.0), tolerance: float = 1e-7, max_steps: int = 200_000,
              damping: float = 0.8, safety: float = 0.5, check_every: int = 100) -> dict:
        """Static relaxation to equilibrium: nodal masses scaled to one stable step of Δt = 1
        (m_i = R_i (Δt/2s)², R_i the node's Gershgorin row, s the safety; density scaling) under
        local damping, until the ratio Σ|F_unb|/Σ|F_applied| < ``tolerance``. The weight is the
        true mass times ``gravity``. Returns {steps, ratio, converged}."""
        K = self._K
        scaled = self.rows / (2 * safety) ** 2
        inv_mass = 1.0 / np.maximum(scaled, 1e-300)
        out = np.zeros(4)
        rc = K.advance_zones(int(max_steps), self.xy, self.vel, self.tri, self.zmat, self.mtab,
                             self.sig, self.strain, self.state, self.eps_p, self.mixed,
                             self.fext, self.mass, inv_mass, self.mode, self.presc,
                             np.asarray(gravity, float),
                             float(damping), 0.0, 1.0, float(tolerance), int(check_every),
                             self.E, out)
        if rc == K.RC_NONFINITE:
            raise FloatingPointError("zones: a non-finite value appeared (unstable step)")
        self.vel[:] = 0.0
        return {"steps": int(out[0]), "ratio": float(out[1]), "converged": rc == K.RC_CONVERGED}

    # --- results ----------------------------------------------------------------------------

    @property
    def displacement(self) -> np.ndarray:
        """Node displacements (N, 2), m."""
        return self.xy - self.x0

    @property
    def stress(self) -> np.ndarray:
        """Zone stresses (Z, 4): σ_xx, σ_yy, σ_zz, σ_xy, compression positive (Pa)."""
        return -self.sig

    @property
    def centroids(self) -> np.ndarray:
        return self.xy[self.tri].mean(axis=1)

    def plastic(self, now: bool = False) -> np.ndarray:
        """Zones that yielded (shear or tension) — at the last step with ``now``, else ever."""
        K = self._K
        bits = (K.ZST_SHEAR_NOW | K.ZST_TENSION_NOW) if now else (K.ZST_SHEAR_PAST
                                                                   | K.ZST_TENSION_PAST)
        return (self.state & bits) != 0

    def plastic_area(self, now: bool = False) -> float:
        """Area of the zones that yielded (m²)."""
        return float(self.area0[self.plastic(now)].sum())
