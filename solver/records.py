"""Band-limited synthetic table motions: an earthquake-like input when the record itself is missing
(docs/dem.md §9.2, eq. (9.2a)–(9.2c)).

A pass of duration T is the table displacement

    u(t) = s w(t) g(t),   g(t) = Σ_k A_k/(2π f_k)² sin(2π f_k t + φ_k),   0 ≤ t ≤ T,        (9.2a)

on the frequencies f_k = k/T of the pass. A_k is the Fourier amplitude of the acceleration g″:
1 inside the band [f_lo, f_hi], falling as cos²(π x/2) over x = log₂(f_lo/f) or log₂(f/f_hi)
octaves of a roll-off outside it, 0 beyond (a flat acceleration spectrum inside the band, the shape
a record's Fourier amplitude takes between its corner frequencies). The phases φ_k are uniform on
[0, 2π) from ``numpy.random.default_rng(seed)``: the same seed gives the same record. The window
w is a Tukey window: 1 in the middle, ½(1 − cos(π t/τ)) over the first and last τ = r T, so the
table starts and ends each pass at rest at its origin,

    u(0) = u(T) = 0,   v(0) = v(T) = 0   (w and w′ vanish at both ends).                       (9.2b)

The scale s makes the largest |u| over the pass D (``peak="displacement"``) or the largest
|a| = |u″| over the pass a_max (``peak="acceleration"``), both found on a grid of 64 points per
period of f_max (the largest f_k), refined by a bounded search around the largest samples and
checked at the window's kinks. The velocity and acceleration are the exact derivatives,

    v = s (w′g + w g′),   a = s (w″g + 2w′g′ + w g″).                                         (9.2c)

w″ jumps at 0, τ, T − τ and T (by ½(π/τ)²), so the acceleration jumps there by s ½(π/τ)² g(t):
the table starts each pass with a step of acceleration, as a record cut out of a longer one does.

Passes repeat the same record back to back (each starts and ends at rest), as a shake-table test
replays one scaled record cycle after cycle (Varma et al. 2019 §4: "a single cycle of the scaled
Mexico earthquake loading lasting 10 s").

The sum is evaluated directly (no FFT): exact at any time, so the solver can sample it at its own
half steps. Its cost is one sine and one cosine per component and time; a 10 s pass with a band
of 0.6–6 Hz and one octave of roll-off has 116 components (0.4–11.9 Hz).
"""

from __future__ import annotations

import functools

import numpy as np

__all__ = ["band_amplitudes", "band_problem", "record_components", "tukey_window", "record_motion"]

GRID_PER_PERIOD = 64  # samples per period of the highest component when the peak is searched
REFINED = 8  # largest grid samples whose neighbourhood is searched for the exact peak
BLOCK_SINES = 2 ** 20  # times × components evaluated together (memory of the sine arrays)
MAX_COMPONENTS = 20_000  # a record longer or wider than this is refused (its cost per time)
MAX_PHASES = 1_000_000  # phases drawn, one per k/T up to the band's top (8 MB)


def band_amplitudes(f: np.ndarray, f_lo: float, f_hi: float, rolloff_octaves: float) -> np.ndarray:
    """Fourier amplitude A(f) of the acceleration: 1 on [f_lo, f_hi], cos²(π x/2) over
    x = log₂(f_lo/f) (below) or log₂(f/f_hi) (above) for x < ``rolloff_octaves`` (as a fraction of
    it), 0 beyond (eq. (9.2a))."""
    f = np.asarray(f, float)
    x = np.zeros_like(f)
    below, above = f < f_lo, f > f_hi
    x[below] = np.log2(f_lo / f[below])
    x[above] = np.log2(f[above] / f_hi)
    if rolloff_octaves <= 0.0:
        return np.where(below | above, 0.0, 1.0)
    y = x / rolloff_octaves
    return np.where(y < 1.0, np.cos(0.5 * np.pi * y) ** 2, 0.0)


def tukey_window(t: np.ndarray, duration_s: float, taper_fraction: float) -> tuple[np.ndarray, ...]:
    """(w, w′, w″) of the Tukey window over [0, T]: ½(1 − cos(π t/τ)) for t < τ, the mirror for
    t > T − τ, 1 between, τ = ``taper_fraction`` T (0 outside [0, T])."""
    t = np.asarray(t, float)
    w, dw, d2w = np.ones_like(t), np.zeros_like(t), np.zeros_like(t)
    tau = taper_fraction * duration_s
    if tau > 0.0:
        for s, sign in ((t, 1.0), (duration_s - t, -1.0)):
            edge = s < tau
            c = np.pi / tau
            w[edge] = 0.5 * (1.0 - np.cos(c * s[edge]))
            dw[edge] = sign * 0.5 * c * np.sin(c * s[edge])
            d2w[edge] = 0.5 * c * c * np.cos(c * s[edge])
    outside = (t < 0.0) | (t > duration_s)
    for a in (w, dw, d2w):
        a[outside] = 0.0
    return w, dw, d2w


def band_problem(f_lo: float, f_hi: float, rolloff_octaves: float, duration_s: float,
                 seed: int) -> str | None:
    """What is wrong with a band for passes of ``duration_s`` (None: nothing): the phases drawn
    up to its top, one per frequency k/T, must stay under MAX_PHASES (checked first, without
    building anything); then it must hold at least one frequency k/T with A_k > 0 and at most
    MAX_COMPONENTS (:func:`record_components`, whose arrays the record then uses)."""
    if not 0 < f_lo < f_hi:
        return "expected 0 < f_lo < f_hi"
    top = f_hi * 2.0 ** rolloff_octaves
    if top * duration_s > MAX_PHASES:
        return (f"its top, {top:g} Hz, lies {top * duration_s:.3g} frequencies k/T up (at most "
                f"{MAX_PHASES}): a lower band or a shorter pass")
    count = len(record_components(f_lo, f_hi, rolloff_octaves, duration_s, seed)[0])
    if count == 0:
        return f"the band and its roll-off hold no frequency k/T of a pass (T = {duration_s:g} s)"
    if count > MAX_COMPONENTS:
        return (f"{count} frequencies k/T in the band and its roll-off (at most {MAX_COMPONENTS}): "
                "a narrower band or a shorter pass")
    return None


@functools.lru_cache(maxsize=32)
def record_components(f_lo: float, f_hi: float, rolloff_octaves: float, duration_s: float,
                      seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(f_k, A_k, φ_k) of eq. (9.2a): the frequencies k/T whose amplitude is not 0, their
    acceleration amplitudes, and their phases from ``default_rng(seed)`` (one uniform draw per
    frequency k/T up to the band's end, so the phases of a frequency do not depend on the band
    below it). Read-only arrays (cached)."""
    f_top = f_hi * 2.0 ** max(rolloff_octaves, 0.0)
    k = np.arange(1, int(np.ceil(f_top * duration_s)) + 1)
    f = k / duration_s
    phases = np.random.default_rng(seed).uniform(0.0, 2.0 * np.pi, len(k))
    amp = band_amplitudes(f, f_lo, f_hi, rolloff_octaves)
    keep = amp > 0.0
    out = (f[keep], amp[keep], phases[keep])
    for a in out:
        a.setflags(write=False)
    return out


def _unit_motion(t, f, amp, phases, duration_s, taper_fraction, order: int) -> np.ndarray:
    """Derivative ``order`` (0: u, 1: v, 2: a) of w g (s = 1) at times ``t`` within one pass."""
    t = np.asarray(t, float)
    w = tukey_window(t, duration_s, taper_fraction)
    omega = 2.0 * np.pi * f
    arg = np.multiply.outer(t, omega) + phases
    s = np.sin(arg)
    b = amp / omega ** 2
    g = s @ b
    if order == 0:
        return w[0] * g
    g1 = np.cos(arg) @ (b * omega)
    if order == 1:
        return w[1] * g + w[0] * g1
    g2 = -(s @ amp)
    return w[2] * g + 2.0 * w[1] * g1 + w[0] * g2


def _evaluate(t, f, amp, phases, duration_s, taper_fraction, order: int) -> np.ndarray:
    """:func:`_unit_motion` over any number of times, in blocks of at most ~2²⁰ sines."""
    rows = max(1, BLOCK_SINES // len(f))
    return np.concatenate([_unit_motion(t[i:i + rows], f, amp, phases, duration_s,
                                        taper_fraction, order) for i in range(0, len(t), rows)]
                          or [np.zeros(0)])


@functools.lru_cache(maxsize=64)
def _unit_peak(f_lo, f_hi, rolloff_octaves, duration_s, taper_fraction, seed, order: int) -> float:
    """max |u| (``order`` 0) or max |a| (``order`` 2) of one pass with s = 1. The motion is sampled
    on a grid of GRID_PER_PERIOD points per period of the highest component; around the REFINED
    largest samples the peak is then searched (scipy's bounded scalar search) between their
    neighbours, on each side of any kink of the window in between (w″ jumps at 0, τ, T − τ and T,
    so a has kinks there), and the kinks themselves are candidates."""
    from scipy.optimize import minimize_scalar

    f, amp, phases = record_components(f_lo, f_hi, rolloff_octaves, duration_s, seed)
    tau = taper_fraction * duration_s
    kinks = np.array([0.0, tau, duration_s - tau, duration_s])
    n = int(np.ceil(GRID_PER_PERIOD * f[-1] * duration_s)) + 1
    t = np.linspace(0.0, duration_s, n)

    def size(x):
        return float(abs(_unit_motion(np.array([x]), f, amp, phases, duration_s, taper_fraction,
                                      order)[0]))

    y = np.abs(_evaluate(t, f, amp, phases, duration_s, taper_fraction, order))
    best = max(size(k) for k in kinks)
    for i in np.argsort(y)[::-1][:REFINED]:
        lo, hi = t[max(i - 1, 0)], t[min(i + 1, n - 1)]
        cuts = [lo, *kinks[(kinks > lo) & (kinks < hi)], hi]
        for a, b in zip(cuts[:-1], cuts[1:]):
            found = minimize_scalar(lambda x: -size(x), bounds=(a, b), method="bounded",
                                    options={"xatol": 1e-9 * duration_s})
            best = max(best, -float(found.fun), size(a), size(b))
    return best


def record_motion(t, *, f_lo: float, f_hi: float, rolloff_octaves: float, duration_s: float,
                  taper_fraction: float, seed: int, passes: int, peak: str, peak_value: float,
                  order: int = 1) -> np.ndarray:
    """Displacement (``order`` 0), velocity (1) or acceleration (2) of the table at times ``t``
    (eqs. (9.2a)–(9.2c)): ``passes`` passes of the record back to back from t = 0, scaled so that
    its peak displacement (``peak="displacement"``) or acceleration (``"acceleration"``) is
    ``peak_value``; 0 before t = 0 and after the last pass."""
    f, amp, phases = record_components(f_lo, f_hi, rolloff_octaves, duration_s, seed)
    scale = peak_value / _unit_peak(f_lo, f_hi, rolloff_octaves, duration_s, taper_fraction, seed,
                                    0 if peak == "displacement" else 2)
    t = np.asarray(t, float)
    flat = t.ravel()
    out = np.zeros_like(flat)
    inside = (flat >= 0.0) & (flat <= passes * duration_s)
    local = np.mod(flat[inside], duration_s)  # the pass's own time (g is T-periodic, w is not:
    local[(local == 0.0) & (flat[inside] > 0.0)] = duration_s  # a pass's end is its t = T)
    out[inside] = scale * _evaluate(local, f, amp, phases, duration_s, taper_fraction, order)
    return out.reshape(t.shape)
