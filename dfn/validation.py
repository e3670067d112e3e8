"""Closed loop: generate a network with known sets, sample it like the field, re-fit, compare.

:func:`virtual_scanline` and :func:`virtual_face` turn line and plane samples of a
:class:`~rockmass.dfn.network.DiskNetwork` into the same objects the field readers make
(:class:`~rockmass.dfn.scanline.Scanline`, :class:`~rockmass.dfn.field_fit.FaceSurvey`), so the
re-fit runs exactly the code that fits field data (:func:`~rockmass.dfn.field_fit.fit_field`).
:func:`closed_loop` reports, per set, the true and recovered parameters with a tolerance from their
sampling error and pass / fail:

=================  ==========================================================================
quantity           tolerance (about 99.9 % two-sided when the fit's error model holds)
=================  ==========================================================================
mean pole          angle <= 1.52 α95: the mean of N Fisher poles is Fisher with concentration
                   ≈ Nκ, so P(angle > t) = exp(−Nκ(1 − cos t)); α95 solves this for 0.05 and
                   t for 0.001 is α95 √(ln 1000 / ln 20) = 1.52 α95 (small angles)
κ                  |κ̂ − κ| <= 3 sd, sd = κ̂ / √(N − 1) (2κ(N − R) ~ χ²(2N − 2))
P32                |P̂32 − P32| <= 3 sd of :func:`~rockmass.dfn.stereology.solve_p32` (Poisson
                   counts); "true" is the P32 the realization achieved for the set
size parameters    |θ̂ − θ| <= 3 sd of the likelihood fit (:mod:`~rockmass.dfn.size_fit`)
=================  ==========================================================================

True and recovered sets are paired by the permutation with the smallest sum of angles between
mean poles.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .field_fit import FaceSurvey, FieldFit, fit_field
from .generation import FisherOrientation, FractureSetSpec, generate
from .network import DiskNetwork, _require_network
from .orientation import angle_between, dip_from_normal, trend_plunge_from_vector
from .sampling import sample_line, sample_plane
from .scanline import Scanline
from .sizes import ExponentialSize, LognormalSize, PowerLawSize

__all__ = ["ClosedLoop", "closed_loop", "virtual_face", "virtual_scanline"]

#: α95 multiple of the mean-pole tolerance (module docstring): sqrt(ln 1000 / ln 20).
POLE_TOLERANCE_FACTOR = float(np.sqrt(np.log(1000.0) / np.log(20.0)))
#: Standard deviations allowed for κ, P32 and size parameters.
N_SIGMA = 3.0


def virtual_scanline(network: DiskNetwork, start: ArrayLike, end: ArrayLike) -> Scanline:
    """A :class:`Scanline` survey of ``network`` along the segment ``start`` → ``end`` (metres).

    The dip / dip direction of each hit is that of the disk's normal; trend / plunge of the line and
    ``start_xyz_m`` are set, so the result can be written and read back like a field survey.

    Examples
    --------
    >>> net = DiskNetwork([[0, 0, 1]], [[0, 0, 1]], [1.0], [0], [-5, -5, 0, 5, 5, 5])
    >>> s = virtual_scanline(net, [0, 0, 0], [0, 0, 4])
    >>> s.distance_m.tolist(), s.dip_deg.tolist(), s.plunge_deg, s.length_m
    ([1.0], [0.0], -90.0, 4.0)
    """
    _require_network(network)
    hits = sample_line(network, start, end)
    dip, dd = dip_from_normal(network.normal[hits.disk_index].reshape(-1, 3))
    trend, plunge = trend_plunge_from_vector(hits.direction)
    return Scanline(hits.position_m, np.atleast_1d(dip), np.atleast_1d(dd), float(trend), float(plunge),
                    hits.length_m, start_xyz_m=np.asarray(start, dtype=float))


def virtual_face(network: DiskNetwork, point: ArrayLike, normal: ArrayLike, window_uv_m: ArrayLike,
                 name: str = "") -> FaceSurvey:
    """A :class:`FaceSurvey` of ``network``: its traces on the plane (``point``, ``normal``) in the window."""
    trace_map = sample_plane(network, point, normal, window_uv_m)
    return FaceSurvey(trace_map, normal, point, name)


@dataclass(frozen=True)
class ClosedLoop:
    """Result of :func:`closed_loop`.

    Attributes
    ----------
    rows : tuple of dict
        One row per (set, quantity): ``set``, ``quantity``, ``true``, ``recovered``, ``sd``,
        ``tolerance``, ``error`` (recovered − true, or the angle for the mean pole) and ``ok``.
    fit : FieldFit
        The re-fit.
    network : DiskNetwork
        The generated network.
    n_hits : int
        Scanline intersections in all.
    n_traces : int
        Face traces in all.
    """

    rows: tuple
    fit: FieldFit
    network: DiskNetwork
    n_hits: int
    n_traces: int

    @property
    def ok(self) -> bool:
        return all(r["ok"] for r in self.rows)

    def as_dict(self) -> dict:
        def clean(v):
            if isinstance(v, (bool, np.bool_)):
                return bool(v)
            if isinstance(v, (int, float, np.floating, np.integer)):
                return float(v) if np.isfinite(v) else None
            return v
        return {"ok": self.ok, "n_hits": self.n_hits, "n_traces": self.n_traces,
                "rows": [{k: clean(v) for k, v in r.items()} for r in self.rows]}


def _pairing(true_poles: np.ndarray, fitted_poles: np.ndarray) -> list[int | None]:
    """For each true set, the index of its fitted set (None when there are fewer fitted sets)."""
    k_true, k_fit = len(true_poles), len(fitted_poles)
    angles = angle_between(true_poles[:, None, :], fitted_poles[None, :, :])
    best, best_cost = None, np.inf
    for perm in itertools.permutations(range(k_fit), min(k_true, k_fit)):
        cost = sum(angles[i, j] for i, j in enumerate(perm))
        if cost < best_cost:
            best, best_cost = perm, cost
    pairing = list(best) + [None] * (k_true - len(best))
    return pairing


def _size_truth(size) -> dict:
    if isinstance(size, PowerLawSize):
        return {"alpha": size.alpha, "r_min_m": size.r_min_m}
    if isinstance(size, LognormalSize):
        return {"mean_m": size.mean_m, "sd_m": size.sd_m}
    if isinstance(size, ExponentialSize):
        return {"scale_m": size.scale_m}
    return {}


def _row(set_name: str, quantity: str, true: float, recovered: float, sd: float | None, tolerance: float,
         error: float) -> dict:
    ok = bool(np.isfinite(error) and np.isfinite(tolerance) and abs(error) <= tolerance)
    return {"set": set_name, "quantity": quantity, "true": float(true), "recovered": float(recovered),
            "sd": float("nan") if sd is None else float(sd), "tolerance": float(tolerance),
            "error": float(error), "ok": ok}


def compare_fit(fit: FieldFit, specs: Sequence[FractureSetSpec], network: DiskNetwork) -> list[dict]:
    """Rows of true vs recovered parameters (module docstring) for a fit of ``network`` made from ``specs``."""
    true_poles = np.array([spec.orientation.mean_pole for spec in specs])
    fitted = np.array([s.mean_pole for s in fit.sets])
    rows = []
    for j, (spec, i) in enumerate(zip(specs, _pairing(true_poles, fitted))):
        name = spec.name or f"set {j}"
        achieved = network.p32(j)
        if i is None:
            rows.append(_row(name, "found", 1, 0, None, 0.5, 1.0))
            continue
        got = fit.sets[i]
        angle = float(angle_between(true_poles[j], got.mean_pole))
        rows.append(_row(name, "mean_pole_deg", 0.0, angle, None, POLE_TOLERANCE_FACTOR * got.alpha95_deg, angle))
        if isinstance(spec.orientation, FisherOrientation):
            kappa = spec.orientation.kappa
            rows.append(_row(name, "kappa", kappa, got.kappa, got.kappa_sd, N_SIGMA * got.kappa_sd, got.kappa - kappa))
        rows.append(_row(name, "p32", achieved, got.p32, got.p32_sd, N_SIGMA * got.p32_sd, got.p32 - achieved))
        if got.size is not None and got.size.ok and got.size.family == _family_of(spec.size):
            for key, value in _size_truth(spec.size).items():
                sd = got.size.sd.get(key)
                tol = N_SIGMA * sd if sd is not None else float("nan")
                rows.append(_row(name, f"size.{key}", value, got.size.params[key], sd, tol,
                                 got.size.params[key] - value))
        elif got.size is not None:
            rows.append(_row(name, "size.family", 1, 0, None, 0.5, 1.0))
    return rows


def _family_of(size) -> str | None:
    return {PowerLawSize: "power_law", LognormalSize: "lognormal", ExponentialSize: "exponential"}.get(type(size))


def closed_loop(specs: Sequence[FractureSetSpec], domain_m: ArrayLike, *, scanlines: Sequence[tuple],
                faces: Sequence[tuple] = (), seed: int = 0, realization: int = 0, size_family: str | None = None,
                r_max_m: float | None = None, max_fractures: int = 5_000_000) -> ClosedLoop:
    """Generate a network from known sets, sample it like the field, re-fit it and compare.

    Parameters
    ----------
    specs : sequence of FractureSetSpec
        The true sets (Fisher or uniform orientations; P32, P10 or P21 intensities).
    domain_m : (2, 3) array_like
        Generation domain, metres.
    scanlines : sequence of (start, end)
        Scanline end points (metres, inside the domain).
    faces : sequence of (point, normal, window_uv_m)
        Sampling planes with their convex windows (plane frame of
        :func:`~rockmass.dfn.sampling.plane_frame`).
    seed, realization : int
        Seeding of the generated network (DESIGN.md §3).
    size_family : str, optional
        Family to fit; default the family of the first set's size law.
    r_max_m : float, optional
        Power-law upper truncation used in the fit; default the largest true r_max (or 100 m).
    max_fractures : int, default 5,000,000
        Guard of :func:`~rockmass.dfn.generation.generate`.

    Returns
    -------
    ClosedLoop
        ``rows`` of true vs recovered values with tolerances (module docstring) and ``ok``.
    """
    specs = list(specs)
    network = generate(specs, domain_m, seed=seed, realization=realization, max_fractures=max_fractures)
    surveys = [virtual_scanline(network, a, b) for a, b in scanlines]
    face_surveys = [virtual_face(network, p, m, w, name=f"face {k}") for k, (p, m, w) in enumerate(faces)]
    family = size_family or _family_of(specs[0].size) or "best"
    if r_max_m is None:
        r_max_m = max([getattr(s.size, "r_max_m", 0.0) for s in specs if np.isfinite(getattr(s.size, "r_max_m", np.inf))]
                      or [100.0])
    fit = fit_field(surveys, face_surveys, n_sets=len(specs), size_family=family, r_max_m=r_max_m)
    rows = compare_fit(fit, specs, network)
    return ClosedLoop(tuple(rows), fit, network, sum(s.n_intersections for s in surveys),
                      sum(f.trace_map.n_traces for f in face_surveys))
