"""The band-limited synthetic table motion (docs/dem.md §9.2, eqs. (9.2a)–(9.2c)): at rest at the
start and end of every pass, the peak it is scaled to, derivatives consistent with each other, a
flat acceleration spectrum on its band, passes that repeat, seeds that reproduce."""

from __future__ import annotations

import numpy as np
import pytest

from rockmass.solver import BandRecord
from rockmass.solver.records import band_amplitudes, tukey_window

T = 4.0  # a short pass keeps the tests fast


def record(**kw) -> BandRecord:
    args = dict(band_hz=(1.0, 8.0), duration_s=T, peak_value=0.01, passes=2, seed=3)
    args.update(kw)
    return BandRecord(**args)


def grid(h: BandRecord, per_second: int = 20_000) -> np.ndarray:
    return np.linspace(0.0, h.passes * h.duration_s, int(per_second * h.passes * h.duration_s) + 1)


def test_each_pass_starts_and_ends_at_rest():
    h = record(passes=3)
    ends = np.array([0.0, T, 2 * T, 3 * T])
    t = grid(h, 2_000)
    assert np.abs(h.displacement(ends)).max() < 1e-12 * np.abs(h.displacement(t)).max()
    assert np.abs(h(ends)).max() < 1e-12 * np.abs(h(t)).max()


def test_zero_outside_the_passes():
    h = record()
    t = np.array([-1.0, -1e-9, 2 * T + 1e-9, 2 * T + 5.0])
    for motion in (h.displacement, h, h.acceleration):
        assert not motion(t).any()


@pytest.mark.parametrize("peak, value", [("displacement", 0.0155), ("acceleration", 4.6)])
@pytest.mark.parametrize("seed", [3, 9, 17, 28])
def test_scaled_to_its_peak(peak, value, seed):
    """The largest |u| or |a| on a dense grid (and at the window's kinks, where the acceleration
    of seed 9 peaks) is the value asked for."""
    h = record(peak=peak, peak_value=value, passes=1, seed=seed)
    tau = h.taper_fraction * T
    t = np.concatenate([grid(h, 50_000), [tau, T - tau]])
    motion = h.displacement(t) if peak == "displacement" else h.acceleration(t)
    assert np.abs(motion).max() == pytest.approx(value, rel=2e-4)


def test_velocity_and_acceleration_are_the_derivatives():
    h = record(passes=1)
    t = grid(h, 40_000)
    dt = t[1] - t[0]
    u, v, a = h.displacement(t), h(t), h.acceleration(t)
    u_of_v = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])
    assert np.abs(u_of_v - u).max() < 1e-6 * np.abs(u).max()
    # central differences, away from the kinks of w″ at τ and T − τ and the ends
    tau = h.taper_fraction * T
    smooth = (np.abs(t - tau) > 1e-3) & (np.abs(t - (T - tau)) > 1e-3) & (t > 1e-3) & (t < T - 1e-3)
    dv = np.gradient(v, dt)
    assert np.abs(dv - a)[smooth].max() < 1e-4 * np.abs(a).max()


def test_passes_repeat_the_same_record():
    h = record(passes=3)
    t = np.linspace(0.0, T, 2001)
    for k in (1, 2):
        np.testing.assert_allclose(h(t + k * T), h(t), rtol=0, atol=1e-12 * np.abs(h(t)).max())


def test_seed_reproduces_and_changes_the_record():
    t = np.linspace(0.0, T, 1001)
    np.testing.assert_array_equal(record(seed=5)(t), record(seed=5)(t))
    assert np.abs(record(seed=5)(t) - record(seed=6)(t)).max() > 1e-3 * np.abs(record(seed=5)(t)).max()


def test_acceleration_spectrum_is_flat_on_the_band():
    """The Fourier amplitude of one pass's acceleration: as flat across the band (each third of
    it within 15 % of the band's mean), and all but a little of its energy within the band and
    its roll-off."""
    h = BandRecord(band_hz=(1.0, 8.0), duration_s=20.0, peak_value=1.0, seed=11,
                   rolloff_octaves=1.0, taper_fraction=0.05)
    n = 2 ** 18
    t = np.linspace(0.0, 20.0, n, endpoint=False)
    spectrum = np.abs(np.fft.rfft(h.acceleration(t)))
    f = np.fft.rfftfreq(n, t[1])
    band = (f >= 1.2) & (f <= 7.0)
    mean = np.sqrt(np.mean(spectrum[band] ** 2))
    edges = np.linspace(1.2, 7.0, 4)
    for lo, hi in zip(edges[:-1], edges[1:]):
        part = (f >= lo) & (f <= hi)
        assert np.sqrt(np.mean(spectrum[part] ** 2)) == pytest.approx(mean, rel=0.15)
    energy = spectrum ** 2
    inside = (f >= 0.5) & (f <= 16.0)
    assert energy[inside].sum() > 0.99 * energy.sum()


def test_band_amplitudes_and_window_closed_forms():
    f = np.array([0.25, 0.5, 1.0 / np.sqrt(2.0), 1.0, 3.0, 8.0, 16.0 / np.sqrt(2.0), 16.0, 32.0])
    np.testing.assert_allclose(band_amplitudes(f, 1.0, 8.0, 1.0),
                               [0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 0.5, 0.0, 0.0], atol=1e-12)
    w, dw, d2w = tukey_window(np.array([0.0, 0.05, 0.1, 0.5, 0.95, 1.0]), 1.0, 0.1)
    np.testing.assert_allclose(w, [0.0, 0.5, 1.0, 1.0, 0.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(dw, [0.0, 0.5 * np.pi / 0.1, 0.0, 0.0, -0.5 * np.pi / 0.1, 0.0],
                               atol=1e-9)
    assert d2w[0] == pytest.approx(0.5 * (np.pi / 0.1) ** 2)


@pytest.mark.parametrize("kw, field", [({"band_hz": (5.0, 2.0)}, "band_hz"),
                                       ({"band_hz": (0.01, 0.1), "duration_s": 2.0}, "band_hz"),
                                       ({"peak_value": 0.0}, "peak_value"),
                                       ({"passes": 0}, "passes"),
                                       ({"taper_fraction": 0.6}, "taper_fraction"),
                                       ({"band_hz": (0.62, 0.68), "duration_s": 10.0,
                                         "rolloff_octaves": 0.0}, "no frequency"),
                                       ({"band_hz": (0.6, 6e3)}, "at most 20000"),
                                       ({"band_hz": (0.6, 2e5)}, "at most 1000000")])
def test_bad_settings_name_the_field(kw, field):
    with pytest.raises(ValueError, match=field):
        record(**kw)


def test_read_from_a_solve_config(tmp_path):
    from rockmass.solve_config import VelocityInputConfig

    cfg = VelocityInputConfig.model_validate({
        "where": "bottom", "component": "x",
        "history": {"type": "band_record", "band_hz": [0.6, 6.0], "duration_s": 10.0,
                    "peak_value": 0.0155, "passes": 15, "seed": 2}})
    h = cfg.history
    assert isinstance(h, BandRecord) and h.passes == 15 and h.band_hz == (0.6, 6.0)


class _Counted:
    """A velocity history that logs how many times it is sampled; equal to any other _Counted of
    the same ``tag`` (as two equal BandRecords are)."""

    def __init__(self, log: list, tag: str):
        self.log, self.tag = log, tag

    def __call__(self, t):
        self.log.append(len(t))
        return 0.01 * np.sin(2 * np.pi * 2.0 * np.asarray(t))

    def __eq__(self, other):
        return isinstance(other, _Counted) and other.tag == self.tag

    __hash__ = None


@pytest.mark.parametrize("tags, calls_per_chunk", [(("a", "a"), 1), (("a", "b"), 2)])
def test_inputs_sharing_a_history_sample_it_once(tags, calls_per_chunk):
    """The base and sides of a shake table share one motion: the runner samples it once per
    chunk of steps, and only when the histories are equal."""
    from rockmass.solver import Coulomb, Material, Settings, Stage, VelocityInput, run

    from ._models import incline

    log: list = []
    inputs = tuple(VelocityInput(f"blocks:{b}", "x", _Counted(log, tag))
                   for b, tag in zip((0, 1), tags))
    settings = Settings(joints={"default": Coulomb(1e9, 1e9, 40.0)}, material=Material(2000.0),
                        stages=(Stage("shake", "dynamic", duration_s=0.05),),
                        velocity_inputs=inputs)
    result = run(incline(0.0), settings)
    steps = result.stages[0].steps
    assert sum(log) == calls_per_chunk * steps
