"""Joint sets in the UDEC style: straight joints at an angle, spaced normal to themselves.

A set is the family of lines at angle β (degrees counter-clockwise from +x, 0 <= β < 180) whose
offsets along the unit normal n = (−sin β, cos β) are p₀, p₀ + s₁, p₀ + s₁ + s₂, …, covering the
domain. The spacings sᵢ are constant or drawn from a distribution (exponential, lognormal) with mean
``spacing_m``. p₀ comes from ``origin_xy_m`` (the set passes through that point) or, when it is None,
is drawn uniformly in [0, s) from the seeded generator. Persistence: with ``trace_length_m`` each
line is cut into joints of that length separated by rock bridges of ``gap_length_m``, starting at a
random phase along the line (UDEC ``jset`` trace/gap); without it joints are persistent.
"""

from __future__ import annotations

import math
import typing
from typing import Annotated, Literal, Optional

import numpy as np
from pydantic import Field, Strict, ValidationInfo, field_validator

from ..dfn.specs import Float, spec

__all__ = ["JointSet", "SPACING_DISTRIBUTIONS", "set_segments", "joint_set_segments",
           "seed_sequence"]

SpacingDistribution = Literal["constant", "exponential", "lognormal"]
SPACING_DISTRIBUTIONS = typing.get_args(SpacingDistribution)


_Length = Annotated[Float, Field(gt=0, le=1e6)]
_Coord = Annotated[Float, Field(ge=-1e7, le=1e7)]


@spec
class JointSet:
    """One joint set.

    A frozen pydantic dataclass: the annotations below declare each parameter's type, range and
    description once, for Python callers and for the ``[[blocks.sets]]`` TOML tables
    (:mod:`rockmass.blocks_config` uses this class as the table type). A bad value raises
    ``pydantic.ValidationError`` (a ``ValueError``) naming the field.

    Parameters
    ----------
    angle_deg : float
        Angle of the joints in the section, degrees counter-clockwise from +x, -360 to 360
        (taken modulo 180).
    spacing_m : float
        Mean spacing measured normal to the joints, > 0.
    spacing_distribution : {"constant", "exponential", "lognormal"}, default "constant"
    spacing_std_m : float, default 0
        Standard deviation of the lognormal spacing, >= 0 (> 0 for a lognormal spacing).
    trace_length_m, gap_length_m : float, optional
        Joint length and rock-bridge length along each line (both > 0); None: persistent joints.
    origin_xy_m : (float, float), optional
        A point the set passes through; None: random offset from the generator.
    name : str, optional
        Label used in reports (default ``"set <index>"``).
    """

    angle_deg: Annotated[Float, Field(
        ge=-360, le=360, description="angle of the joints, counter-clockwise from +x")]
    spacing_m: Annotated[_Length, Field(description="mean spacing normal to the joints")]
    spacing_distribution: Annotated[SpacingDistribution, Field(
        description="law of the spacings (mean spacing_m)")] = "constant"
    spacing_std_m: Annotated[Float, Field(
        ge=0, le=1e6, description="standard deviation of a lognormal spacing")] = 0.0
    trace_length_m: Annotated[Optional[_Length], Field(
        description="joint length along a line (with gap_length_m); none: persistent")] = None
    gap_length_m: Annotated[Optional[_Length], Field(
        description="rock-bridge length between joints of a line (with trace_length_m)")] = None
    origin_xy_m: Annotated[Optional[tuple[_Coord, _Coord]], Field(
        description="a point the set passes through; none: a random offset")] = None
    name: Annotated[Optional[str], Strict(), Field(
        min_length=1, max_length=64, description="label in reports; none: \"set <index>\"")] = None

    @field_validator("spacing_std_m")
    @classmethod
    def _lognormal_has_spread(cls, value: float, info: ValidationInfo) -> float:
        if info.data.get("spacing_distribution") == "lognormal" and value <= 0:
            raise ValueError("must be > 0 for a lognormal spacing")
        return value

    @field_validator("gap_length_m")
    @classmethod
    def _persistence_pair(cls, value: float | None, info: ValidationInfo) -> float | None:
        if "trace_length_m" in info.data and (info.data["trace_length_m"] is None) != (value is None):
            raise ValueError("trace_length_m and gap_length_m go together (persistence); give "
                             "both or neither")
        return value

    @property
    def persistent(self) -> bool:
        return self.trace_length_m is None


def _spacings(js: JointSet, n: int, rng: np.random.Generator) -> np.ndarray:
    if js.spacing_distribution == "constant":
        return np.full(n, js.spacing_m)
    if js.spacing_distribution == "exponential":
        return rng.exponential(js.spacing_m, n)
    m, s = js.spacing_m, js.spacing_std_m  # lognormal with this mean and standard deviation
    sigma2 = math.log1p((s / m) ** 2)
    return rng.lognormal(math.log(m) - sigma2 / 2, math.sqrt(sigma2), n)


def set_segments(js: JointSet, domain_xy_m: np.ndarray, rng: np.random.Generator,
                 index: int = 0) -> np.ndarray:
    """Joint segments of one set clipped to the domain's bounding box (extended by one spacing).

    Returns
    -------
    (n, 2, 2) float64
        Segment end points; the caller clips them to the domain polygon.
    """
    beta = math.radians(js.angle_deg % 180.0)
    d = np.array([math.cos(beta), math.sin(beta)])
    nrm = np.array([-d[1], d[0]])
    proj_n = domain_xy_m @ nrm
    proj_d = domain_xy_m @ d
    pmin, pmax = proj_n.min(), proj_n.max()
    tmin, tmax = proj_d.min() - js.spacing_m, proj_d.max() + js.spacing_m
    if js.origin_xy_m is not None:
        p0 = float(np.asarray(js.origin_xy_m, float) @ nrm)
        phase0 = float(np.asarray(js.origin_xy_m, float) @ d)
    else:
        p0 = pmin + rng.uniform(0.0, js.spacing_m)
        phase0 = None
    # offsets covering [pmin, pmax]: walk down from p0 then up
    if js.spacing_distribution == "constant":
        k0 = math.ceil((pmin - p0) / js.spacing_m)
        k1 = math.floor((pmax - p0) / js.spacing_m)
        offsets = p0 + js.spacing_m * np.arange(k0, k1 + 1)
    else:
        n_est = int((pmax - pmin) / js.spacing_m * 3) + 16
        up = p0 + np.concatenate([[0.0], np.cumsum(_spacings(js, n_est, rng))])
        down = p0 - np.cumsum(_spacings(js, n_est, rng))
        while up[-1] < pmax:
            up = np.concatenate([up, up[-1] + np.cumsum(_spacings(js, n_est, rng))])
        while down[-1] > pmin:
            down = np.concatenate([down, down[-1] - np.cumsum(_spacings(js, n_est, rng))])
        offsets = np.sort(np.concatenate([down, up]))
        offsets = offsets[(offsets >= pmin) & (offsets <= pmax)]
    if js.persistent:
        starts = np.full(offsets.size, tmin)
        ends = np.full(offsets.size, tmax)
    else:
        period = js.trace_length_m + js.gap_length_m
        phase = (rng.uniform(0.0, period, offsets.size) if phase0 is None
                 else np.full(offsets.size, phase0))
        k0 = np.floor((tmin - phase) / period)
        n_per = int(math.ceil((tmax - tmin) / period)) + 2
        s = phase[:, None] + (k0[:, None] + np.arange(n_per)[None, :]) * period
        e = s + js.trace_length_m
        offsets = np.repeat(offsets, n_per)
        starts, ends = s.ravel(), e.ravel()
        keep = (ends > tmin) & (starts < tmax)
        offsets, starts, ends = offsets[keep], starts[keep], ends[keep]
    a = offsets[:, None] * nrm + starts[:, None] * d
    b = offsets[:, None] * nrm + ends[:, None] * d
    return np.stack([a, b], axis=1)


def seed_sequence(seed) -> np.random.SeedSequence:
    """The root :class:`numpy.random.SeedSequence` of a block model: ``seed`` itself when it is one,
    else ``SeedSequence(seed)``."""
    return seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)


def joint_set_segments(joint_sets, domain_xy_m, seed=0) -> list[np.ndarray]:
    """The joints of every set, drawn exactly as :func:`rockmass.blockgen.build` draws them.

    The seeding rule lives here only: set ``i`` draws from the generator of child ``i`` of
    ``SeedSequence(seed)`` (``SeedSequence(seed).spawn(len(joint_sets))[i]``); the builder's
    potential cracks take child ``len(joint_sets)``. A caller that needs the joints of a model
    (the box count of a study) calls this with the model's sets, domain and seed.

    Parameters
    ----------
    joint_sets : sequence of JointSet
        The sets, in the order given to ``build``.
    domain_xy_m : (k, 2) array_like of float
        Domain outline in metres, as given to ``build`` (a closing vertex is ignored).
    seed : int or numpy.random.SeedSequence, default 0
        The model's root seed; a SeedSequence spawns its next ``len(joint_sets)`` children.

    Returns
    -------
    list of (n_i, 2, 2) float64
        Per set, its joint segments clipped to the domain's bounding box extended by one spacing
        (:func:`set_segments`); the builder then snaps them to its grid and clips them to the
        domain polygon.

    Examples
    --------
    >>> sets = [JointSet(0.0, 1.0), JointSet(90.0, 2.0)]
    >>> a = joint_set_segments(sets, [(0, 0), (4, 0), (4, 4), (0, 4)], seed=3)
    >>> b = joint_set_segments(sets, [(0, 0), (4, 0), (4, 4), (0, 4)], seed=3)
    >>> [len(s) for s in a], all(np.array_equal(x, y) for x, y in zip(a, b))
    ([4, 2], True)
    """
    from .excavations import _as_ring

    domain_xy = _as_ring(domain_xy_m, "domain_xy_m")
    joint_sets = list(joint_sets)
    children = seed_sequence(seed).spawn(len(joint_sets)) if joint_sets else []
    return [set_segments(js, domain_xy, np.random.default_rng(child), i)
            for i, (js, child) in enumerate(zip(joint_sets, children))]
