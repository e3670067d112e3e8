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

:func:`compare_with_field` is the check of a realization against field data: it re-samples the
network with the field's own scanlines and faces and compares measured and re-sampled values, each
with a two-sample tolerance of 3 combined standard deviations:

- P10 of each scanline: hit counts are Poisson, sd = √(N_field + N_sim) / L;
- P21 of each face: sd² = Σ P21² (1 + CV²) / M over the two maps (M traces, CV of their lengths);
- mean (clipped) trace length of each face: sd² = Σ var(l) / M (same window, so the same censoring);
- mean pole of each set: angle <= 1.52 √(α95_field² + α95_sim²) (module table).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .field_fit import FaceSurvey, FieldFit, _trace_sample, fit_field
from .generation import FisherOrientation, FractureSetSpec, generate
from .network import DiskNetwork, _require_network
from .orientation import angle_between, dip_from_normal, trend_plunge_from_vector
from .sampling import sample_line, sample_plane
from .scanline import Scanline
from .sizes import ExponentialSize, LognormalSize, PowerLawSize

__all__ = ["ClosedLoop", "closed_loop", "compare_fit", "compare_with_field", "section_check", "virtual_face",
           "virtual_scanline"]

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
        Seeding of the generated network (docs/fractures.md §11.2).
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


def compare_with_field(network: DiskNetwork, field_fit: FieldFit, scanlines: Sequence[Scanline],
                       faces: Sequence[FaceSurvey]) -> list[dict]:
    """Measured vs re-sampled P10, P21, mean trace length and set orientations (module docstring).

    Parameters
    ----------
    network : DiskNetwork
        A realization generated from ``field_fit``.
    field_fit : FieldFit
        The fit of the field data.
    scanlines : sequence of Scanline
        The field scanlines, each with ``start_xyz_m``.
    faces : sequence of FaceSurvey
        The field faces, each with ``point_m``.

    Returns
    -------
    list of dict
        Rows ``set`` (the scanline or face label for P10 / P21 / length rows), ``quantity``, ``true``
        (measured), ``recovered`` (re-sampled), ``sd``, ``tolerance``, ``error`` and ``ok``.

    Raises
    ------
    ValueError
        A scanline without ``start_xyz_m`` or a face without ``point_m`` (their position is needed).
    """
    from .intensity import clipped_lengths_m

    _require_network(network)
    rows = []
    virtual_lines = []
    for k, line in enumerate(scanlines):
        label = line.source or f"scanline {k}"
        if line.start_xyz_m is None:
            raise ValueError(f"{label}: the scanline has no start point (start_xyz_m); it is needed to "
                             "re-sample a realization along it")
        end = line.start_xyz_m + line.length_m * line.direction
        sim = virtual_scanline(network, line.start_xyz_m, end)
        virtual_lines.append(sim)
        n_f, n_s = line.n_intersections, sim.n_intersections
        sd = float(np.sqrt(n_f + n_s)) / line.length_m
        rows.append(_row(label, "p10", n_f / line.length_m, n_s / line.length_m, sd, N_SIGMA * max(sd, 1 / line.length_m),
                         (n_s - n_f) / line.length_m))
    virtual_faces = []
    for j, face in enumerate(faces):
        label = face.name or f"face {j}"
        if face.point_m is None:
            raise ValueError(f"{label}: the face has no position (point_m); it is needed to re-sample a "
                             "realization on it")
        sim = virtual_face(network, face.point_m, face.normal, face.trace_map.window_xy_m, name=label)
        virtual_faces.append(sim)
        area = face.area_m2
        f, v = (_trace_sample(clipped_lengths_m(x.trace_map), area) for x in (face, sim))
        sd = float(np.hypot(f.p21_sd or 0.0, v.p21_sd or 0.0))
        rows.append(_row(label, "p21", f.p21, v.p21, sd, N_SIGMA * sd, v.p21 - f.p21))
        if f.mean_m is not None and v.mean_m is not None:
            sd_l = float(np.hypot(f.mean_sd or 0.0, v.mean_sd or 0.0))
            rows.append(_row(label, "mean_trace_length_m", f.mean_m, v.mean_m, sd_l, N_SIGMA * sd_l,
                             v.mean_m - f.mean_m))
    if sum(s.n_intersections for s in virtual_lines) >= 2:
        from .sets3d import fit_sets_3d

        poles = np.concatenate([s.poles() for s in virtual_lines])
        sim_sets = fit_sets_3d(poles, len(field_fit.sets))
        field_poles = np.array([s.mean_pole for s in field_fit.sets])
        for s, i in zip(field_fit.sets, _pairing(field_poles, sim_sets.mean_pole)):
            if i is None or sim_sets.fits[i] is None:
                continue
            angle = float(angle_between(s.mean_pole, sim_sets.mean_pole[i]))
            tol = POLE_TOLERANCE_FACTOR * float(np.hypot(s.alpha95_deg, sim_sets.fits[i].alpha95_deg))
            rows.append(_row(s.name, "mean_pole_deg", 0.0, angle, None, tol, angle))
    return rows


def section_check(network: DiskNetwork, specs: Sequence[FractureSetSpec], point: ArrayLike, normal: ArrayLike,
                  window_uv_m: ArrayLike) -> dict:
    """Traces of a realization on a plane: measured P21 against Σ_s P32_s / C23_s.

    The expected value is eq. (7.4) of docs/fractures.md §7.3 (Wang 2005).

    Parameters
    ----------
    network : DiskNetwork
        Generated from ``specs`` (set j of the network is ``specs[j]``).
    specs : sequence of FractureSetSpec
    point, normal : (3,) array_like
        The plane (origin of its (u, v) frame and its normal m).
    window_uv_m : (k, 2) array_like
        Window polygon in the plane frame.

    Returns
    -------
    dict
        ``traces``, ``area_m2``, ``p21`` (measured, m/m²), ``p21_expected`` (with each set's achieved
        P32 and its C23 for m), ``p21_sd`` (P21 √((1 + CV²)/M), M traces, CV of their clipped lengths),
        ``z`` = (measured − expected)/sd, ``mean_trace_length_m`` (clipped, window-censored) and the
        same per set under ``sets``. Undefined numbers are None.
    """
    from .intensity import clipped_lengths_m

    _require_network(network)
    face = virtual_face(network, point, normal, window_uv_m)
    area = face.area_m2
    lengths = np.asarray(clipped_lengths_m(face.trace_map))
    set_of = np.asarray(face.trace_map.attributes["set"])

    def stats(mask, expected):
        t = _trace_sample(lengths[mask], area)
        return {"traces": t.m, "p21": t.p21, "p21_expected": float(expected), "p21_sd": t.p21_sd,
                "z": None if not t.p21_sd else (t.p21 - expected) / t.p21_sd, "mean_trace_length_m": t.mean_m}

    m = face.normal
    expected = [network.p32(j) / spec.orientation.c23(m) for j, spec in enumerate(specs)]
    out = stats(np.ones(lengths.size, dtype=bool), sum(expected))
    out["area_m2"] = area
    out["sets"] = [dict(stats(set_of == j, e), set=j, name=spec.name) for j, (spec, e) in enumerate(zip(specs, expected))]
    return out
