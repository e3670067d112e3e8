"""Seeded generation of Poisson disk networks filled to a P32 target per fracture set.

A fracture set is a :class:`FractureSetSpec`: an orientation model (:class:`FisherOrientation`,
:class:`UniformOrientation`, :class:`BootstrapOrientation`), a size distribution of disk radii
(:mod:`rockmass.dfn.sizes`) and an intensity (:class:`IntensityP32`, or :class:`IntensityP10` along a
line, or :class:`IntensityP21` on a plane, converted to P32 with the set's C13 / C23,
:mod:`rockmass.dfn.stereology`). These are spec dataclasses (:func:`rockmass.dfn.specs.spec`) that
declare each parameter's range and description once, for Python calls and for the ``[[dfn.sets]]``
tables; :class:`BootstrapOrientation` (poles as an array) is a plain dataclass, given in a config
as planes (``rockmass.dfn_config.BootstrapConfig``).

Algorithm (docs/fractures.md §11.1)
-----------------------------------
For each set: draw radii first, then normals, then centres uniform in the domain box padded by the
largest radius r_max on every side (so the edges of the domain are not under-filled), in batches of
about the expected count; accumulate the *clipped* one-sided area of each disk in the domain
(:meth:`~rockmass.dfn.network.DiskNetwork.clipped_area_m2`) and stop at the first disk with which the
sum reaches P32 · V. Disks that do not reach into the domain are dropped. The achieved P32 exceeds the
target by less than one disk's area / V.

For a distribution without an upper truncation (lognormal, exponential) the padding is the radius
with survival probability 1e-9 (:data:`TAIL_PROBABILITY`); larger disks (one in 10⁹) are drawn but
centred no further out than that.

Seeding (docs/fractures.md §11.2, eqs. (11.2)-(11.3))
-----------------------------------------------------
Realization i of root seed s uses ``SeedSequence(s, spawn_key=(i,))`` — the child that
``SeedSequence(s).spawn(i + 1)[i]`` would be — and set j within it ``SeedSequence(s, spawn_key=(i, j))``.
Each is built directly from (s, i, j), so realization i is identical alone, in a batch, in any
order and on any worker. All draws are numpy; kernels run after. :func:`realization_seed` is the one
place this rule is written; every seeded draw of a realization in rockmass goes through it.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np
from numpy.typing import ArrayLike
from pydantic import Field, InstanceOf, Strict

from .fisher import sample_fisher
from .network import DiskNetwork, as_box, clipped_disk_areas
from .orientation import _as_vectors, pole_from_dip, vector_from_trend_plunge
from .sizes import ConstantSize, SizeDistribution, _check_size
from .specs import Float, Int, spec
from .stereology import c13, c23

__all__ = [
    "BootstrapOrientation",
    "DEFAULT_MAX_FRACTURES",
    "FisherOrientation",
    "FractureSetSpec",
    "IntensityP10",
    "IntensityP21",
    "IntensityP32",
    "UniformOrientation",
    "expected_counts",
    "generate",
    "realization_seed",
    "realizations",
    "size_upper_bound",
]

#: Default guard on the number of fractures one generation may need (all sets together).
DEFAULT_MAX_FRACTURES = 5_000_000
#: Survival probability that defines the padding radius of an untruncated size distribution.
TAIL_PROBABILITY = 1e-9


# -- orientation models ------------------------------------------------------------------------


@spec
class FisherOrientation:
    """Fisher-distributed poles about the pole of a mean plane (dip / dip direction, degrees).

    Parameters
    ----------
    dip_deg : float
        Mean dip, 0-90°.
    dip_direction_deg : float
        Mean dip direction, 0-360° clockwise from North.
    kappa : float
        Fisher concentration κ >= 0 (0: uniform).
    """

    dip_deg: Annotated[Float, Field(ge=0, le=90, description="dip of the mean plane")]
    dip_direction_deg: Annotated[Float, Field(ge=0, le=360, description="dip direction of the mean plane")]
    kappa: Annotated[Float, Field(ge=0, description="Fisher concentration κ (0: uniform)")]
    distribution: Annotated[Literal["fisher"], Field(
        description="orientation law: Fisher about a mean pole")] = "fisher"

    @property
    def mean_pole(self) -> np.ndarray:
        """Lower-hemisphere unit pole of the mean plane, (3,)."""
        return pole_from_dip(self.dip_deg, self.dip_direction_deg)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` unit normals, (n, 3)."""
        return sample_fisher(rng, self.mean_pole, self.kappa, n)

    def c13(self, line_direction: np.ndarray) -> float:
        return float(c13(line_direction, self.mean_pole, self.kappa))

    def c23(self, plane_normal: np.ndarray) -> float:
        return float(c23(plane_normal, self.mean_pole, self.kappa))


@spec
class UniformOrientation:
    """Isotropic normals (uniform on the sphere): C13 = 2, C23 = 4/π."""

    distribution: Annotated[Literal["uniform"], Field(
        description="orientation law: uniform on the sphere")] = "uniform"

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        return sample_fisher(rng, [0.0, 0.0, 1.0], 0.0, n)

    def c13(self, line_direction: np.ndarray) -> float:
        return float(c13(line_direction))

    def c23(self, plane_normal: np.ndarray) -> float:
        return float(c23(plane_normal))


@dataclass(frozen=True, eq=False)
class BootstrapOrientation:
    """Normals resampled with replacement from measured poles.

    Parameters
    ----------
    poles : (k, 3) array_like
        Measured poles or normals (any sign, normalised here), k >= 1.

    Notes
    -----
    C13 and C23 are those of the empirical distribution: 1 / mean |p·t| and 1 / mean sqrt(1 - (p·m)²).
    """

    poles: np.ndarray

    def __post_init__(self) -> None:
        poles = _as_vectors(self.poles, "poles")
        if poles.ndim != 2 or poles.shape[0] < 1:
            raise ValueError(f"poles must have shape (k, 3) with k >= 1, got {poles.shape}")
        poles.setflags(write=False)
        object.__setattr__(self, "poles", poles)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        return self.poles[rng.integers(0, self.poles.shape[0], n)]

    def c13(self, line_direction: np.ndarray) -> float:
        mean = float(np.mean(np.abs(self.poles @ line_direction)))
        if mean == 0:
            raise ValueError("the scanline is parallel to every bootstrap pole's plane: C13 is infinite")
        return 1.0 / mean

    def c23(self, plane_normal: np.ndarray) -> float:
        cos = np.clip(np.abs(self.poles @ plane_normal), 0.0, 1.0)
        mean = float(np.mean(np.sqrt(1.0 - cos ** 2)))
        if mean == 0:
            raise ValueError("the plane is parallel to every bootstrap pole's plane: C23 is infinite")
        return 1.0 / mean


Orientation = FisherOrientation | UniformOrientation | BootstrapOrientation


# -- intensities -------------------------------------------------------------------------------


Angle360 = Annotated[Float, Field(ge=0, le=360)]
Dip = Annotated[Float, Field(ge=0, le=90)]


def _value(what: str):
    """The intensity itself: > 0; its config key is ``value`` (the ``measure`` says which)."""
    return Annotated[Float, Field(gt=0, alias="value", description=what)]


class _Intensity:
    """Shared by the intensities: ``value`` is the intensity in its measure's unit, as the config
    key ``value`` gives it (the field named after the ``measure``)."""

    @property
    def value(self) -> float:
        return getattr(self, self.measure.lower())


@spec
class IntensityP32(_Intensity):
    """One-sided fracture area per volume P32 > 0 (m²/m³)."""

    p32: _value("P32, m²/m³")
    measure: Annotated[Literal["P32"], Field(
        description="intensity given as P32 (fracture area per volume)")] = "P32"

    def to_p32(self, orientation: Orientation) -> float:
        return self.p32


@spec
class IntensityP10(_Intensity):
    """P10 > 0 (1/m) along a scanline of trend / plunge (degrees); P32 = P10 · C13."""

    p10: _value("P10, 1/m")
    trend_deg: Annotated[Angle360, Field(description="trend of the line")]
    plunge_deg: Annotated[Float, Field(ge=-90, le=90, description="plunge of the line (down positive)")]
    measure: Annotated[Literal["P10"], Field(
        description="intensity given as P10 (fractures per metre of a line)")] = "P10"

    def to_p32(self, orientation: Orientation) -> float:
        line = vector_from_trend_plunge(self.trend_deg, self.plunge_deg)
        return self.p10 * orientation.c13(line)


@spec
class IntensityP21(_Intensity):
    """P21 > 0 (m/m²) on a sampling plane of dip / dip direction (degrees); P32 = P21 · C23."""

    p21: _value("P21, m/m²")
    dip_deg: Annotated[Dip, Field(description="dip of the plane")]
    dip_direction_deg: Annotated[Angle360, Field(description="dip direction of the plane")]
    measure: Annotated[Literal["P21"], Field(
        description="intensity given as P21 (trace length per area of a plane)")] = "P21"

    def to_p32(self, orientation: Orientation) -> float:
        return self.p21 * orientation.c23(pole_from_dip(self.dip_deg, self.dip_direction_deg))


Intensity = IntensityP32 | IntensityP10 | IntensityP21


@spec
class FractureSetSpec:
    """One fracture set: orientation, disk radius distribution, intensity and shape.

    Parameters
    ----------
    orientation : FisherOrientation, UniformOrientation or BootstrapOrientation
    size : ConstantSize, PowerLawSize, LognormalSize or ExponentialSize
        Disk radii in metres.
    intensity : IntensityP32, IntensityP10 or IntensityP21
    name : str, default ""
        Label used in messages and summaries.
    shape : {"disk"}, default "disk"
        Fracture shape (disks; exported as polygons).
    n_vertices : int, default 16
        Vertices of the polygon that stands for a disk in mesh export, 3-1024.
    """

    orientation: Annotated[FisherOrientation | UniformOrientation | InstanceOf[BootstrapOrientation], Field(
        description="orientation law (distribution = fisher, uniform or bootstrap)")]
    size: Annotated[SizeDistribution, Field(
        discriminator="distribution",
        description="radius law (distribution = constant, power_law, lognormal or exponential)")]
    intensity: Annotated[Intensity, Field(discriminator="measure",
                                          description="intensity (measure = P32, P10 or P21)")]
    name: Annotated[str, Strict(), Field(max_length=64, description="label in outputs")] = ""
    shape: Annotated[Literal["disk"], Field(description="fracture shape")] = "disk"
    n_vertices: Annotated[Int, Field(ge=3, le=1024,
                                     description="vertices of the polygon that stands for a disk")] = 16

    @property
    def p32(self) -> float:
        """Target one-sided P32 (m²/m³), converted from P10 / P21 with this set's C13 / C23."""
        return self.intensity.to_p32(self.orientation)

    @property
    def p30(self) -> float:
        """Expected disk centres per m³: P32 / (π E[r²])."""
        return self.p32 / (np.pi * self.size.moment(2.0))


# -- sizes ---------------------------------------------------------------------------------------


def size_upper_bound(size: object) -> float:
    """Largest radius to plan for: r_max when truncated, else the (1 - 1e-9) quantile (metres)."""
    _check_size(size)
    if isinstance(size, ConstantSize):
        return float(size.radius_m)
    if np.isfinite(size.r_max_m):
        return float(size.r_max_m)
    hi = max(size.mean(), 1e-300)
    while float(size.cdf(hi)) < 1.0 - TAIL_PROBABILITY:
        hi *= 2.0
    lo = hi / 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if float(size.cdf(mid)) < 1.0 - TAIL_PROBABILITY:
            lo = mid
        else:
            hi = mid
    return float(hi)


# -- seeding -------------------------------------------------------------------------------------


def _check_index(value: object, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {value!r}")
    if value < 0:
        raise ValueError(f"{name} must be >= 0, got {value}")
    return int(value)


def realization_seed(seed: int, realization: int, set_index: int | None = None) -> np.random.SeedSequence:
    """The SeedSequence of a realization (spawn key (i,)) or of one of its sets (spawn key (i, j)).

    This is rockmass's single seeding rule (docs/fractures.md §11.2, eqs. (11.2)-(11.3)):
    realization ``i`` of root seed ``s`` is ``SeedSequence(s, spawn_key=(i,))``, the child
    ``SeedSequence(s).spawn(i + 1)[i]`` would be, and set ``j`` within it is
    ``SeedSequence(s, spawn_key=(i, j))``. Each is built from (s, i, j) alone, so a realization is
    the same whether it is generated alone, in a batch, in any order or on any worker.

    Parameters
    ----------
    seed : int
        Root seed s >= 0.
    realization : int
        Realization index i >= 0.
    set_index : int, optional
        Fracture set index j >= 0 within the realization. Default None: the realization's own
        sequence.

    Returns
    -------
    numpy.random.SeedSequence
        Pass it to :func:`numpy.random.default_rng`. A caller that needs an integer seed for
        realization i (a config field, a worker argument) derives it from this sequence's
        ``generate_state``, so the integer follows the same rule.

    Raises
    ------
    ValueError, TypeError
        A negative or non-integer ``seed``, ``realization`` or ``set_index`` (the message names it).

    Examples
    --------
    >>> a = realization_seed(1, 3).generate_state(2)
    >>> b = np.random.SeedSequence(1).spawn(4)[3].generate_state(2)
    >>> bool((a == b).all())
    True
    """
    seed = _check_index(seed, "seed")
    realization = _check_index(realization, "realization")
    key = (realization,) if set_index is None else (realization, _check_index(set_index, "set_index"))
    return np.random.SeedSequence(seed, spawn_key=key)


def _check_sets(sets: Sequence[FractureSetSpec]) -> list[FractureSetSpec]:
    sets = list(sets) if not isinstance(sets, FractureSetSpec) else [sets]
    if not sets:
        raise ValueError("sets must hold at least one FractureSetSpec")
    for j, spec in enumerate(sets):
        if not isinstance(spec, FractureSetSpec):
            raise TypeError(f"sets[{j}] must be a FractureSetSpec, got {type(spec).__name__}")
    return sets


def _set_label(j: int, spec: FractureSetSpec) -> str:
    return f"sets[{j}]" + (f" ({spec.name})" if spec.name else "")


# -- generation ----------------------------------------------------------------------------------


def _fill_set(rng: np.random.Generator, spec: FractureSetSpec, box: np.ndarray, target_area: float,
              expected: float, limit: int, label: str):
    """Draw batches until the clipped area reaches ``target_area``; arrays of the kept disks."""
    pad = size_upper_bound(spec.size)
    lo, hi = box[0] - pad, box[1] + pad
    parts, total, drawn = [], 0.0, 0
    while True:
        n = int(np.ceil(1.02 * expected + 4.0 * np.sqrt(expected) + 16))
        if drawn + n > 2 * limit + 64:
            raise ValueError(f"{label}: more than {drawn} fractures drawn without reaching the P32 "
                             f"target; raise max_fractures (now {limit}) or lower the intensity")
        radius = spec.size.sample(rng, n)          # sizes first (docs/fractures.md §11.1)
        normal = spec.orientation.sample(rng, n)
        centre = lo + rng.random((n, 3)) * (hi - lo)
        area = clipped_disk_areas(centre, normal, radius, box)
        cum = total + np.cumsum(area)
        drawn += n
        if cum.size and cum[-1] >= target_area:
            k = int(np.searchsorted(cum, target_area, side="left")) + 1
            parts.append((centre[:k], normal[:k], radius[:k], area[:k]))
            break
        parts.append((centre, normal, radius, area))
        total = float(cum[-1]) if cum.size else total
        expected = max((target_area - total) / max(target_area, 1e-300) * expected, 1.0)
    centre, normal, radius, area = (np.concatenate(p) for p in zip(*parts))
    keep = area > 0
    return centre[keep], normal[keep], radius[keep]


def expected_counts(sets: Sequence[FractureSetSpec], domain_m: ArrayLike) -> np.ndarray:
    """Expected number of disks :func:`generate` draws for each set: P30 times the domain box
    padded by the set's largest radius (:func:`size_upper_bound`) on every side.

    Parameters
    ----------
    sets : sequence of FractureSetSpec
        The fracture sets.
    domain_m : (2, 3) or (6,) array_like of float
        Domain box in metres.

    Returns
    -------
    (n_sets,) ndarray of float64
        Expected counts, before any is drawn (budgets check them before work starts).

    Examples
    --------
    >>> spec = FractureSetSpec(FisherOrientation(45, 90, 20), ConstantSize(1.0), IntensityP32(0.5))
    >>> float(expected_counts([spec], [0, 0, 0, 10, 10, 10])[0] * np.pi)  # P30 = P32 / (pi r^2)
    864.0000000000001
    """
    box = as_box(domain_m)
    return np.array([spec.p30 * float(np.prod(box[1] - box[0] + 2 * size_upper_bound(spec.size)))
                     for spec in _check_sets(sets)], dtype=np.float64)


def generate(sets: Sequence[FractureSetSpec], domain_m: ArrayLike, *, seed: int, realization: int = 0,
             max_fractures: int = DEFAULT_MAX_FRACTURES) -> DiskNetwork:
    """One seeded realization of a Poisson disk network, each set filled to its clipped P32 target.

    Parameters
    ----------
    sets : sequence of FractureSetSpec
        The fracture sets; set j gets ``set_id`` j.
    domain_m : (2, 3) or (6,) array_like of float
        Domain box ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]`` in metres.
    seed : int
        Root seed >= 0.
    realization : int, default 0
        Realization index i >= 0 (spawn key (i,), see the module docstring).
    max_fractures : int, default 5,000,000
        Guard: the expected number of disks drawn (in the padded box, all sets) may not exceed it.

    Returns
    -------
    DiskNetwork
        Disks that reach into the domain, sets in order; ``domain_m`` the domain.

    Raises
    ------
    ValueError
        Bad domain, seed or realization, or a target needing more than ``max_fractures`` fractures
        (the message names the set and the number needed).

    Examples
    --------
    >>> spec = FractureSetSpec(FisherOrientation(45, 90, 20), ConstantSize(1.0), IntensityP32(0.5))
    >>> net = generate([spec], [0, 0, 0, 10, 10, 10], seed=1)
    >>> abs(net.p32() - 0.5) < np.pi / 1000 + 1e-12   # within one disk's area / V
    True
    """
    sets = _check_sets(sets)
    box = as_box(domain_m)
    limit = _check_index(max_fractures, "max_fractures")
    realization_seed(seed, realization)  # validates both
    volume = float(np.prod(box[1] - box[0]))
    plans = []
    needed_total = 0.0
    for j, (spec, expected) in enumerate(zip(sets, expected_counts(sets, box))):
        label = _set_label(j, spec)
        expected = float(expected)
        if expected > limit:
            raise ValueError(f"{label}: P32 = {spec.p32:.4g} m²/m³ in this domain needs about "
                             f"{expected:.3g} fractures, more than max_fractures = {limit}")
        needed_total += expected
        plans.append((label, spec, expected))
    if needed_total > limit:
        raise ValueError(f"all sets together need about {needed_total:.3g} fractures, more than "
                         f"max_fractures = {limit}")
    columns = []
    for j, (label, spec, expected) in enumerate(plans):
        rng = np.random.default_rng(realization_seed(seed, realization, j))
        centre, normal, radius = _fill_set(rng, spec, box, spec.p32 * volume, expected, limit, label)
        columns.append((centre, normal, radius, np.full(radius.size, j, dtype=np.int64)))
    centre, normal, radius, set_id = (np.concatenate(c) for c in zip(*columns))
    return DiskNetwork(centre, normal, radius, set_id, box)


def realizations(sets: Sequence[FractureSetSpec], domain_m: ArrayLike, seed: int,
                 indices: Iterable[int], *, max_fractures: int = DEFAULT_MAX_FRACTURES) -> Iterator[DiskNetwork]:
    """Yield :func:`generate` for each realization index in ``indices``, in that order.

    Realization i is the same network whatever else ``indices`` holds (module docstring).
    """
    for i in indices:
        yield generate(sets, domain_m, seed=seed, realization=i, max_fractures=max_fractures)
