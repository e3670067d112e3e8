"""Fracture size distributions (disk radii) and the relations between radii, traces and intensities.

Each distribution is a small frozen spec dataclass (:func:`rockmass.dfn.specs.spec`: its annotations
carry each parameter's range and description, and a ``distribution`` tag, so that the size table of a
``[[dfn.sets]]`` entry is the class itself) with the same methods::

    sample(rng, n) -> (n,) float64     radii in metres, drawn with a caller-owned numpy Generator
    moment(k)      -> float            E[r^k] in m^k, closed form
    mean()         -> float            E[r]
    pdf(r), cdf(r)                     density (1/m) and distribution function, vectorised

:class:`ConstantSize`, :class:`PowerLawSize` (truncated, density ∝ r^-(α+1) on [r_min, r_max]),
:class:`LognormalSize` and :class:`ExponentialSize` (both optionally truncated). Every draw uses one
uniform per radius (inverse transform), so a sample is a deterministic function of the generator's
stream.

Relations for disks cut by a plane or a line (docs/fractures.md §10.2, eqs. (10.4)-(10.7);
[Zha02]_, [Pig97]_): P32 = P30 · π E[r²]; traces per
area P20 = P30 · 2 E[r] · E[sin ψ] = P30 · 2 E[r] / C23; mean trace length π E[r²] / (2 E[r])
(size-biased, independent of orientation); power-law density exponents of trace lengths and radii
a₂ = a₃ - 1.

References
----------
.. [Zha02] Zhang, L., Einstein, H. H., Dershowitz, W. S. (2002). Stereological relationship between
   trace length and size distribution of elliptical discontinuities. Géotechnique 52(6), 419-433.
   doi:10.1680/geot.2002.52.6.419
.. [Pig97] Piggott, A. R. (1997). Fractal relations for the diameter and trace length of disc-shaped
   fractures. Journal of Geophysical Research 102(B8), 18121-18125. doi:10.1029/97JB01202
.. [Dev86] Devroye, L. (1986). Non-Uniform Random Variate Generation. Springer, §II.2 (inversion).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import ArrayLike
from pydantic import BeforeValidator, Field, PlainSerializer, model_validator
from scipy.special import exprel, gamma, gammainc, gammaincc, ndtr, ndtri

from .orientation import _as_float_array, _as_nonnegative as _nonnegative, _as_scalar
from .specs import Float, FloatOrInf, field_error, spec
from .stereology import _as_constant

__all__ = [
    "ConstantSize",
    "ExponentialSize",
    "LognormalSize",
    "PowerLawSize",
    "SizeDistribution",
    "mean_trace_length",
    "p20_from_p30",
    "p30_from_p32",
    "p32_from_p30",
    "radius_exponent_from_trace",
    "trace_exponent_from_radius",
]

#: Smallest probability a truncation interval may hold: below it the inverse transform would work on
#: differences of nearly equal numbers and the distribution is not what the user means.
_MIN_MASS = 1e-12
#: Largest r_min / scale of a truncated exponential: its normalising constant e^(-r_min/scale) must
#: not underflow (e^-500 ~ 7e-218 still has full precision).
_MAX_EXPONENTIAL_SHIFT = 500.0


def _check_sample_args(rng: np.random.Generator, n: int) -> None:
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"n must be an integer, got {n!r}")
    if n < 0:
        raise ValueError(f"n must be >= 0 (number of radii), got {n}")


def _unbounded(value: Any) -> Any:
    """None (how a config dump writes "no upper truncation") as +inf."""
    return np.inf if value is None else value


def _no_limit_as_none(value: float) -> float | None:
    return None if value == np.inf else value


# the parameters of the size laws, declared once for Python calls and the [dfn] TOML tables
Radius = Annotated[Float, Field(gt=0)]
#: lower truncation radius, >= 0
RMin = Annotated[Float, Field(ge=0, description="lower truncation")]
#: upper truncation radius, > 0; +inf (written as none / omitted in a config) for no limit
RMax = Annotated[FloatOrInf, BeforeValidator(_unbounded), Field(gt=0),
                 PlainSerializer(_no_limit_as_none, when_used="json")]


def _check_truncation(size: Any) -> Any:
    """r_min_m < r_max_m (reported on r_min_m, as a config key path names it)."""
    if not size.r_min_m < size.r_max_m:
        raise field_error(size, "r_min_m", f"must be < r_max_m ({size.r_max_m}), got {size.r_min_m}",
                          size.r_min_m)
    return size


def _check_k(k: float) -> float:
    return _as_scalar(k, "k", what="order of the moment E[r^k]")


class _Size:
    """Shared methods: ``mean`` is the first moment."""

    def mean(self) -> float:
        """Mean radius E[r] in metres."""
        return self.moment(1.0)  # type: ignore[attr-defined]


@spec(type_errors=True)
class ConstantSize(_Size):
    """Every fracture has the same radius.

    Parameters
    ----------
    radius_m : float
        The radius in metres, > 0.

    Examples
    --------
    >>> size = ConstantSize(2.0)
    >>> size.moment(2), size.mean()
    (4.0, 2.0)
    """

    radius_m: Annotated[Radius, Field(description="disk radius")]
    distribution: Annotated[Literal["constant"], Field(description="size law: one radius")] = "constant"

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` copies of the radius (draws nothing from ``rng``)."""
        _check_sample_args(rng, n)
        return np.full(n, self.radius_m)

    def moment(self, k: float) -> float:
        """E[r^k] = radius^k."""
        return float(self.radius_m ** _check_k(k))

    def pdf(self, r_m: ArrayLike) -> np.ndarray:
        """A point mass: +inf at the radius and 0 elsewhere."""
        r = _as_float_array(r_m, "r_m")
        return np.where(r == self.radius_m, np.inf, 0.0)

    def cdf(self, r_m: ArrayLike) -> np.ndarray:
        """0 below the radius, 1 from it on."""
        return (_as_float_array(r_m, "r_m") >= self.radius_m).astype(np.float64)


def _log_exprel(x: np.ndarray) -> np.ndarray:
    """log((e^x - 1)/x), without overflow for large x and equal to 0 at x = 0."""
    positive = x > 0
    xp = np.where(positive, x, 1.0)
    large = xp + np.log(-np.expm1(-xp)) - np.log(xp)
    return np.where(positive, large, np.log(exprel(np.where(positive, 0.0, x))))


def _log1p_over(y: np.ndarray) -> np.ndarray:
    """log1p(y)/y for y > -1, equal to 1 at y = 0 (series 1 - y/2 + y²/3 for |y| < 1e-8)."""
    tiny = np.abs(y) < 1e-8
    safe = np.where(tiny, 1.0, y)
    return np.where(tiny, 1.0 - y / 2.0 + y * y / 3.0, np.log1p(safe) / safe)


@spec(type_errors=True)
class PowerLawSize(_Size):
    """Truncated power law of radii: density ∝ r^-(α+1) on [r_min, r_max].

    Parameters
    ----------
    r_min_m, r_max_m : float
        Truncation radii in metres, 0 < r_min_m < r_max_m < inf.
    alpha : float
        Exponent α >= 0 (the density exponent is a₃ = α + 1); α = 0 is the log-uniform law.

    Notes
    -----
    With Λ = ln(r_max/r_min) and exprel(x) = (e^x - 1)/x (exprel(0) = 1), the formulas of
    docs/fractures.md §10.1, eqs. (10.1)-(10.3), are written so that no α or k makes a 0/0:

    - pdf f(r) = α r_min^α r^-(α+1) / (1 - (r_min/r_max)^α) = (r_min/r)^α / (r Λ exprel(-αΛ));
    - cdf F(r) = (1 - (r_min/r)^α)/(1 - (r_min/r_max)^α) = ℓ exprel(-αℓ) / (Λ exprel(-αΛ)),
      ℓ = ln(r/r_min);
    - moments E[r^k] = α r_min^α (r_max^(k-α) - r_min^(k-α)) / ((1 - (r_min/r_max)^α)(k - α))
      = r_min^k exprel((k - α)Λ) / exprel(-αΛ), computed as exp of a sum of logs (no overflow
      for extreme ranges), which is continuous through k = α (E[r^α] = α r_min^α Λ / (1 - (r_min/r_max)^α))
      and α → 0 (log-uniform: E[r^k] = r_min^k exprel(kΛ));
    - sampling by inversion ([Dev86]_), r = r_min (1 - u + u (r_min/r_max)^α)^(-1/α), evaluated as
      ln(r/r_min) = uΛ exprel(-αΛ) · log1p(y)/y with y = u expm1(-αΛ) (= -ln(1 + y)/α), exact at α = 0
      (ln(r/r_min) = uΛ) and free of overflow for large α.

    Examples
    --------
    >>> size = PowerLawSize(r_min_m=1.0, r_max_m=10.0, alpha=2.0)
    >>> round(size.mean(), 6)              # 2 (1 - 1/10) / (1 - 1/100)
    1.818182
    >>> round(PowerLawSize(1.0, np.e, 0.0).moment(1.0), 6)   # log-uniform: (e - 1) / 1
    1.718282
    """

    r_min_m: Annotated[Radius, Field(description="smallest radius")]
    r_max_m: Annotated[FloatOrInf, Field(gt=0, description="largest radius")]
    alpha: Annotated[Float, Field(ge=0, description="exponent α of the radius density r^-(α+1)")]
    distribution: Annotated[Literal["power_law"], Field(
        description="size law: truncated power law of radii")] = "power_law"

    @model_validator(mode="after")
    def _truncated(self) -> PowerLawSize:
        if not np.isfinite(self.r_max_m):
            raise field_error(self, "r_max_m", f"must be finite for a truncated power law, got "
                              f"{self.r_max_m}", self.r_max_m)
        return _check_truncation(self)

    @property
    def density_exponent(self) -> float:
        """a₃ = α + 1, the exponent of the radius density r^-a₃."""
        return self.alpha + 1.0

    @property
    def _log_range(self) -> float:
        """Λ = ln(r_max/r_min), as a difference of logs so that extreme ratios do not overflow."""
        return float(np.log(self.r_max_m) - np.log(self.r_min_m))

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` radii by inversion (one uniform each)."""
        _check_sample_args(rng, n)
        u = rng.random(n)
        lam, alpha = self._log_range, self.alpha
        y = u * np.expm1(-alpha * lam)
        log_ratio = u * lam * exprel(-alpha * lam) * _log1p_over(y)
        return np.clip(np.exp(np.log(self.r_min_m) + log_ratio), self.r_min_m, self.r_max_m)

    def moment(self, k: float) -> float:
        """E[r^k] for any real k (closed form, see Notes)."""
        k = _check_k(k)
        lam, alpha = self._log_range, self.alpha
        log_value = k * np.log(self.r_min_m) + _log_exprel(np.float64((k - alpha) * lam)) \
            - _log_exprel(np.float64(-alpha * lam))
        with np.errstate(over="ignore"):
            return float(np.exp(log_value))

    def pdf(self, r_m: ArrayLike) -> np.ndarray:
        """Density in 1/m; 0 outside [r_min, r_max]."""
        r = _as_float_array(r_m, "r_m")
        inside = (r >= self.r_min_m) & (r <= self.r_max_m)
        safe = np.where(inside, r, self.r_min_m)
        value = (self.r_min_m / safe) ** self.alpha / (safe * self._log_range * exprel(-self.alpha * self._log_range))
        return np.where(inside, value, 0.0)

    def cdf(self, r_m: ArrayLike) -> np.ndarray:
        """Distribution function; 0 below r_min, 1 above r_max."""
        r = _as_float_array(r_m, "r_m")
        lam = self._log_range
        ell = np.clip(np.log(np.clip(r, self.r_min_m, self.r_max_m)) - np.log(self.r_min_m), 0.0, lam)
        value = ell * exprel(-self.alpha * ell) / (lam * exprel(-self.alpha * lam))
        return np.clip(value, 0.0, 1.0)


def _normal_mass(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Φ(b) - Φ(a) for a <= b, from the tail where both terms are small (no cancellation of ~1)."""
    return np.where(a > 0, ndtr(-a) - ndtr(-b), ndtr(b) - ndtr(a))


@spec(type_errors=True)
class LognormalSize(_Size):
    """Lognormal radii given by their mean and standard deviation, optionally truncated.

    Parameters
    ----------
    mean_m, sd_m : float
        Mean and standard deviation of the (untruncated) lognormal radius in metres, both > 0. Then
        ln r ~ N(μ, σ²) with σ² = ln(1 + (sd/mean)²) and μ = ln(mean) - σ²/2.
    r_min_m : float, default 0.0
        Lower truncation radius, >= 0.
    r_max_m : float, default inf
        Upper truncation radius, > r_min_m. With truncation, ``mean()`` and ``moment()`` are those of
        the truncated law, not ``mean_m`` and ``sd_m``.

    Notes
    -----
    With z(r) = (ln r - μ)/σ, a = z(r_min), b = z(r_max) and M = Φ(b) - Φ(a):
    E[r^k] = exp(kμ + k²σ²/2) (Φ(b - kσ) - Φ(a - kσ)) / M; sampling by inversion,
    z = Φ⁻¹(Φ(a) + uM) (computed from the upper tail, z = -Φ⁻¹(Φ(-a) - uM), when a > 0 so that
    truncation far in the upper tail keeps its precision). A truncation interval holding less than
    1e-12 of the probability is an error.

    Examples
    --------
    >>> size = LognormalSize(mean_m=2.0, sd_m=1.0)
    >>> round(size.mean(), 12), round(size.moment(2) - size.mean() ** 2, 12)
    (2.0, 1.0)
    """

    mean_m: Annotated[Radius, Field(description="mean radius")]
    sd_m: Annotated[Radius, Field(description="standard deviation of the radius")]
    r_min_m: RMin = 0.0
    r_max_m: Annotated[RMax, Field(description="upper truncation; none: no limit")] = np.inf
    distribution: Annotated[Literal["lognormal"], Field(description="size law: lognormal radii")] = \
        "lognormal"

    @model_validator(mode="after")
    def _mass_left(self) -> LognormalSize:
        _check_truncation(self)
        mass = float(_normal_mass(*self._bounds_z()))
        if not mass >= _MIN_MASS:
            raise field_error(self, "r_min_m", f"and r_max_m [{self.r_min_m}, {self.r_max_m}] hold {mass:.3g} "
                              f"of the lognormal probability (< {_MIN_MASS:g}): widen the truncation "
                              f"interval", self.r_min_m)
        return self

    @property
    def _sigma(self) -> float:
        return float(np.sqrt(np.log1p((self.sd_m / self.mean_m) ** 2)))

    @property
    def _mu(self) -> float:
        return float(np.log(self.mean_m) - self._sigma ** 2 / 2.0)

    def _z(self, r: np.ndarray) -> np.ndarray:
        """(ln r - μ)/σ, -inf at r <= 0 and +inf at r = inf (no warnings)."""
        positive = r > 0
        finite = np.isfinite(r)
        safe = np.where(positive & finite, r, 1.0)
        z = (np.log(safe) - self._mu) / self._sigma
        return np.where(positive, np.where(finite, z, np.inf), -np.inf)

    def _bounds_z(self) -> tuple[np.ndarray, np.ndarray]:
        return self._z(np.float64(self.r_min_m)), self._z(np.float64(self.r_max_m))

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` radii by inversion (one uniform each)."""
        _check_sample_args(rng, n)
        u = rng.random(n)
        a, b = self._bounds_z()
        mass = _normal_mass(a, b)
        if a > 0:
            z = -ndtri(ndtr(-a) - u * mass)
        else:
            z = ndtri(ndtr(a) + u * mass)
        return np.clip(np.exp(self._mu + self._sigma * z), self.r_min_m, self.r_max_m)

    def moment(self, k: float) -> float:
        """E[r^k] for any real k (closed form, see Notes)."""
        k = _check_k(k)
        a, b = self._bounds_z()
        shift = k * self._sigma
        ratio = _normal_mass(a - shift, b - shift) / _normal_mass(a, b)
        with np.errstate(over="ignore"):
            return float(np.exp(k * self._mu + (k * self._sigma) ** 2 / 2.0) * ratio)

    def pdf(self, r_m: ArrayLike) -> np.ndarray:
        """Density in 1/m; 0 outside [r_min, r_max] and at r <= 0."""
        r = _as_float_array(r_m, "r_m")
        inside = (r >= self.r_min_m) & (r <= self.r_max_m) & (r > 0)
        safe = np.where(inside, r, 1.0)
        z = self._z(safe)
        value = np.exp(-z * z / 2.0) / (safe * self._sigma * np.sqrt(2.0 * np.pi) * _normal_mass(*self._bounds_z()))
        return np.where(inside, value, 0.0)

    def cdf(self, r_m: ArrayLike) -> np.ndarray:
        """Distribution function; 0 below r_min, 1 above r_max."""
        r = np.clip(_as_float_array(r_m, "r_m"), self.r_min_m, self.r_max_m)
        a, b = self._bounds_z()
        return np.clip(_normal_mass(a, np.maximum(self._z(r), a)) / _normal_mass(a, b), 0.0, 1.0)


@spec(type_errors=True)
class ExponentialSize(_Size):
    """Exponential radii, optionally truncated to [r_min, r_max].

    Parameters
    ----------
    scale_m : float
        Scale s in metres, > 0: the mean of the untruncated law (density e^(-r/s)/s).
    r_min_m : float, default 0.0
        Lower truncation radius, 0 <= r_min_m <= 500 s (the exponential is memoryless, so this is
        r_min_m plus an exponential truncated at r_max_m - r_min_m).
    r_max_m : float, default inf
        Upper truncation radius, > r_min_m.

    Notes
    -----
    With x = r/s and Δ = (r_max - r_min)/s: pdf e^(-(r - r_min)/s) / (s (1 - e^(-Δ))), cdf
    expm1(-(r - r_min)/s)/expm1(-Δ), sampling r = r_min - s log1p(u expm1(-Δ)) (Δ = ∞ included),
    and for k > -1

        E[r^k] = s^k Γ(k + 1) (Q(k + 1, x_min) - Q(k + 1, x_max)) e^(x_min) / (1 - e^(-Δ))

    with Q the regularised upper incomplete gamma function; the difference is taken as
    P(k + 1, x_max) - P(k + 1, x_min) when x_min < k + 1 (both small there). A truncation interval
    much narrower than s loses relative precision in that difference (~ machine epsilon · s / width).

    Examples
    --------
    >>> size = ExponentialSize(scale_m=2.0)
    >>> size.mean(), size.moment(2)
    (2.0, 8.0)
    >>> round(ExponentialSize(2.0, r_min_m=1.0).mean(), 12)   # memoryless: 1 + 2
    3.0
    """

    scale_m: Annotated[Radius, Field(description="mean of the untruncated law")]
    r_min_m: RMin = 0.0
    r_max_m: Annotated[RMax, Field(description="upper truncation; none: no limit")] = np.inf
    distribution: Annotated[Literal["exponential"], Field(
        description="size law: exponential radii")] = "exponential"

    @model_validator(mode="after")
    def _normalisable(self) -> ExponentialSize:
        _check_truncation(self)
        if self.r_min_m > _MAX_EXPONENTIAL_SHIFT * self.scale_m:
            raise field_error(self, "r_min_m", f"must be <= {_MAX_EXPONENTIAL_SHIFT:g} * scale_m = "
                              f"{_MAX_EXPONENTIAL_SHIFT * self.scale_m:g} (the truncated exponential's "
                              f"normalising constant underflows), got {self.r_min_m}", self.r_min_m)
        return self

    @property
    def _width(self) -> float:
        """Δ = (r_max - r_min)/s (may be inf)."""
        return (self.r_max_m - self.r_min_m) / self.scale_m

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` radii by inversion (one uniform each)."""
        _check_sample_args(rng, n)
        u = rng.random(n)
        r = self.r_min_m - self.scale_m * np.log1p(u * np.expm1(-self._width))
        return np.clip(r, self.r_min_m, self.r_max_m)

    def moment(self, k: float) -> float:
        """E[r^k] for real k > -1 (closed form, see Notes)."""
        k = _as_scalar(k, "k", low=-1.0, low_open=True, what="order of the moment E[r^k], k > -1")
        s, x_min = self.scale_m, self.r_min_m / self.scale_m
        x_max = self.r_max_m / self.scale_m
        if not np.isfinite(x_max):
            tail = gammaincc(k + 1.0, x_min)
        elif x_min < k + 1.0:
            tail = gammainc(k + 1.0, x_max) - gammainc(k + 1.0, x_min)
        else:
            tail = gammaincc(k + 1.0, x_min) - gammaincc(k + 1.0, x_max)
        with np.errstate(over="ignore"):
            return float(s ** k * gamma(k + 1.0) * tail * np.exp(x_min) / -np.expm1(-self._width))

    def pdf(self, r_m: ArrayLike) -> np.ndarray:
        """Density in 1/m; 0 outside [r_min, r_max]."""
        r = _as_float_array(r_m, "r_m")
        inside = (r >= self.r_min_m) & (r <= self.r_max_m)
        excess = np.where(inside, r - self.r_min_m, 0.0) / self.scale_m
        return np.where(inside, np.exp(-excess) / (self.scale_m * -np.expm1(-self._width)), 0.0)

    def cdf(self, r_m: ArrayLike) -> np.ndarray:
        """Distribution function; 0 below r_min, 1 above r_max."""
        r = np.clip(_as_float_array(r_m, "r_m"), self.r_min_m, self.r_max_m)
        return np.clip(np.expm1(-(r - self.r_min_m) / self.scale_m) / np.expm1(-self._width), 0.0, 1.0)


SizeDistribution = ConstantSize | PowerLawSize | LognormalSize | ExponentialSize


def _check_size(size: object) -> None:
    if not isinstance(size, (ConstantSize, PowerLawSize, LognormalSize, ExponentialSize)):
        raise TypeError(f"size must be one of ConstantSize, PowerLawSize, LognormalSize, ExponentialSize, "
                        f"got {type(size).__name__}")


def mean_trace_length(size: SizeDistribution) -> float:
    """Mean length of the traces that disks of this radius distribution leave on a plane, in metres.

    Returns
    -------
    float
        π E[r²] / (2 E[r]). A disk of radius r is cut by the plane with probability ∝ r (size bias),
        and a random chord at offset d has length 2 sqrt(r² - d²) with d uniform on [0, r], mean
        πr/2; hence E[r · πr/2]/E[r]. Independent of orientation ([Zha02]_).

    Examples
    --------
    >>> round(mean_trace_length(ConstantSize(1.0)), 6)       # π/2
    1.570796
    """
    _check_size(size)
    return float(np.pi * size.moment(2.0) / (2.0 * size.moment(1.0)))


def p32_from_p30(p30: ArrayLike, size: SizeDistribution) -> np.ndarray:
    """P32 = P30 · π E[r²] (m²/m³, one-sided) of disks with ``p30`` centres per m³.

    Examples
    --------
    >>> round(float(p32_from_p30(1.0, ConstantSize(1.0))), 6)
    3.141593
    """
    _check_size(size)
    return _nonnegative(p30, "p30", "fractures per cubic metre") * (np.pi * size.moment(2.0))


def p30_from_p32(p32: ArrayLike, size: SizeDistribution) -> np.ndarray:
    """P30 = P32 / (π E[r²]) (1/m³): number density of disks giving one-sided intensity ``p32``.

    Examples
    --------
    >>> round(float(p30_from_p32(np.pi, ConstantSize(1.0))), 12)
    1.0
    """
    _check_size(size)
    return _nonnegative(p32, "p32", "fracture area per volume, m²/m³") / (np.pi * size.moment(2.0))


def p20_from_p30(p30: ArrayLike, size: SizeDistribution, c23_value: ArrayLike) -> np.ndarray:
    """Traces per unit area P20 = P30 · 2 E[r] / C23 on a plane cutting a disk network.

    Parameters
    ----------
    p30 : float or array_like
        Disk centres per m³, >= 0.
    size : size distribution
        Radius distribution of the disks.
    c23_value : float or array_like
        C23 of the set for the plane (:func:`rockmass.dfn.stereology.c23`), >= 1; E[sin ψ] = 1/C23.

    Returns
    -------
    ndarray
        P20 in 1/m²: a disk of radius r at angle ψ to the plane is cut when its centre lies within
        r sin ψ of it, so P20 = P30 · E[2 r sin ψ] = P30 · 2 E[r] E[sin ψ] (radius and orientation
        independent).

    Examples
    --------
    >>> round(float(p20_from_p30(1.0, ConstantSize(1.0), 4.0 / np.pi)), 6)   # isotropic: π/2
    1.570796
    """
    _check_size(size)
    c = _as_constant(c23_value, "c23_value")
    return _nonnegative(p30, "p30", "fractures per cubic metre") * (2.0 * size.moment(1.0)) / c


def trace_exponent_from_radius(radius_exponent: float) -> float:
    """Power-law density exponent of trace lengths a₂ = a₃ - 1 from that of disk radii a₃.

    Parameters
    ----------
    radius_exponent : float
        a₃ >= 1 with radius density ∝ r^-a₃ (a₃ = α + 1 for :class:`PowerLawSize`).

    Returns
    -------
    float
        a₂ = a₃ - 1, the exponent of the trace-length density on a plane ([Pig97]_; size-biased
        sampling of the disks removes one power).

    Examples
    --------
    >>> trace_exponent_from_radius(3.5)
    2.5
    """
    return _as_scalar(radius_exponent, "radius_exponent", low=1.0,
                      what="density exponent of disk radii, pdf ∝ r^-a3") - 1.0


def radius_exponent_from_trace(trace_exponent: float) -> float:
    """Power-law density exponent of disk radii a₃ = a₂ + 1 from that of trace lengths a₂ >= 0.

    Examples
    --------
    >>> radius_exponent_from_trace(2.5)
    3.5
    """
    return _as_scalar(trace_exponent, "trace_exponent", low=0.0,
                      what="density exponent of trace lengths, pdf ∝ l^-a2") + 1.0
