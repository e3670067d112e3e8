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
from dataclasses import dataclass

import numpy as np

__all__ = ["JointSet", "SPACING_DISTRIBUTIONS", "set_segments"]

SPACING_DISTRIBUTIONS = ("constant", "exponential", "lognormal")


@dataclass(frozen=True)
class JointSet:
    """One joint set.

    Parameters
    ----------
    angle_deg : float
        Angle of the joints in the section, degrees counter-clockwise from +x; any finite value
        (taken modulo 180).
    spacing_m : float
        Mean spacing measured normal to the joints, > 0.
    spacing_distribution : {"constant", "exponential", "lognormal"}, default "constant"
    spacing_std_m : float, default 0
        Standard deviation of the lognormal spacing, >= 0.
    trace_length_m, gap_length_m : float, optional
        Joint length and rock-bridge length along each line (both > 0); None: persistent joints.
    origin_xy_m : (float, float), optional
        A point the set passes through; None: random offset from the generator.
    name : str, optional
        Label used in reports (default ``"set <index>"``).
    """

    angle_deg: float
    spacing_m: float
    spacing_distribution: str = "constant"
    spacing_std_m: float = 0.0
    trace_length_m: float | None = None
    gap_length_m: float | None = None
    origin_xy_m: tuple[float, float] | None = None
    name: str | None = None

    def __post_init__(self):
        _finite(self.angle_deg, "angle_deg")
        if not (_finite(self.spacing_m, "spacing_m") > 0):
            raise ValueError(f"spacing_m must be > 0 (joint spacing in metres), got {self.spacing_m!r}")
        if self.spacing_distribution not in SPACING_DISTRIBUTIONS:
            raise ValueError(f"spacing_distribution must be one of {SPACING_DISTRIBUTIONS}, "
                             f"got {self.spacing_distribution!r}")
        if not (_finite(self.spacing_std_m, "spacing_std_m") >= 0):
            raise ValueError(f"spacing_std_m must be >= 0, got {self.spacing_std_m!r}")
        if self.spacing_distribution == "lognormal" and self.spacing_std_m <= 0:
            raise ValueError("spacing_std_m must be > 0 for a lognormal spacing")
        if (self.trace_length_m is None) != (self.gap_length_m is None):
            raise ValueError("trace_length_m and gap_length_m must be given together (or neither)")
        for field in ("trace_length_m", "gap_length_m"):
            value = getattr(self, field)
            if value is not None and not (_finite(value, field) > 0):
                raise ValueError(f"{field} must be > 0, got {value!r}")
        if self.origin_xy_m is not None:
            if len(self.origin_xy_m) != 2:
                raise ValueError(f"origin_xy_m must be (x, y), got {self.origin_xy_m!r}")
            for v in self.origin_xy_m:
                _finite(v, "origin_xy_m")

    @property
    def persistent(self) -> bool:
        return self.trace_length_m is None


def _finite(value, name) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a number, got {value!r}") from exc
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return value


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
