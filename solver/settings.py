"""What a DEM run needs besides the blocks: materials, joint models, boundaries, loading and stages.

Sign conventions (stated once, used everywhere in :mod:`rockmass.solver`)
-------------------------------------------------------------------------
- Stresses given by the user are **compression positive** (rock mechanics): ``InSituStress(sxx=5e6)``
  is 5 MPa of horizontal compression. Internally the solver converts once to tension positive.
- Contact normal force ``F_n`` is compression positive; ``F_n < 0`` is tension (glued contacts only).
- Angles are degrees, lengths metres, stiffnesses per unit contact area Pa/m (force per unit length of
  contact per metre of closure, unit thickness in 2D), time seconds, gravity a vector in m/s².

Everything here is a frozen dataclass with checks in ``__post_init__`` that raise ``ValueError``
naming the field and what was expected; the pipeline maps these to exit code 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Union

import numpy as np

__all__ = ["Coulomb", "ContinuouslyYielding", "JointModel", "Material", "InSituStress",
           "Fix", "BoundaryStress", "Sine", "Ricker", "TableHistory", "History", "VelocityInput",
           "QuietBoundary", "Monitor", "Stage", "Settings", "SIDES"]

SIDES = ("left", "right", "bottom", "top")


def _positive(name: str, value: float, allow_zero: bool = False):
    ok = math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        raise ValueError(f"{name} must be a finite number {'>= 0' if allow_zero else '> 0'}, "
                         f"got {value!r}")


def _sides(sides) -> tuple[str, ...]:
    sides = tuple(sides)
    if not sides or any(s not in SIDES for s in sides):
        raise ValueError(f"sides must be a non-empty subset of {SIDES}, got {sides!r}")
    return sides


def _angle(name: str, value: float, low: float = 0.0, high: float = 90.0):
    if not (math.isfinite(value) and low <= value < high):
        raise ValueError(f"{name} must be in [{low}, {high}) degrees, got {value!r}")


@dataclass(frozen=True)
class Coulomb:
    """Linear Coulomb slip joint with cohesion, tensile strength and dilation (brittle).

    Elastic: Δσ_n = k_n Δu_n, Δτ = k_s Δu_s. Strength |τ| ≤ c + σ_n tan φ, tension σ_n ≥ −T. When
    either limit is reached the contact fails: c → 0, T → 0 and φ → ``residual_friction_deg``
    (UDEC's brittle Coulomb slip; REFERENCE.md §5; seed 002 eqs. 7–9). While slipping the joint
    dilates by tan ψ per unit plastic shear displacement, up to ``max_dilation_m`` of opening.
    A glued contact (potential crack, seed 000 eqs. 1–2) is this model with intact-rock c, φ, T.
    """

    kn_pa_m: float
    ks_pa_m: float
    friction_deg: float
    cohesion_pa: float = 0.0
    tension_pa: float = 0.0
    dilation_deg: float = 0.0
    residual_friction_deg: float | None = None
    max_dilation_m: float = math.inf

    def __post_init__(self):
        _positive("kn_pa_m", self.kn_pa_m)
        _positive("ks_pa_m", self.ks_pa_m)
        _angle("friction_deg", self.friction_deg)
        _positive("cohesion_pa", self.cohesion_pa, allow_zero=True)
        _positive("tension_pa", self.tension_pa, allow_zero=True)
        _angle("dilation_deg", self.dilation_deg, 0.0, 60.0)
        if self.residual_friction_deg is not None:
            _angle("residual_friction_deg", self.residual_friction_deg)
        if not self.max_dilation_m >= 0:
            raise ValueError(f"max_dilation_m must be >= 0, got {self.max_dilation_m!r}")

    @property
    def residual_deg(self) -> float:
        return self.friction_deg if self.residual_friction_deg is None else self.residual_friction_deg


@dataclass(frozen=True)
class ContinuouslyYielding:
    """Continuously yielding joint (Cundall & Hart 1984; seed 001 eqs. 4–13; REFERENCE.md §5).

    k_n = a_n σ_n^e_n, k_s = a_s σ_n^e_s; Δτ = F k_s Δu_s with F = (1 − τ/τ_m)/(1 − r),
    τ_m = σ_n tan φ_m, r = 0 at the start and reset to τ/τ_m at each reversal;
    φ_m = φ_b + (φ_m − φ_b) exp(−Δu_p / R) with Δu_p = (1 − F)|Δu_s| (eq. 12);
    dilation angle i = atan(|τ|/σ_n) − φ_b (eq. 13). No tensile strength.
    With e_n = e_s = 0 (as in seed 001, Table 2) the stiffnesses are a_n and a_s (Pa/m).
    """

    an_pa_m: float
    as_pa_m: float
    initial_friction_deg: float = 59.3
    basic_friction_deg: float = 30.0
    roughness_m: float = 1e-4
    en: float = 0.0
    es: float = 0.0

    def __post_init__(self):
        _positive("an_pa_m", self.an_pa_m)
        _positive("as_pa_m", self.as_pa_m)
        _angle("initial_friction_deg", self.initial_friction_deg)
        _angle("basic_friction_deg", self.basic_friction_deg)
        if self.basic_friction_deg > self.initial_friction_deg:
            raise ValueError("basic_friction_deg must not exceed initial_friction_deg "
                             f"({self.basic_friction_deg} > {self.initial_friction_deg})")
        _positive("roughness_m", self.roughness_m)
        for name in ("en", "es"):
            if not 0.0 <= getattr(self, name) < 1.0:
                raise ValueError(f"{name} must be in [0, 1), got {getattr(self, name)!r}")


JointModel = Union[Coulomb, ContinuouslyYielding]


@dataclass(frozen=True)
class Material:
    """Intact rock: density, and elastic moduli (used by quiet boundaries only: blocks are rigid)."""

    density_kg_m3: float = 2700.0
    bulk_modulus_pa: float | None = None
    shear_modulus_pa: float | None = None

    def __post_init__(self):
        _positive("density_kg_m3", self.density_kg_m3)
        for name in ("bulk_modulus_pa", "shear_modulus_pa"):
            if getattr(self, name) is not None:
                _positive(name, getattr(self, name))

    def wave_speeds(self) -> tuple[float, float]:
        """(C_p, C_s) = (√((K + 4G/3)/ρ), √(G/ρ)) in m/s."""
        if self.bulk_modulus_pa is None or self.shear_modulus_pa is None:
            raise ValueError("quiet boundaries need material.bulk_modulus_pa and shear_modulus_pa")
        k, g, rho = self.bulk_modulus_pa, self.shear_modulus_pa, self.density_kg_m3
        return math.sqrt((k + 4.0 * g / 3.0) / rho), math.sqrt(g / rho)


@dataclass(frozen=True)
class InSituStress:
    """Initial stress written into the contact forces (compression positive, Pa).

    σ_yy(y) = syy + ρ g_unit (y_ref − y) when ``gravity_gradient`` (ρ|g| from the settings), and
    σ_xx = sxx + k0 (σ_yy − syy) (so ``k0`` scales only the gravity part), σ_xy = sxy. Contact forces
    start at F_n = n·σ·n l, F_s = t·σ·n l (REFERENCE.md §5, problem 10), lumped consistently for the
    linear variation so every block starts in equilibrium.
    """

    sxx_pa: float = 0.0
    syy_pa: float = 0.0
    sxy_pa: float = 0.0
    gravity_gradient: bool = False
    k0: float = 1.0
    y_ref_m: float | None = None

    def __post_init__(self):
        for name in ("sxx_pa", "syy_pa", "sxy_pa", "k0"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if self.k0 < 0:
            raise ValueError(f"k0 must be >= 0, got {self.k0}")


@dataclass(frozen=True)
class Fix:
    """Fix degrees of freedom of the blocks chosen by ``where``.

    ``where`` is a side (``"left"``, ``"right"``, ``"bottom"``, ``"top"``: blocks touching that side
    of the domain), ``"region:K"``, ``"box:x0,y0,x1,y1"`` (centroid inside), ``"blocks:i,j,k"``.
    ``dofs`` is any of ``"x"``, ``"y"``, ``"r"`` (rotation): ``"xyr"`` clamps, ``"x"`` is a roller
    on a vertical side.
    """

    where: str
    dofs: str = "xyr"

    def __post_init__(self):
        if not self.dofs or set(self.dofs) - set("xyr"):
            raise ValueError(f"dofs must be a non-empty combination of 'x', 'y', 'r', got {self.dofs!r}")


@dataclass(frozen=True)
class BoundaryStress:
    """Constant stress (compression positive, Pa) applied as tractions on the domain edges of the
    blocks on ``sides``: force on an edge = −σ·n_out L (tension-positive σ), lumped to its ends."""

    sides: tuple[str, ...]
    sxx_pa: float = 0.0
    syy_pa: float = 0.0
    sxy_pa: float = 0.0
    from_insitu: bool = False

    def __post_init__(self):
        object.__setattr__(self, "sides", _sides(self.sides))


@dataclass(frozen=True)
class Sine:
    """v(t) = amplitude sin(2π f t) for ``cycles`` cycles (all time if None), then 0."""

    amplitude: float
    frequency_hz: float
    cycles: float | None = None

    def __post_init__(self):
        _positive("frequency_hz", self.frequency_hz)
        if self.cycles is not None:
            _positive("cycles", self.cycles)

    def __call__(self, t):
        t = np.asarray(t, float)
        v = self.amplitude * np.sin(2.0 * np.pi * self.frequency_hz * t)
        if self.cycles is not None:
            v = np.where(t <= self.cycles / self.frequency_hz, v, 0.0)
        return np.where(t >= 0, v, 0.0)


@dataclass(frozen=True)
class Ricker:
    """Ricker wavelet a(1 − 2π²f²τ²) exp(−π²f²τ²), τ = t − t0 (t0 = 1.5/f when None)."""

    amplitude: float
    peak_frequency_hz: float
    t0_s: float | None = None

    def __post_init__(self):
        _positive("peak_frequency_hz", self.peak_frequency_hz)

    def __call__(self, t):
        f = self.peak_frequency_hz
        t0 = 1.5 / f if self.t0_s is None else self.t0_s
        a = (np.pi * f * (np.asarray(t, float) - t0)) ** 2
        return self.amplitude * (1.0 - 2.0 * a) * np.exp(-a)


@dataclass(frozen=True)
class TableHistory:
    """Piecewise-linear history from samples (times strictly increasing); 0 outside."""

    times_s: tuple[float, ...]
    values: tuple[float, ...]
    source: str = "table"

    def __post_init__(self):
        t = np.asarray(self.times_s, float)
        v = np.asarray(self.values, float)
        if t.ndim != 1 or t.shape != v.shape or len(t) < 2:
            raise ValueError(f"{self.source}: a history needs >= 2 (time, value) rows of equal length")
        if not (np.isfinite(t).all() and np.isfinite(v).all()):
            raise ValueError(f"{self.source}: times and values must be finite")
        if (np.diff(t) <= 0).any():
            raise ValueError(f"{self.source}: times must be strictly increasing")
        object.__setattr__(self, "times_s", tuple(t.tolist()))
        object.__setattr__(self, "values", tuple(v.tolist()))

    def __call__(self, t):
        return np.interp(t, self.times_s, self.values, left=0.0, right=0.0)

    def integrated(self) -> "TableHistory":
        """The running integral (trapezoid) — an acceleration history turned into velocity."""
        t = np.asarray(self.times_s)
        v = np.asarray(self.values)
        out = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
        return TableHistory(tuple(t), tuple(out), source=f"{self.source} (integrated)")


History = Union[Sine, Ricker, TableHistory]


@dataclass(frozen=True)
class VelocityInput:
    """Prescribe velocity component ``component`` (``"x"`` or ``"y"``) of the chosen blocks to
    ``history(t)`` (m/s) during dynamic stages — the shake-table base and sides (seed 002 §3).
    ``t`` is the time since the start of the dynamic stage (each dynamic stage starts its input at
    t = 0); in static stages these degrees of freedom are held fixed."""

    where: str
    component: Literal["x", "y"]
    history: History

    def __post_init__(self):
        if self.component not in ("x", "y"):
            raise ValueError(f"component must be 'x' or 'y', got {self.component!r}")


@dataclass(frozen=True)
class QuietBoundary:
    """Viscous (Lysmer–Kuhlemeyer) boundary on the domain edges of ``sides``: tractions −ρC_p v_n
    and −ρC_s v_s (REFERENCE.md §5), active in dynamic stages only."""

    sides: tuple[str, ...]

    def __post_init__(self):
        object.__setattr__(self, "sides", _sides(self.sides))


@dataclass(frozen=True)
class Monitor:
    """Record the block containing ``point_xy_m`` (or block ``block``) in ``history.csv``."""

    name: str
    point_xy_m: tuple[float, float] | None = None
    block: int | None = None

    def __post_init__(self):
        if (self.point_xy_m is None) == (self.block is None):
            raise ValueError(f"monitor {self.name!r}: give exactly one of point_xy_m and block")


@dataclass(frozen=True)
class Stage:
    """One stage of a run.

    ``kind="static"``: local non-viscous damping ``local_damping`` (0.8), stepping until
    equilibrium — the model's unbalanced-force ratio < ``tolerance`` (1e-5), every block's own
    force and moment ratio < ``block_tolerance`` (1e-3) and the kinetic energy falling
    (:func:`rockmass.solver._kernels.advance`) — or ``max_steps``. ``kind="dynamic"``: no local
    damping, Rayleigh damping (``rayleigh_ratio`` ξ at ``rayleigh_frequency_hz``; ``rayleigh_mode``
    ``"mass_stiffness"`` (minimum at f), ``"mass"`` or ``"stiffness"`` only — the stiffness part
    shortens the stable step, the mass part damps rigid-body motion), velocity inputs
    and quiet boundaries, for ``duration_s``. ``excavate``: excavation stages (regions of the
    BlockModel) removed at the start of this stage. ``time_step_s``: None picks it automatically;
    a value above the stable limit is refused.
    """

    name: str
    kind: Literal["static", "dynamic"] = "static"
    excavate: tuple[int, ...] = ()
    max_steps: int = 200_000
    tolerance: float = 1e-5
    block_tolerance: float = 1e-3
    local_damping: float = 0.8
    duration_s: float | None = None
    rayleigh_ratio: float = 0.0
    rayleigh_frequency_hz: float | None = None
    rayleigh_mode: Literal["mass_stiffness", "mass", "stiffness"] = "mass_stiffness"
    time_step_s: float | None = None
    frames: int = 10
    history_every: int = 0

    def __post_init__(self):
        object.__setattr__(self, "excavate", tuple(int(k) for k in self.excavate))
        if self.kind not in ("static", "dynamic"):
            raise ValueError(f"stage {self.name!r}: kind must be 'static' or 'dynamic', got {self.kind!r}")
        if self.max_steps < 1:
            raise ValueError(f"stage {self.name!r}: max_steps must be >= 1")
        _positive(f"stage {self.name!r}: tolerance", self.tolerance)
        _positive(f"stage {self.name!r}: block_tolerance", self.block_tolerance)
        if not 0.0 <= self.local_damping < 1.0:
            raise ValueError(f"stage {self.name!r}: local_damping must be in [0, 1), got {self.local_damping}")
        if self.kind == "dynamic":
            if self.duration_s is None:
                raise ValueError(f"stage {self.name!r}: a dynamic stage needs duration_s")
            _positive(f"stage {self.name!r}: duration_s", self.duration_s)
        if not 0.0 <= self.rayleigh_ratio < 1.0:
            raise ValueError(f"stage {self.name!r}: rayleigh_ratio must be in [0, 1)")
        if self.rayleigh_mode not in ("mass_stiffness", "mass", "stiffness"):
            raise ValueError(f"stage {self.name!r}: rayleigh_mode must be 'mass_stiffness', 'mass' or "
                             f"'stiffness', got {self.rayleigh_mode!r}")
        if self.rayleigh_ratio > 0 and self.rayleigh_frequency_hz is None:
            raise ValueError(f"stage {self.name!r}: rayleigh_ratio needs rayleigh_frequency_hz")
        if self.time_step_s is not None:
            _positive(f"stage {self.name!r}: time_step_s", self.time_step_s)
        if self.frames < 0 or self.history_every < 0:
            raise ValueError(f"stage {self.name!r}: frames and history_every must be >= 0")


@dataclass(frozen=True)
class Settings:
    """Everything :func:`rockmass.solver.run` needs besides the :class:`BlockModel`.

    ``joints`` maps a contact label to its joint model. A contact's label is looked up as its joint
    set name (``contact_kind == "joint"``), then its kind (``"joint"``, ``"trace"``, ``"glued"``,
    ``"excavation"``), then ``"default"`` (also used for contacts formed during the run between
    blocks that were not neighbours). ``rounding_m`` is the corner rounding d (UDEC): every corner
    is an arc of radius d tangent to its two edges (smaller on a block whose sharp corners would
    leave less than half of an edge flat; :func:`rockmass.solver.engine.rounded_corners`), so
    contacts turn smoothly over corners; None takes the d the block model was built for (its
    ``quality["tolerances"]["rounding_m"]``, which blockgen's minimum edge 2d was made for), else
    1 % of the median edge length; the overlap
    limit is d/2 (REFERENCE.md §5). ``sleep``: in static
    stages, blocks whose own unbalanced-force ratio stays below the stage tolerance stop being
    integrated until a neighbour disturbs them (REFERENCE.md §6; speed-up and the displacement error
    it adds are measured in ``benchmarks/bench_solver.py``).

    Failing blocks (:mod:`rockmass.solver.failure`): in static stages a block that has moved more
    than ``failure_displacement_m`` (None: a quarter of the rounding d) and keeps moving over
    ``failure_checks`` consecutive checks (500 steps apart) is taken out and reported; failing
    blocks smaller than ``sliver_area_m2`` are reported as slivers, and blocks that small are left
    out of the displacement measures. ``energy_tolerance``: the energy ledger is checked after
    every chunk of steps; a residual above this fraction of the energy turned over in the stage
    ends it with status ``unstable``.
    """

    joints: dict
    stages: tuple[Stage, ...]
    material: Material = field(default_factory=Material)
    gravity_m_s2: tuple[float, float] = (0.0, -9.81)
    insitu: InSituStress | None = None
    fixes: tuple[Fix, ...] = ()
    boundary_stress: tuple[BoundaryStress, ...] = ()
    velocity_inputs: tuple[VelocityInput, ...] = ()
    quiet: QuietBoundary | None = None
    monitors: tuple[Monitor, ...] = ()
    rounding_m: float | None = None
    contact_tolerance_m: float | None = None
    time_step_safety: float = 0.5
    sleep: bool = False
    failure_displacement_m: float | None = None
    failure_checks: int = 3
    sliver_area_m2: float = 0.0
    energy_tolerance: float = 0.2

    def __post_init__(self):
        for name in ("stages", "fixes", "boundary_stress", "velocity_inputs", "monitors"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        if not self.stages:
            raise ValueError("settings need at least one stage")
        if "default" not in self.joints:
            raise ValueError("joints must define a 'default' joint model (used for any contact "
                             "whose set or kind has none, and for contacts formed during the run)")
        for label, model in self.joints.items():
            if not isinstance(model, (Coulomb, ContinuouslyYielding)):
                raise ValueError(f"joints[{label!r}] must be a Coulomb or ContinuouslyYielding model")
        g = tuple(float(v) for v in self.gravity_m_s2)
        if len(g) != 2 or not all(math.isfinite(v) for v in g):
            raise ValueError(f"gravity_m_s2 must be two finite numbers, got {self.gravity_m_s2!r}")
        object.__setattr__(self, "gravity_m_s2", g)
        if self.rounding_m is not None:
            _positive("rounding_m", self.rounding_m)
        if self.contact_tolerance_m is not None:
            _positive("contact_tolerance_m", self.contact_tolerance_m)
        if self.failure_displacement_m is not None:
            _positive("failure_displacement_m", self.failure_displacement_m)
        if self.failure_checks < 1:
            raise ValueError(f"failure_checks must be >= 1, got {self.failure_checks}")
        _positive("sliver_area_m2", self.sliver_area_m2, allow_zero=True)
        _positive("energy_tolerance", self.energy_tolerance)
        if not 0 < self.time_step_safety <= 1:
            raise ValueError(f"time_step_safety must be in (0, 1], got {self.time_step_safety}")
        names = [s.name for s in self.stages]
        if len(set(names)) != len(names):
            raise ValueError(f"stage names must be unique, got {names}")
