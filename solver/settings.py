"""What a DEM run needs besides the blocks: materials, joint models, boundaries, loading and stages.

Sign conventions (stated once, used everywhere in :mod:`rockmass.solver`)
-------------------------------------------------------------------------
- Stresses given by the user are **compression positive** (rock mechanics): ``InSituStress(sxx=5e6)``
  is 5 MPa of horizontal compression. Internally the solver converts once to tension positive.
- Contact normal force ``F_n`` is compression positive; ``F_n < 0`` is tension (glued contacts only).
- Angles are degrees, lengths metres, stiffnesses per unit contact area Pa/m (force per unit length of
  contact per metre of closure, unit thickness in 2D), time seconds, gravity a vector in m/s².

Parameters are declared once, here
----------------------------------
Every type but :class:`TableHistory` is a frozen ``pydantic`` dataclass
(:func:`rockmass.dfn.specs.spec`): each field's annotation carries its type, range and
description, its default is the dataclass default, and cross-field rules are validators on the
class. Constructing one from Python (``Coulomb(kn_pa_m=-1, ...)``) and reading one from a
TOML ``[solve]`` section (:mod:`rockmass.solve_config`, which uses these classes as its field types)
run the same checks; a bad value raises ``pydantic.ValidationError`` (a ``ValueError``) naming the
field, and the pipeline maps it to exit code 2. Numbers are checked strictly (an ``int`` field takes
no float, a ``bool`` field no number; NaN and infinity are refused unless a field says otherwise), and
sequences accept any iterable (stored as tuples). The generated configuration reference
(``docs/config.md``) is written from these declarations. The solver kernels see none of this: the
engine reads the values into plain arrays.
"""

from __future__ import annotations

import math
import typing
from dataclasses import dataclass as _plain_dataclass
from typing import Annotated, Any, Callable, Literal, Optional, Union

import numpy as np
from pydantic import BeforeValidator, Field, PlainSerializer, Strict, model_validator

from ..dfn.specs import Bool, Float, Int, field_error, spec
from . import tolerances as T
from .zones import ZoneModel

__all__ = ["Coulomb", "ContinuouslyYielding", "JointModel", "Material", "InSituStress",
           "Fix", "BoundaryStress", "Sine", "BandRecord", "Ricker", "TableHistory", "History", "VelocityInput",
           "QuietBoundary", "FreeField", "Monitor", "BoltProperties", "Bolt", "BoltPattern",
           "Deformable", "Stage", "Settings", "SIDES"]


def _none_is_inf(value: Any) -> Any:
    return math.inf if value is None else value


# the domain quantities used by several classes
Stiffness = Annotated[Float, Field(gt=0, le=1e16)]
Friction = Annotated[Float, Field(ge=0, lt=90)]
Stress = Annotated[Float, Field(ge=-1e11, le=1e11)]
Coord = Annotated[Float, Field(ge=-1e7, le=1e7)]
Side = Literal["left", "right", "bottom", "top"]
SIDES = typing.get_args(Side)
Sides = Annotated[tuple[Side, ...], Field(min_length=1, max_length=4)]
Where = Annotated[str, Strict(), Field(min_length=1, max_length=4096)]

_WHERE = ("blocks chosen by a side (left, right, bottom, top: blocks touching that side of the "
          "domain), \"region:K\", \"box:x0,y0,x1,y1\" (centroid inside) or \"blocks:i,j,k\"")


Impedance = Annotated[Literal["rock_mass", "rock_mass_intact", "rock"], Field(description=(
    "where the dashpots' ρC_p, ρC_s come from: rock_mass (the joints of the boundary blocks: "
    "joint stiffness × spacing), rock_mass_intact (those in series with the intact moduli), rock "
    "(material.bulk_modulus_pa and shear_modulus_pa)"))]
PWaveSpeed = Annotated[Optional[Float], Field(gt=0, le=1e6, description=(
    "P-wave speed C_p of the normal dashpots (ρC_p) instead of the impedance rule's; none: the "
    "rule's"))]
SWaveSpeed = Annotated[Optional[Float], Field(gt=0, le=1e6, description=(
    "S-wave speed C_s of the tangential dashpots (ρC_s) instead of the impedance rule's; none: "
    "the rule's"))]


@spec
class Coulomb:
    """Linear Coulomb slip joint with cohesion, tensile strength and dilation (brittle).

    Elastic: Δσ_n = k_n Δu_n, Δτ = k_s Δu_s. Strength |τ| ≤ c + σ_n tan φ, tension σ_n ≥ −T. When
    either limit is reached the contact fails: c → 0, T → 0 and φ → ``residual_friction_deg``
    (UDEC's brittle Coulomb slip; docs/dem.md §5, eqs. (5.1)–(5.7); Varma et al. 2019). While slipping the joint
    dilates by tan ψ per unit plastic shear displacement, up to ``max_dilation_m`` of opening.
    A glued contact (potential crack; docs/dem.md §7, eqs. (7.1)–(7.3)) is this model with intact-rock c, φ, T.
    """

    kn_pa_m: Annotated[Stiffness, Field(description="normal stiffness k_n")]
    ks_pa_m: Annotated[Stiffness, Field(description="shear stiffness k_s")]
    friction_deg: Annotated[Friction, Field(description="friction angle φ")]
    cohesion_pa: Annotated[Float, Field(ge=0, le=1e11, description="cohesion c (lost at failure)")] = 0.0
    tension_pa: Annotated[Float, Field(ge=0, le=1e11,
                                       description="tensile strength T (lost at failure)")] = 0.0
    dilation_deg: Annotated[Float, Field(ge=0, lt=60, description="dilation angle ψ while slipping")] = 0.0
    residual_friction_deg: Annotated[Optional[Friction], Field(
        description="friction angle after failure; none: friction_deg")] = None
    max_dilation_m: Annotated[
        float, Strict(), Field(ge=0, allow_inf_nan=True,
                               description="largest opening by dilation; none or inf: no limit"),
        BeforeValidator(_none_is_inf), PlainSerializer(lambda v: None if math.isinf(v) else v)
    ] = math.inf
    model: Annotated[Literal["coulomb"], Field(description="joint model: \"coulomb\"")] = "coulomb"

    @property
    def residual_deg(self) -> float:
        return self.friction_deg if self.residual_friction_deg is None else self.residual_friction_deg


@spec
class ContinuouslyYielding:
    """Continuously yielding joint (Cundall & Hart 1984; docs/dem.md §6, eqs. (6.1)–(6.8)).

    k_n = a_n σ_n^e_n, k_s = a_s σ_n^e_s; Δτ = F k_s Δu_s with F = (1 − τ/τ_m)/(1 − r),
    τ_m = σ_n tan φ_m, r = 0 at the start and reset to τ/τ_m at each reversal;
    φ_m = φ_b + (φ_m − φ_b) exp(−Δu_p / R) with Δu_p = (1 − F)|Δu_s| (eq. 12);
    dilation angle i = atan(|τ|/σ_n) − φ_b (eq. 13). No tensile strength.
    With e_n = e_s = 0 (as in Kiran & Juneja 2022, Table 2) the stiffnesses are a_n and a_s (Pa/m).
    """

    an_pa_m: Annotated[Stiffness, Field(description="normal stiffness factor a_n")]
    as_pa_m: Annotated[Stiffness, Field(description="shear stiffness factor a_s")]
    initial_friction_deg: Annotated[Friction, Field(
        description="initial mobilised friction angle φ_m")] = 59.3
    basic_friction_deg: Annotated[Friction, Field(
        description="basic friction angle φ_b, <= initial_friction_deg")] = 30.0
    roughness_m: Annotated[Float, Field(gt=0, le=1e3,
                                        description="roughness R of the friction decay")] = 1e-4
    en: Annotated[Float, Field(ge=0, lt=1, description="exponent e_n of k_n = a_n σ_n^e_n")] = 0.0
    es: Annotated[Float, Field(ge=0, lt=1, description="exponent e_s of k_s = a_s σ_n^e_s")] = 0.0
    model: Annotated[Literal["cy"], Field(description="joint model: \"cy\"")] = "cy"

    @model_validator(mode="after")
    def _basic_below_initial(self):
        if self.basic_friction_deg > self.initial_friction_deg:
            raise field_error(self, "basic_friction_deg", "must not exceed initial_friction_deg "
                              f"({self.initial_friction_deg}), got {self.basic_friction_deg}",
                              self.basic_friction_deg)
        return self


JointModel = Annotated[Union[Coulomb, ContinuouslyYielding], Field(discriminator="model")]


@spec
class Material:
    """Intact rock: density, and elastic moduli (used by the impedance of quiet and free-field
    boundaries only, docs/dem.md §14: blocks are rigid)."""

    density_kg_m3: Annotated[Float, Field(gt=0, le=1e5, description="density ρ")] = 2700.0
    bulk_modulus_pa: Annotated[Optional[Float], Field(
        gt=0, le=1e13, description="bulk modulus K (boundary impedance only)")] = None
    shear_modulus_pa: Annotated[Optional[Float], Field(
        gt=0, le=1e13, description="shear modulus G (boundary impedance only)")] = None

    @property
    def has_moduli(self) -> bool:
        return self.bulk_modulus_pa is not None and self.shear_modulus_pa is not None

    def moduli(self) -> tuple[float, float]:
        """(M, G) = (K + 4G/3, G) in Pa: the P-wave (constrained) and shear moduli."""
        if not self.has_moduli:
            raise ValueError("this boundary impedance needs material.bulk_modulus_pa and "
                             "shear_modulus_pa")
        return self.bulk_modulus_pa + 4.0 * self.shear_modulus_pa / 3.0, self.shear_modulus_pa

    def wave_speeds(self) -> tuple[float, float]:
        """(C_p, C_s) = (√((K + 4G/3)/ρ), √(G/ρ)) in m/s."""
        m, g = self.moduli()
        return math.sqrt(m / self.density_kg_m3), math.sqrt(g / self.density_kg_m3)


@spec
class InSituStress:
    """Initial stress written into the contact forces (compression positive, Pa).

    σ_yy(y) = syy + ρ g_unit (y_ref − y) when ``gravity_gradient`` (ρ|g| from the settings), and
    σ_xx = sxx + k0 (σ_yy − syy) (so ``k0`` scales only the gravity part), σ_xy = sxy. Contact forces
    start at F_n = n·σ·n l, F_s = t·σ·n l (docs/dem.md §9.3 and §13, problem 10), lumped consistently for the
    linear variation so every block starts in equilibrium.
    """

    sxx_pa: Annotated[Stress, Field(description="horizontal stress σ_xx (at y_ref_m)")] = 0.0
    syy_pa: Annotated[Stress, Field(description="vertical stress σ_yy (at y_ref_m)")] = 0.0
    sxy_pa: Annotated[Stress, Field(description="shear stress σ_xy")] = 0.0
    gravity_gradient: Annotated[Bool, Field(
        description="add the weight of the rock above: σ_yy grows by ρ|g| per metre below y_ref_m")] = False
    k0: Annotated[Float, Field(ge=0, le=100, description="ratio of the horizontal to the vertical "
                                                         "gravity stress")] = 1.0
    y_ref_m: Annotated[Optional[Coord], Field(
        description="level where the gravity part is zero; none: the top of the model")] = None


@spec
class Fix:
    """Fix degrees of freedom of the blocks chosen by ``where``.

    ``where`` is a side (``"left"``, ``"right"``, ``"bottom"``, ``"top"``: blocks touching that side
    of the domain), ``"region:K"``, ``"box:x0,y0,x1,y1"`` (centroid inside), ``"blocks:i,j,k"``.
    ``dofs`` is any of ``"x"``, ``"y"``, ``"r"`` (rotation): ``"xyr"`` clamps, ``"x"`` is a roller
    on a vertical side.
    """

    where: Annotated[Where, Field(description=_WHERE)]
    dofs: Annotated[str, Strict(), Field(pattern=r"^[xyr]{1,3}$", description=(
        "fixed degrees of freedom, letters of x, y, r (rotation): \"xyr\" clamps, \"x\" is a "
        "roller on a vertical side"))] = "xyr"


@spec
class BoundaryStress:
    """Constant stress (compression positive, Pa) applied as tractions on the domain edges of the
    blocks on ``sides``: force on an edge = −σ·n_out L (tension-positive σ), lumped to its ends."""

    sides: Annotated[Sides, Field(description="domain sides loaded")]
    sxx_pa: Annotated[Stress, Field(description="σ_xx applied")] = 0.0
    syy_pa: Annotated[Stress, Field(description="σ_yy applied")] = 0.0
    sxy_pa: Annotated[Stress, Field(description="σ_xy applied")] = 0.0
    from_insitu: Annotated[Bool, Field(
        description="apply the in-situ stress at each edge instead of sxx_pa, syy_pa, sxy_pa")] = False


@spec
class Sine:
    """v(t) = amplitude sin(2π f t) for ``cycles`` cycles (all time if None), then 0."""

    amplitude: Annotated[Float, Field(ge=-1e6, le=1e6, description="peak value (m/s of velocity)")]
    frequency_hz: Annotated[Float, Field(gt=0, le=1e7, description="frequency f")]
    cycles: Annotated[Optional[Float], Field(
        gt=0, le=1e7, description="number of cycles, then 0; none: all time")] = None
    type: Annotated[Literal["sine"], Field(description="history kind: \"sine\"")] = "sine"

    def __call__(self, t):
        t = np.asarray(t, float)
        v = self.amplitude * np.sin(2.0 * np.pi * self.frequency_hz * t)
        if self.cycles is not None:
            v = np.where(t <= self.cycles / self.frequency_hz, v, 0.0)
        return np.where(t >= 0, v, 0.0)


@spec
class TableSine:
    """A shake table's sinusoidal motion given by its displacement: u(t) = D r(t) sin(2π f t) for
    ``cycles`` cycles, the amplitude ramped linearly from 0 over the first ``ramp_cycles`` and
    back to 0 over the last (r(t) = min(1, f t/n_r, f (T − t)/n_r), T = cycles/f); 0 outside. It
    returns the velocity, the exact derivative v = D (r′ sin 2πft + 2πf r cos 2πft): the table
    starts and ends at rest at its origin, swings ± D about it (the "maximum displacement of the
    shake table from its original position" of Varma et al. 2019 §3), and its acceleration peaks
    near (2πf)² D. A velocity Sine, by contrast, moves the table between 0 and 2A/(2πf).

    >>> h = TableSine(0.0155, 3.0, cycles=15)
    >>> t = np.linspace(0.0, 5.0, 200_001)
    >>> u = np.concatenate([[0.0], np.cumsum(0.5 * (h(t[1:]) + h(t[:-1])) * np.diff(t))])
    >>> round(float(np.abs(u).max()), 5), round(float(abs(u[-1])), 8)
    (0.0155, 0.0)
    """

    displacement_amplitude_m: Annotated[Float, Field(gt=0, le=1e3, description=(
        "table displacement amplitude D (m)"))]
    frequency_hz: Annotated[Float, Field(gt=0, le=1e7, description="frequency f")]
    cycles: Annotated[Float, Field(gt=0, le=1e7, description="number of cycles")]
    ramp_cycles: Annotated[Float, Field(ge=0, le=1e7, description=(
        "cycles over which the amplitude rises at the start and falls at the end"))] = 1.0
    type: Annotated[Literal["table_sine"], Field(description="history kind: \"table_sine\"")] = \
        "table_sine"

    @model_validator(mode="after")
    def _ramps_fit(self):
        if 2 * self.ramp_cycles > self.cycles:
            raise field_error(self, "ramp_cycles", f"the two ramps ({self.ramp_cycles} cycles "
                              f"each) must fit in cycles = {self.cycles}", self.ramp_cycles)
        return self

    def __call__(self, t):
        t = np.asarray(t, float)
        f, n_r = self.frequency_hz, self.ramp_cycles
        end = self.cycles / f
        phase = 2.0 * np.pi * f * t
        if n_r > 0:
            r = np.minimum(1.0, np.minimum(f * t, f * (end - t)) / n_r)
            dr = np.where(f * t < n_r, f / n_r, np.where(f * (end - t) < n_r, -f / n_r, 0.0))
            dr = np.where(r < 1.0, dr, 0.0)
        else:
            r, dr = np.ones_like(t), np.zeros_like(t)
        v = self.displacement_amplitude_m * (dr * np.sin(phase) + 2.0 * np.pi * f * r * np.cos(phase))
        return np.where((t >= 0) & (t <= end), v, 0.0)


@spec
class BandRecord:
    """A band-limited synthetic table motion, for a dynamic stage whose earthquake record is not
    at hand (docs/dem.md §9.2, eqs. (9.2a)–(9.2c); :mod:`rockmass.solver.records`): a pass of
    ``duration_s`` whose acceleration has a flat Fourier amplitude on ``band_hz`` (cos² roll-off
    over ``rolloff_octaves`` octaves beyond each end), random phases from ``seed``, a Tukey window
    (tapers of ``taper_fraction`` of the pass at each end, so the table starts and ends each pass
    at rest at its origin), scaled so that its largest displacement (``peak = "displacement"``) or
    acceleration (``"acceleration"``) over the pass is ``peak_value`` (m or m/s²); ``passes`` passes
    of the same record back to back, as a shake table replays one scaled record cycle after cycle.
    It returns the velocity (the exact derivative); :meth:`displacement` and :meth:`acceleration`
    give the other two.

    >>> h = BandRecord(band_hz=(0.6, 6.0), duration_s=10.0, peak="displacement",
    ...                peak_value=0.0155, passes=2, seed=1)
    >>> t = np.linspace(0.0, 20.0, 400_001)
    >>> u = h.displacement(t)
    >>> round(float(np.abs(u).max()), 6), float(u[0]), abs(float(u[-1])) < 1e-12
    (0.0155, 0.0, True)
    """

    band_hz: Annotated[tuple[Float, Float], Field(description=(
        "[f_lo, f_hi]: the band where the acceleration's Fourier amplitude is flat (Hz)"))]
    duration_s: Annotated[Float, Field(gt=0, le=1e5, description="duration of one pass (s)")]
    peak_value: Annotated[Float, Field(gt=0, le=1e6, description=(
        "largest displacement (m) or acceleration (m/s²) of a pass, by peak"))]
    peak: Annotated[Literal["displacement", "acceleration"], Field(
        description="what peak_value fixes")] = "displacement"
    passes: Annotated[Int, Field(ge=1, le=100_000, description="passes of the record, back to back")] = 1
    seed: Annotated[Int, Field(ge=0, le=2 ** 63 - 1, description="seed of the phases")] = 0
    rolloff_octaves: Annotated[Float, Field(ge=0, le=10, description=(
        "octaves over which the amplitude falls to 0 beyond each end of the band"))] = 1.0
    taper_fraction: Annotated[Float, Field(gt=0, le=0.5, description=(
        "fraction of a pass tapered (Tukey window) at each end"))] = 0.1
    type: Annotated[Literal["band_record"], Field(description="history kind: \"band_record\"")] = \
        "band_record"

    @model_validator(mode="after")
    def _band_holds_a_component(self):
        from .records import band_problem
        problem = band_problem(*self.band_hz, self.rolloff_octaves, self.duration_s, self.seed)
        if problem is not None:
            raise field_error(self, "band_hz", problem, self.band_hz)
        return self

    def _motion(self, t, order: int):
        from .records import record_motion
        f_lo, f_hi = self.band_hz
        return record_motion(t, f_lo=f_lo, f_hi=f_hi, rolloff_octaves=self.rolloff_octaves,
                             duration_s=self.duration_s, taper_fraction=self.taper_fraction,
                             seed=self.seed, passes=self.passes, peak=self.peak,
                             peak_value=self.peak_value, order=order)

    def __call__(self, t):
        return self._motion(t, 1)

    def displacement(self, t):
        """The table's displacement u(t) (m), eq. (9.2a)."""
        return self._motion(t, 0)

    def acceleration(self, t):
        """The table's acceleration a(t) (m/s²), eq. (9.2c)."""
        return self._motion(t, 2)


@spec
class Ricker:
    """Ricker wavelet a(1 − 2π²f²τ²) exp(−π²f²τ²), τ = t − t0 (t0 = 1.5/f when None)."""

    amplitude: Annotated[Float, Field(ge=-1e6, le=1e6, description="peak value a (m/s of velocity)")]
    peak_frequency_hz: Annotated[Float, Field(gt=0, le=1e7, description="peak frequency f")]
    t0_s: Annotated[Optional[Float], Field(ge=0, le=1e7,
                                           description="centre time t0; none: 1.5/f")] = None
    type: Annotated[Literal["ricker"], Field(description="history kind: \"ricker\"")] = "ricker"

    def __call__(self, t):
        f = self.peak_frequency_hz
        t0 = 1.5 / f if self.t0_s is None else self.t0_s
        a = (np.pi * f * (np.asarray(t, float) - t0)) ** 2
        return self.amplitude * (1.0 - 2.0 * a) * np.exp(-a)


@_plain_dataclass(frozen=True)
class TableHistory:
    """Piecewise-linear history from samples (times strictly increasing); 0 outside.

    A plain dataclass (checked in ``__post_init__``): it is built from arrays (a CSV file read by
    :func:`rockmass.solve_config.read_history_csv`), never from configuration keys.
    """

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


History = Union[Sine, TableSine, BandRecord, Ricker, TableHistory]


@spec
class VelocityInput:
    """Prescribe velocity component ``component`` (``"x"`` or ``"y"``) of the chosen blocks to
    ``history(t)`` (m/s) during dynamic stages — the shake-table base and sides (Varma et al. 2019 §3; docs/dem.md §9.2).
    ``t`` is the time since the start of the dynamic stage (each dynamic stage starts its input at
    t = 0); in static stages these degrees of freedom are held fixed."""

    where: Annotated[Where, Field(description=_WHERE)]
    component: Annotated[Literal["x", "y"], Field(description="velocity component prescribed")]
    history: Annotated[Callable[[Any], Any], Field(
        description="velocity in m/s as a function of time: a Sine, Ricker, TableHistory or any "
                    "callable of a time array")]


@spec
class QuietBoundary:
    """Viscous (Lysmer–Kuhlemeyer) boundary on the domain edges of ``sides``: tractions −ρC_p v_n
    and −ρC_s v_s (docs/dem.md §9.4, eq. (9.1)), active in dynamic stages only.

    ``impedance`` says where ρC_p = √(ρM) and ρC_s = √(ρG) come from (docs/dem.md §14.1):
    ``"rock_mass"`` (default) the moduli of the jointed rock mass the rigid-block model is, per
    boundary edge, from the joints of its block (1/M = Σ_f (l_f / 2A) c²(c²/k_n + s²/k_s),
    c = n_f·n, s = t_f·n: k_n s for joints of spacing s parallel to the boundary);
    ``"rock_mass_intact"`` those in series with the intact moduli, 1/M_mass = 1/M_rock +
    1/M_joints (deformable blocks; Schoenberg 1980); ``"rock"`` the intact moduli alone.
    ``p_wave_speed_m_s`` / ``s_wave_speed_m_s`` override C_p / C_s."""

    sides: Annotated[Sides, Field(description="domain sides that absorb waves")]
    impedance: Impedance = "rock_mass"
    p_wave_speed_m_s: PWaveSpeed = None
    s_wave_speed_m_s: SWaveSpeed = None


@spec
class FreeField:
    """Free-field boundaries on the lateral ``sides`` of dynamic stages (seed 001, Kiran & Juneja
    2022, eqs. 14–16; Itasca's free field; docs/dem.md §14.2).

    Each side is coupled to a 1D column of the blocks along it (their heights, their joints),
    solved alongside the model, driven by the same velocity inputs and starting from the in-situ
    stress: the side edges carry F = −ρC_p (v_n − v_n^ff) A − ρC_s (v_t − v_t^ff) A + F^ff,
    F^ff = σ^ff·n A, σ^ff the in-situ stress plus the column's dynamic shear stress. In static
    stages the sides are held normal to themselves (a roller carrying the in-situ stress). The
    dashpots' impedance follows the rules of :class:`QuietBoundary`."""

    sides: Annotated[tuple[Literal["left", "right"], ...], Field(
        min_length=1, max_length=2, description="lateral sides coupled to a free-field column")]
    impedance: Impedance = "rock_mass"
    p_wave_speed_m_s: PWaveSpeed = None
    s_wave_speed_m_s: SWaveSpeed = None


@spec
class Monitor:
    """Record the block containing ``point_xy_m`` (or block ``block``) in ``history.csv``."""

    name: Annotated[str, Strict(), Field(pattern=r"^[A-Za-z0-9_\-]{1,40}$",
                                         description="column name in history.csv")]
    point_xy_m: Annotated[Optional[tuple[Coord, Coord]], Field(
        description="point (x, y) inside the recorded block")] = None
    block: Annotated[Optional[Int], Field(ge=0, description="number of the recorded block")] = None

    @model_validator(mode="after")
    def _one_of(self):
        if (self.point_xy_m is None) == (self.block is None):
            raise field_error(self, "point_xy_m", f"monitor {self.name!r}: give exactly one of "
                              "point_xy_m and block", self.point_xy_m)
        return self


@spec
class BoltProperties:
    """A fully grouted bolt or cable, as a UDEC cable element (Itasca 2004; docs/dem.md §15).

    Steel: an elastic–perfectly-plastic axial spring, axial stiffness E·A (``axial_stiffness_n``,
    or E and the diameter d: E·πd²/4), yielding at ``yield_force_n`` in tension and
    ``compressive_yield_force_n`` in compression. Grout: a shear spring along the bolt between the
    steel and the rock, ``bond_stiffness_n_m2`` (k_bond, force per metre of bolt per metre of
    slip) and ``bond_strength_n_m`` (s_bond, force per metre of bolt) at which it slips. The 2D
    model is a section of unit thickness through bolts ``out_of_plane_spacing_m`` apart: every
    force, stiffness and strength is divided by that spacing.
    """

    bond_stiffness_n_m2: Annotated[Float, Field(gt=0, le=1e16, description=(
        "grout shear stiffness k_bond per metre of bolt (N/m per m)"))]
    bond_strength_n_m: Annotated[Float, Field(gt=0, le=1e12, description=(
        "grout bond strength s_bond per metre of bolt (N/m)"))]
    axial_stiffness_n: Annotated[Optional[Float], Field(gt=0, le=1e14, description=(
        "axial stiffness E·A of one bolt; none: from youngs_modulus_pa and diameter_m"))] = None
    youngs_modulus_pa: Annotated[Optional[Float], Field(gt=0, le=1e13, description=(
        "Young's modulus E of the steel (with diameter_m, instead of axial_stiffness_n)"))] = None
    diameter_m: Annotated[Optional[Float], Field(gt=0, le=10, description=(
        "bolt diameter d: A = πd²/4 (with youngs_modulus_pa)"))] = None
    yield_force_n: Annotated[Optional[Float], Field(gt=0, le=1e12, description=(
        "tensile yield force of one bolt; none: no yield"))] = None
    compressive_yield_force_n: Annotated[Optional[Float], Field(gt=0, le=1e12, description=(
        "compressive yield force of one bolt; none: yield_force_n"))] = None
    out_of_plane_spacing_m: Annotated[Float, Field(gt=0, le=1e3, description=(
        "spacing of the bolts normal to the section: forces per metre of thickness are those of "
        "one bolt divided by it"))] = 1.0

    @model_validator(mode="after")
    def _one_stiffness(self):
        pair = (self.youngs_modulus_pa is not None, self.diameter_m is not None)
        given = self.axial_stiffness_n is not None
        if not ((given and not any(pair)) or (not given and all(pair))):
            raise field_error(self, "axial_stiffness_n", "give either axial_stiffness_n or both "
                              "youngs_modulus_pa and diameter_m", self.axial_stiffness_n)
        return self

    def per_metre(self) -> dict[str, float]:
        """The kernel's values per metre of thickness: E·A, k_bond, s_bond and the yield forces
        (tension, compression; inf when none), each divided by the out-of-plane spacing.

        >>> BoltProperties(1e8, 2e5, youngs_modulus_pa=2e11, diameter_m=0.02,
        ...                out_of_plane_spacing_m=2.0).per_metre()["axial_stiffness_n"]
        31415926.535897933
        """
        ea = (self.axial_stiffness_n if self.axial_stiffness_n is not None
              else self.youngs_modulus_pa * math.pi * self.diameter_m ** 2 / 4.0)
        tension = math.inf if self.yield_force_n is None else self.yield_force_n
        compression = (tension if self.compressive_yield_force_n is None
                       else self.compressive_yield_force_n)
        s = self.out_of_plane_spacing_m
        return {"axial_stiffness_n": ea / s, "bond_stiffness_n_m2": self.bond_stiffness_n_m2 / s,
                "bond_strength_n_m": self.bond_strength_n_m / s, "yield_force_n": tension / s,
                "compressive_yield_force_n": compression / s}


BoltSegments = Annotated[Int, Field(ge=1, le=10_000, description=(
    "segments of the bolt (nodes: segments + 1); each node is grouted over its share of the "
    "length"))]
BoltStage = Annotated[str, Strict(), Field(min_length=1, max_length=64, description=(
    "stage at whose start (after its excavation) the bolt is installed"))]


@spec
class Bolt:
    """One straight bolt from ``start_xy_m`` to ``end_xy_m`` (world frame, m), installed at the start
    of stage ``stage`` after that stage's excavation: its nodes are grouted into the blocks that
    contain them then (docs/dem.md §15)."""

    start_xy_m: Annotated[tuple[Coord, Coord], Field(description="first end (x, y) of the bolt")]
    end_xy_m: Annotated[tuple[Coord, Coord], Field(description="second end (x, y) of the bolt")]
    stage: BoltStage
    properties: Annotated[BoltProperties, Field(description="steel and grout")]
    segments: BoltSegments = 10
    name: Annotated[Optional[str], Strict(), Field(pattern=r"^[A-Za-z0-9_\-]{1,40}$", description=(
        "name in bolts.csv; none: bolt<k>"))] = None

    @model_validator(mode="after")
    def _not_a_point(self):
        if math.dist(self.start_xy_m, self.end_xy_m) <= 0:
            raise field_error(self, "end_xy_m", "must differ from start_xy_m", self.end_xy_m)
        return self


Wall = Literal["roof", "floor", "left", "right"]


@spec
class BoltPattern:
    """Bolts by rule around the opening excavated so far (docs/dem.md §15): at the start of stage
    ``stage``, one bolt every ``spacing_m`` along the boundary of the opening (the union of the
    blocks excavated up to and including that stage; only the walls that stage's own excavation
    exposed when it excavates), normal to the wall and ``length_m`` into the rock. ``walls`` keeps the heads on the roof, floor, left or right walls (by the direction
    of the wall's normal into the rock: up, down, left, right; none: roof, left and right, as
    seed 000's patterns); ``box_m`` keeps only heads inside
    a box — seed 000 pattern 1: 5 m bolts every 1.5 m on the roof and side walls; pattern 2 adds
    15 m bolts on the weak parts of the walls (two patterns with boxes)."""

    stage: BoltStage
    length_m: Annotated[Float, Field(gt=0, le=1e4, description="bolt length into the rock")]
    spacing_m: Annotated[Float, Field(gt=0, le=1e4, description="spacing along the wall")]
    properties: Annotated[BoltProperties, Field(description="steel and grout")]
    walls: Annotated[Optional[tuple[Wall, ...]], Field(min_length=1, max_length=4, description=(
        "walls bolted: roof, floor, left, right (by the direction of the wall's normal into the "
        "rock); none: roof, left and right"))] = None
    box_m: Annotated[Optional[tuple[Coord, Coord, Coord, Coord]], Field(description=(
        "only heads inside this box (x0, y0, x1, y1); none: everywhere on the walls"))] = None
    segments: BoltSegments = 10
    name: Annotated[Optional[str], Strict(), Field(pattern=r"^[A-Za-z0-9_\-]{1,30}$", description=(
        "prefix of the bolts' names in bolts.csv; none: pattern<k>"))] = None


def _region_number(value: Any) -> Any:
    """An ``excavate`` entry must be a region number; say so for a name (issue 19)."""
    if isinstance(value, str):
        raise ValueError(f"excavate takes region numbers (int >= 1) of the BlockModel, got the name "
                         f"{value!r}: pass model.region_names.index({value!r}) (names are resolved "
                         "only by a config's [[solve.stages]] excavate)")
    return value


@spec
class Deformable:
    """Blocks made deformable: meshed into triangular zones of about ``zone_size_m`` with the
    constitutive ``model`` (elastic, Mohr–Coulomb or Hoek–Brown; docs/dem.md §16), the joints
    acting on their boundary. The other blocks stay rigid, and so do chosen blocks smaller than
    ``min_block_area_m2``. For a dynamic stage the zone size should be at most a tenth of the
    shortest wavelength carried: a run warns when it is not and keeps the check in
    ``Result.info["wave_checks"]`` (:mod:`rockmass.solver.wavelength`, docs/dem.md §16.9)."""

    where: Annotated[Where, Field(description=f"the blocks: {_WHERE}")]
    model: Annotated[ZoneModel, Field(description="constitutive model of the zones")]
    zone_size_m: Annotated[Float, Field(gt=0, le=1e6, description="zone size h (edge length)")]
    mixed: Annotated[Optional[Bool], Field(description=(
        "nodal mixed discretisation of the volumetric strain; none: on for plastic models"))] = None
    min_block_area_m2: Annotated[Float, Field(ge=0, le=1e12, description=(
        "chosen blocks smaller than this stay rigid (slivers: their zones would set the time "
        "step of a dynamic stage)"))] = 0.0


@spec
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

    name: Annotated[str, Strict(), Field(min_length=1, max_length=64,
                                         description="stage name, unique in the run")]
    kind: Annotated[Literal["static", "dynamic"], Field(
        description="static: step to equilibrium; dynamic: step for duration_s")] = "static"
    excavate: Annotated[tuple[Annotated[Int, BeforeValidator(_region_number), Field(ge=1)], ...], Field(
        max_length=64, description="regions of the block model removed at the start")] = ()
    max_steps: Annotated[Int, Field(ge=1, le=10 ** 10, description="step limit")] = 200_000
    tolerance: Annotated[Float, Field(gt=0, le=1, description=(
        "static: the model's unbalanced-force ratio at equilibrium"))] = 1e-5
    block_tolerance: Annotated[Float, Field(gt=0, le=1, description=(
        "static: every block's own force and moment ratio at equilibrium"))] = 1e-3
    local_damping: Annotated[Float, Field(ge=0, lt=1, description=(
        "static: local non-viscous damping coefficient"))] = 0.8
    duration_s: Annotated[Optional[Float], Field(gt=0, le=1e6, description=(
        "dynamic: stage duration (required)"))] = None
    rayleigh_ratio: Annotated[Float, Field(ge=0, lt=1, description=(
        "dynamic: Rayleigh damping ratio ξ"))] = 0.0
    rayleigh_frequency_hz: Annotated[Optional[Float], Field(gt=0, le=1e9, description=(
        "dynamic: frequency where the damping ratio is ξ (required when rayleigh_ratio > 0)"))] = None
    rayleigh_mode: Annotated[Literal["mass_stiffness", "mass", "stiffness"], Field(description=(
        "dynamic: Rayleigh terms used (mass_stiffness: minimum at the frequency; the stiffness "
        "part shortens the stable step)"))] = "mass_stiffness"
    rayleigh_reference: Annotated[Literal["absolute", "inputs"], Field(description=(
        "dynamic: velocity the mass-proportional damping acts on — absolute, or relative to the "
        "velocity inputs' motion (a shake table: the model moving with the table is not "
        "damped; each input component needs one history)"))] = "absolute"
    time_step_s: Annotated[Optional[Float], Field(gt=0, le=1e3, description=(
        "time step; none: chosen automatically (a value above the stable limit is refused)"))] = None
    frames: Annotated[Int, Field(ge=0, le=10_000, description="snapshots written in the stage")] = 10
    history_every: Annotated[Int, Field(ge=0, le=10 ** 9, description=(
        "steps between monitor records; 0: chosen automatically"))] = 0

    @model_validator(mode="after")
    def _kind_needs(self):
        if self.kind == "dynamic" and self.duration_s is None:
            raise field_error(self, "duration_s", f"stage {self.name!r}: a dynamic stage needs "
                              "duration_s (> 0 s)", None)
        if self.rayleigh_ratio > 0 and self.rayleigh_frequency_hz is None:
            raise field_error(self, "rayleigh_frequency_hz", f"stage {self.name!r}: required when "
                              "rayleigh_ratio > 0", None)
        return self


@spec
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
    limit is d/2 (docs/dem.md §3.4). ``sleep``: in static
    stages, blocks whose own unbalanced-force ratio stays below the stage tolerance stop being
    integrated until a neighbour disturbs them (docs/dem.md §10.2; speed-up and the displacement error
    it adds are measured in ``benchmarks/bench_solver.py``). ``density_scaling``: in static stages
    each rigid block's inertia is raised where needed so that no block is stiffer for its mass
    than the median block (docs/dem.md §10.4); fewer steps to the same tolerance, at the price of
    a different (non-physical) path to equilibrium.

    Failing blocks (:mod:`rockmass.solver.failure`): in static stages a block that has moved more
    than ``failure_displacement_m`` (None: a quarter of the rounding d) and keeps moving over
    ``failure_checks`` consecutive checks (500 steps apart) is taken out and reported; failing
    blocks smaller than ``sliver_area_m2`` are reported as slivers, and blocks that small are left
    out of the displacement measures. ``energy_tolerance``: the energy ledger is checked after
    every chunk of steps; a residual above this fraction of the energy turned over in the stage
    ends it with status ``unstable``.
    """

    joints: Annotated[dict[Annotated[str, Strict(), Field(min_length=1, max_length=64)], JointModel],
                      Field(min_length=1, description=(
                          "joint model of each contact label: a joint set name, a contact kind "
                          "(joint, trace, glued, excavation) or default (required)"))]
    stages: Annotated[tuple[Stage, ...], Field(min_length=1, max_length=1000, description=(
        "stages, run in order (unique names)"))]
    material: Annotated[Material, Field(description="intact rock")] = Material()
    gravity_m_s2: Annotated[tuple[Annotated[Float, Field(ge=-1e4, le=1e4)],
                                  Annotated[Float, Field(ge=-1e4, le=1e4)]],
                            Field(description="gravity vector (x, y)")] = (0.0, -9.81)
    insitu: Annotated[Optional[InSituStress], Field(description="initial stress")] = None
    fixes: Annotated[tuple[Fix, ...], Field(max_length=256, description="fixed blocks")] = ()
    boundary_stress: Annotated[tuple[BoundaryStress, ...], Field(
        max_length=16, description="stresses applied on domain sides")] = ()
    velocity_inputs: Annotated[tuple[VelocityInput, ...], Field(
        max_length=64, description="prescribed velocities (dynamic stages)")] = ()
    quiet: Annotated[Optional[QuietBoundary], Field(
        description="viscous boundary (dynamic stages)")] = None
    # left out of dumps (and config hashes) when absent: adding it changed no existing hash
    free_field: Annotated[Optional[FreeField], Field(
        description="free-field lateral boundaries (dynamic stages)",
        exclude_if=lambda value: value is None)] = None
    monitors: Annotated[tuple[Monitor, ...], Field(
        max_length=1000, description="blocks recorded in history.csv (unique names)")] = ()
    # left out of dumps (and config hashes) when empty: adding them changed no existing hash
    bolts: Annotated[tuple[Bolt, ...], Field(
        max_length=10_000, description="rock bolts and cables (docs/dem.md §15)",
        exclude_if=lambda value: not value)] = ()
    bolt_patterns: Annotated[tuple[BoltPattern, ...], Field(
        max_length=100, description="bolts by rule around the opening (docs/dem.md §15)",
        exclude_if=lambda value: not value)] = ()
    deformable: Annotated[tuple[Deformable, ...], Field(
        max_length=100, description="blocks meshed into zones (docs/dem.md §16)",
        exclude_if=lambda value: not value)] = ()
    rounding_m: Annotated[Optional[Float], Field(gt=0, le=1e6, description=(
        "corner rounding d; none: the block model's, else 1 % of the median edge"))] = None
    contact_tolerance_m: Annotated[Optional[Float], Field(gt=0, le=1e6, description=(
        "gap below which blocks are in contact; none: chosen from the rounding"))] = None
    time_step_safety: Annotated[Optional[Float], Field(gt=0, le=1, description=(
        "fraction of the stable time step used; none: 0.5 in static stages, 0.2 in dynamic ones "
        "(an elastic impact then gains or loses < 1 % of its energy, docs/dem.md §2.4)"))] = None
    sleep: Annotated[Bool, Field(description=(
        "static stages: stop integrating blocks in equilibrium until a neighbour moves"))] = False
    # left out of dumps (and config hashes) when off: adding it changed no existing hash
    density_scaling: Annotated[Bool, Field(
        description=("static stages: rigid blocks stiffer for their mass than the median block "
                     "step with more mass, so the median block sets the time step (docs/dem.md "
                     "§10.4; the end state is an equilibrium, its path is not physical)"),
        exclude_if=lambda value: not value)] = False
    failure_displacement_m: Annotated[Optional[Float], Field(gt=0, le=1e6, description=(
        "displacement after which a block that keeps moving fails; none: a quarter of the "
        "rounding"))] = None
    failure_checks: Annotated[Int, Field(ge=1, le=1000, description=(
        "consecutive checks (500 steps apart) a failing block keeps moving"))] = 3
    sliver_area_m2: Annotated[Float, Field(ge=0, le=1e12, description=(
        "failing blocks smaller than this are slivers, left out of displacement measures"))] = 0.0
    energy_tolerance: Annotated[Float, Field(gt=0, le=1e6, description=(
        "energy-ledger residual, as a fraction of the energy turned over in a stage, that ends it "
        "as unstable"))] = 0.2

    @model_validator(mode="after")
    def _consistent(self):
        _check_settings(self)
        return self

    def step_safety(self, dynamic: bool) -> float:
        """The fraction of the stable step a stage uses: ``time_step_safety`` when given, else
        :data:`~rockmass.solver.tolerances.STATIC_STEP_SAFETY` (0.5: a static stage only has to
        reach equilibrium) or :data:`~rockmass.solver.tolerances.DYNAMIC_STEP_SAFETY` (0.2: the
        energy error of an impact grows as (ωΔt)², docs/dem.md §2.4).

        >>> s = Settings(joints={"default": Coulomb(1e9, 1e9, 30.0)}, stages=(Stage("s"),))
        >>> s.step_safety(False), s.step_safety(True)
        (0.5, 0.2)
        """
        if self.time_step_safety is not None:
            return self.time_step_safety
        return T.DYNAMIC_STEP_SAFETY if dynamic else T.STATIC_STEP_SAFETY


def same_history(a, b) -> bool:
    """Whether two velocity histories are the same function of time: the same object, or of one
    type and equal (the frozen history types compare by their settings; a plain callable by
    identity). An ``==`` that does not give a plain truth value, or raises, means not the same."""
    if a is b:
        return True
    if type(a) is not type(b):
        return False
    try:
        return (a == b) is True
    except Exception:  # any failure to compare: treat as different
        return False


def _check_reference_inputs(settings: Any, stage: Stage) -> None:
    """``rayleigh_reference="inputs"`` needs velocity inputs, and one history per component (the
    motion the damping is measured from)."""
    if not settings.velocity_inputs:
        raise field_error(settings, "stages", f"stage {stage.name!r}: rayleigh_reference = "
                          "'inputs' needs velocity_inputs", stage.rayleigh_reference)
    for component in ("x", "y"):
        histories = [inp.history for inp in settings.velocity_inputs if inp.component == component]
        if not all(same_history(histories[0], h) for h in histories[1:]):
            raise field_error(settings, "velocity_inputs", f"stage {stage.name!r}: rayleigh_"
                              f"reference = 'inputs' needs the {component} inputs to share one "
                              "history (the motion the damping is relative to)", component)


def _check_settings(settings: Any) -> None:
    """The cross-field rules of :class:`Settings`, for it and for anything with its fields (the
    ``[solve]`` section, :class:`rockmass.solve_config.SolveConfig`): a ``default`` joint model,
    unique stage and monitor names, bolts installed in stages of the run, elastic moduli for a boundary impedance that needs them, no
    side both quiet and free-field, one input history per
    component for damping relative to the inputs."""
    if "default" not in settings.joints:
        raise field_error(settings, "joints", "needs a 'default' joint model ([solve.joints."
                          "default]: used for any contact whose set or kind has none, and "
                          "for contacts formed during the run)", sorted(settings.joints))
    for field, items in (("stages", settings.stages), ("monitors", settings.monitors)):
        names = [item.name for item in items]
        if len(set(names)) != len(names):
            raise field_error(settings, field, f"names must be unique, got {names}", names)
    stage_names = [stage.name for stage in settings.stages]
    for field in ("bolts", "bolt_patterns"):
        for i, item in enumerate(getattr(settings, field, ())):
            if item.stage not in stage_names:
                raise field_error(settings, field, f"{field}[{i}].stage {item.stage!r} is not a "
                                  f"stage of the run ({', '.join(map(repr, stage_names))})",
                                  item.stage)
    for stage in settings.stages:
        if stage.kind == "dynamic" and stage.rayleigh_reference == "inputs":
            _check_reference_inputs(settings, stage)
    for field in ("quiet", "free_field"):
        boundary = getattr(settings, field, None)
        if boundary is None:
            continue
        speeds = boundary.p_wave_speed_m_s is not None and boundary.s_wave_speed_m_s is not None
        if boundary.impedance != "rock_mass" and not speeds and not settings.material.has_moduli:
            raise field_error(settings, field, f"impedance = {boundary.impedance!r} needs "
                              "material.bulk_modulus_pa and material.shear_modulus_pa (or both "
                              "wave speeds)", boundary.impedance)
    free_field = getattr(settings, "free_field", None)
    if free_field is not None and settings.quiet is not None:
        both = sorted(set(free_field.sides) & set(settings.quiet.sides))
        if both:
            raise field_error(settings, "free_field", f"sides {both} are also quiet sides (a "
                              "free-field side has its own dashpots)", both)
