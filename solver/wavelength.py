"""Are a dynamic stage's zones fine enough for the waves it carries? (docs/dem.md §16.9)

A zoning transmits a wave faithfully only if a zone is at most about a tenth of the wavelength
(Kuhlemeyer & Lysmer 1973; seed 001 §2 asks for λ/10–λ/8). The shortest wavelength a dynamic
stage carries is that of the S wave at the highest frequency of its velocity inputs,
λ = c_s / f_max, c_s = √(G/ρ). ``f_max`` is read off each input's spectrum: the frequency below
which :data:`ENERGY_FRACTION` of the input velocity's energy (its mean removed) lies over the
stage, from the history sampled at :data:`SAMPLES` points and zero-padded :data:`PADDING`-fold;
a sine gives its own frequency (:func:`highest_frequency_hz`).

:func:`wave_checks` gives, per dynamic stage and deformable entry, f_max, λ, the largest zone
edge h and the zones per wavelength λ/h; :func:`warn_coarse_zones` warns about those under
:data:`ZONES_PER_WAVELENGTH`. A run records the checks in ``Result.info["wave_checks"]``.

Reference: Kuhlemeyer, R. L., Lysmer, J. (1973). Finite element method accuracy for wave
propagation problems. Journal of the Soil Mechanics and Foundations Division (ASCE) 99(SM5),
421–427 (docs/dem.md, References).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = ["ENERGY_FRACTION", "PADDING", "SAMPLES", "ZONES_PER_WAVELENGTH", "highest_frequency_hz",
           "largest_zone_edges", "wave_checks", "warn_coarse_zones"]

ENERGY_FRACTION = 0.99
SAMPLES = 2 ** 18
PADDING = 4
ZONES_PER_WAVELENGTH = 10.0


def highest_frequency_hz(history, duration_s: float) -> float | None:
    """The frequency (Hz) below which ``ENERGY_FRACTION`` of the energy of ``history`` (a velocity
    history, any callable of a time array) lies over ``[0, duration_s]``: the one-sided power
    spectrum |V(f)|² of the sampled history with its mean removed (zero-padded ``PADDING``-fold,
    so that the bins are a fraction of the stage's own), accumulated from f = 0.
    None when the history is constant over the stage (it carries no wave). Content above the
    sampling's Nyquist frequency, ``SAMPLES / (2 duration_s)`` (131 kHz for a 1 s stage), is not
    seen.

    A :class:`~rockmass.solver.settings.Sine` or
    :class:`~rockmass.solver.settings.TableSine` gives its own frequency: the windowed sine's
    spectrum (its energy beyond the line falls as 1/f⁴, the motion starting and ending at rest)
    would put the 99 % point well above the line, energy of the start and the end rather than of
    the waves the stage is about."""
    from .settings import Sine, TableSine

    if isinstance(history, (Sine, TableSine)):
        return float(history.frequency_hz)
    t = np.linspace(0.0, duration_s, SAMPLES, endpoint=False)
    v = np.asarray(history(t), float)
    scale = np.abs(v).max()
    v = v - v.mean()
    if not np.abs(v).max() > 1e-12 * scale:
        return None  # constant (to round-off)
    n_fft = PADDING * SAMPLES  # zero-padded: bins of 1/(PADDING · duration)
    power = np.abs(np.fft.rfft(v, n_fft)) ** 2
    energy = np.cumsum(power)
    if not np.isfinite(energy[-1]) or energy[-1] <= 0.0:
        return None
    k = min(int(np.searchsorted(energy, ENERGY_FRACTION * energy[-1])), len(power) - 1)
    return float(np.fft.rfftfreq(n_fft, duration_s / SAMPLES)[k])


def largest_zone_edges(nodes: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(Z,) the longest edge of each triangular zone (m)."""
    corners = nodes[tri]
    edges = corners - np.roll(corners, -1, axis=1)
    return np.hypot(edges[..., 0], edges[..., 1]).max(axis=1)


def wave_checks(zoned, settings) -> list[dict]:
    """One row per dynamic stage with velocity inputs and per ``settings.deformable`` entry that
    zoned a block: ``stage``, ``deformable`` (the entry's index), ``f_max_hz``,
    ``shear_wave_speed_m_s``, ``wavelength_m`` (λ = c_s/f_max), ``zone_size_m`` (the largest zone
    edge h) and ``zones_per_wavelength`` (λ/h)."""
    from . import _kernels as K

    if zoned is None or not settings.velocity_inputs:
        return []
    edges = largest_zone_edges(zoned.nodes, zoned.tri)
    rho = settings.material.density_kg_m3
    rows = []
    for stage in settings.stages:
        if stage.kind != "dynamic":
            continue
        freqs = [highest_frequency_hz(vi.history, stage.duration_s)
                 for vi in settings.velocity_inputs]
        freqs = [f for f in freqs if f is not None and f > 0.0]
        if not freqs:
            continue
        f_max = max(freqs)
        for i in np.unique(zoned.zmat):
            c_s = math.sqrt(zoned.mtab[i, K.ZM_G] / rho)
            h = float(edges[zoned.zmat == i].max())
            rows.append({"stage": stage.name, "deformable": int(i), "f_max_hz": f_max,
                         "shear_wave_speed_m_s": c_s, "wavelength_m": c_s / f_max,
                         "zone_size_m": h, "zones_per_wavelength": c_s / f_max / h})
    return rows


def warn_coarse_zones(rows: list[dict]) -> None:
    """A ``UserWarning`` for each row of :func:`wave_checks` with fewer than
    ``ZONES_PER_WAVELENGTH`` zones per wavelength, naming the zone size that would do."""
    for r in rows:
        if r["zones_per_wavelength"] < ZONES_PER_WAVELENGTH:
            need = r["wavelength_m"] / ZONES_PER_WAVELENGTH
            warnings.warn(
                f"stage {r['stage']!r}: the zones of deformable[{r['deformable']}] are up to "
                f"{r['zone_size_m']:.3g} m, {r['zones_per_wavelength']:.2g} per shortest wavelength "
                f"(S wave λ = {r['wavelength_m']:.3g} m at f_max = {r['f_max_hz']:.3g} Hz); waves "
                f"that short are not carried faithfully (at least {ZONES_PER_WAVELENGTH:g} per "
                f"wavelength, Kuhlemeyer & Lysmer 1973): use zone_size_m <= {need:.3g} m",
                UserWarning, stacklevel=3)
