"""Absorbing and free-field boundaries: reflected energy and free-field error against run time.

    python benchmarks/bench_boundaries.py [--quick]

Table 1 — quiet boundaries (docs/dem.md §14.1; issue 16 item 5). A column of rigid blocks of
height s on joints k_n, k_s (a mass-spring chain: long waves at c = √(k s/ρ), impedance √(ρ k s))
is driven at its top by a Ricker velocity pulse that leaves through a quiet base. Reflected energy
is measured at a monitor 60 blocks above the base three ways: ``reflected`` Σv² after the incident
pulse has passed over Σv² before (what the tests assert on); ``by_difference`` Σ(v − v_ref)²/Σv_ref²
against the same column lengthened below the monitor (nothing comes back within the record: the
reflected wave exactly, dispersion included); ``ledger`` (work in − absorbed)/work in from the
energy ledger. ``chain`` is the reflection of the discrete chain (leap-frog Δt included) weighted by
the incident spectrum. Below about 10 blocks per wavelength (seed 001 asks for at least 8–10) the
chain disperses the pulse: its tail is still travelling when the split is made, so ``reflected``
stops measuring the reflection and only ``by_difference`` does; ``ledger`` then fails too, as most
of the pulse lies above the chain's cut-off (at 600 Hz in P the driven top puts in 0.055 J, the base
absorbs 0.194 J, 0.099 J of it strain energy of the preload: the ledger closes, the ratio is no
longer a reflection). Rows vary the impedance rule ("rock_mass", the default, from the joints and
the block size; "tuned", the chain's own wave speeds given explicitly; "rock_mass_intact"; "rock",
the intact moduli, 2.4 × the chain's impedance), the blocks per wavelength (Ricker peak frequency,
and block size) and the time-step safety factor. Blocks per wavelength: c / (f s) at the Ricker's
peak frequency f. A smaller step reflects more (0.17 % at 0.5, 0.39 % at 0.1 in P), as the
chain's closed form with that Δt says: the leap-frog's error partly offsets the chain's.

Table 2 — free-field sides (docs/dem.md §14.2; seed 001 eqs. 14–16). A vertically travelling
wave from a driven base through a column (1 × 30) or slab (3 × 30) of 1 m bricks: the top row's
peak velocity and whole record (relative L2) against the 1D column solved by scipy's DOP853
(independent of the solver), with free-field sides and with free sides. Then a shear pulse driven
into the top of a 3 × 60 slab that leaves through a quiet base while the free-field columns leave
through their own foot dashpots: reflected energy at the middle and the side column of row 30.

Rows also go to benchmarks/results/bench_boundaries.json. The model builders and measurements are
the ones tests/solver/test_quiet_impedance.py and tests/solver/test_free_field.py assert on.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(_HERE))
if str(_HERE.parent) not in sys.path:  # the hand-built models of tests/solver
    sys.path.append(str(_HERE.parent))
from _common import header, save, table  # noqa: E402

from rockmass.solver import (BoundaryStress, Coulomb, Fix, FreeField, InSituStress, Material,  # noqa: E402
                             Monitor, QuietBoundary, Ricker, Settings, Stage, VelocityInput, run)
from rockmass.solver.engine import Engine  # noqa: E402
from rockmass.solver.loading import apply_insitu, quiet_edge_table  # noqa: E402
from tests.solver._models import hand_model, rect  # noqa: E402
from tests.solver._models_advanced import chain_column, chain_reflection  # noqa: E402

RHO, KN, KS = 2600.0, 2e10, 1e10  # density, joint stiffnesses (Pa/m)
K_ROCK, G_ROCK = 30e9, 20e9  # intact moduli (M = 56.7 GPa: 5.7 × k_n s at s = 0.5 m)
SIG0 = 2e6  # preload keeping the joints closed and stuck
S_CHAIN = 0.5  # block height of the chain column (m)
FREQ, V_PEAK = 20.0, 0.01  # free-field runs: Ricker base velocity, peak frequency and amplitude
IMPEDANCES = ("rock_mass", "tuned", "rock_mass_intact", "rock")


# ------------------------------------------------------------------------- quiet boundaries --
def chain_wave_speed(component: str, s: float = S_CHAIN) -> float:
    """Long-wave speed of the chain column, √(k s/ρ), k = k_n along y (P), k_s along x (S)."""
    return math.sqrt((KN if component == "y" else KS) * s / RHO)


def quiet_base(impedance: str = "rock_mass", s: float = S_CHAIN) -> QuietBoundary:
    """The quiet base of the chain column: an impedance rule, or ``"tuned"``: the chain's own wave
    speeds given explicitly (what a user had to do before the rock-mass rule)."""
    if impedance == "tuned":
        return QuietBoundary(("bottom",), p_wave_speed_m_s=chain_wave_speed("y", s),
                             s_wave_speed_m_s=chain_wave_speed("x", s))
    return QuietBoundary(("bottom",), impedance=impedance)


def chain_settings(n: int, impedance: str = "rock_mass", component: str = "y",
                   duration: float = 0.01, monitor: int | None = None, freq: float = 150.0,
                   safety: float | None = 0.5, s: float = S_CHAIN) -> Settings:
    """A column of ``n`` blocks (:func:`chain_column`) preloaded by σ₀, moving only along
    ``component`` (the other translation and the rotation fixed), a quiet base, and the top block
    driven by a Ricker velocity pulse of peak frequency ``freq``."""
    return Settings(
        joints={"default": Coulomb(KN, KS, 40.0)}, material=Material(RHO, K_ROCK, G_ROCK),
        gravity_m_s2=(0.0, 0.0), insitu=InSituStress(syy_pa=SIG0),
        boundary_stress=(BoundaryStress(("bottom",), syy_pa=SIG0),),
        quiet=quiet_base(impedance, s),
        fixes=(Fix(f"blocks:{','.join(map(str, range(n)))}", "xr" if component == "y" else "yr"),),
        velocity_inputs=(VelocityInput("top", component, Ricker(
            -0.01 if component == "y" else 0.01, freq)),),
        time_step_safety=safety,
        stages=(Stage("wave", "dynamic", duration_s=duration, history_every=1, frames=0),),
        monitors=() if monitor is None else (Monitor("m", block=monitor),))


def quiet_table(model, settings: Settings) -> np.ndarray:
    """The quiet boundary's edge table (impedances in columns 6, 7) a run of ``settings`` sets up."""
    eng = Engine(model, settings)
    eng.detect()
    apply_insitu(eng, settings.insitu)
    return quiet_edge_table(eng, settings.quiet)


def pulse_reflection(component: str = "y", impedance: str = "rock_mass", freq: float = 150.0,
                     s: float = S_CHAIN, safety: float | None = 0.5,
                     reference: bool = False) -> dict:
    """A Ricker pulse down a chain column into its quiet base; what comes back.

    Returns ``measured`` (reflected energy at a monitor ``mon`` blocks above the base: energy flux
    ∝ Z v², the same site both ways, so Σv²(reflected)/Σv²(incident), split when the incident
    pulse has passed the monitor and its reflection has not arrived), ``predicted`` (the discrete
    chain's reflection weighted by the incident spectrum), ``ledger`` ((work in − absorbed)/work
    in), ``ratio`` (Z_q / √(ρ k s)), ``blocks_per_wavelength``, ``omega_dt`` (the chain's highest
    frequency 2√(k/m) times Δt), ``steps`` and ``wall_s`` (the run alone). The column is 100 blocks
    above the monitor; the monitor is at least 60 blocks, and 1.8 wavelengths, above the base.

    The split assumes the pulse keeps its length; below about 10 blocks per wavelength the chain
    disperses it and its tail is counted as reflected. With ``reference=True`` the same column is
    also run lengthened below the monitor, so that nothing comes back within the record, and
    ``by_difference`` is Σ(v − v_ref)²/Σv_ref²: the reflected wave exactly, dispersion included
    (the two chains differ only below the monitor).
    """
    k = KN if component == "y" else KS
    c = chain_wave_speed(component, s)
    per_wavelength = c / (freq * s)
    mon = max(60, math.ceil(1.8 * per_wavelength))
    n = mon + 100
    t_arrive = (n - 1 - mon) * s / c
    duration = t_arrive + 2 * mon * s / c + 3.5 / freq  # the reflection has passed the monitor
    settings = chain_settings(n, impedance, component, duration, mon, freq, safety, s)
    model = chain_column(n, s, 1.0)
    z_q = quiet_table(model, settings)[0, 6 if component == "y" else 7]
    t0 = time.perf_counter()
    result = run(model, settings)
    wall = time.perf_counter() - t0
    if result.status != "ok":
        raise RuntimeError(f"pulse run stopped: {result.diagnostic}")
    stage = result.stages[0]
    h = result.history
    v = h[f"m_v{component}_m_s"]
    t_split = t_arrive + 0.5 * (3.0 / freq + 2 * mon * s / c)
    incident = np.where(h["time_s"] < t_split, v, 0.0)
    reflected = np.where(h["time_s"] >= t_split, v, 0.0)
    measured = (reflected ** 2).sum() / (incident ** 2).sum()
    nfft = 1 << 16
    spec = np.fft.rfft(incident, nfft)[1:]
    omega = 2 * np.pi * np.fft.rfftfreq(nfft, stage.time_step_s)[1:]
    r_chain = chain_reflection(omega, k * 1.0, RHO * s * 1.0, z_q * 1.0, stage.time_step_s)
    predicted = (np.abs(r_chain) ** 2 * np.abs(spec) ** 2).sum() / (np.abs(spec) ** 2).sum()
    e = stage.energy
    out = {"measured": float(measured), "predicted": float(predicted),
           "ledger": float((e["work_boundary_j"] - e["quiet_boundary_j"]) / e["work_boundary_j"]),
           "ratio": float(z_q / math.sqrt(RHO * k * s)), "blocks_per_wavelength": per_wavelength,
           "omega_dt": 2 * math.sqrt(k / (RHO * s)) * stage.time_step_s,
           "steps": len(h["time_s"]), "wall_s": wall, "by_difference": None}
    if reference:
        # recorded until the reflection, sent back down by the driven top, could reach the monitor
        out["by_difference"] = _reflection_by_difference(component, impedance, freq, s, safety,
                                                         n, mon, 2 * (n - 1) * s / c)
    return out


def _reflection_by_difference(component, impedance, freq, s, safety, n, mon, duration) -> float:
    """Σ(v − v_ref)²/Σv_ref² at the monitor over ``duration``: the column against the same column
    lengthened below the monitor so far that its base answers after the record ends (long waves
    travel fastest, at c; slower, dispersed components arrive later still)."""
    c = chain_wave_speed(component, s)
    extra = math.ceil(duration * c / (2 * s)) + 10
    records = []
    for blocks, monitor in ((n, mon), (n + extra, mon + extra)):
        result = run(chain_column(blocks, s, 1.0),
                     chain_settings(blocks, impedance, component, duration, monitor, freq,
                                    safety, s))
        if result.status != "ok":
            raise RuntimeError(f"reflection by difference: run stopped: {result.diagnostic}")
        records.append((result.stages[0].time_step_s, result.history[f"m_v{component}_m_s"]))
    (dt, v), (dt_ref, v_ref) = records
    if dt != dt_ref:
        raise RuntimeError(f"reflection by difference: time steps differ ({dt} s, {dt_ref} s)")
    return float(((v - v_ref) ** 2).sum() / (v_ref ** 2).sum())


# ---------------------------------------------------------------------- free-field sides --
def brick_slab(nx: int, ny: int, s: float = 1.0, w: float = 1.0):
    """``nx`` × ``ny`` bricks w × s in aligned columns; block i + nx j is column i, row j (row 0 at
    the bottom), joints between every two neighbours."""
    polys = [rect(i * w, j * s, (i + 1) * w, (j + 1) * s) for j in range(ny) for i in range(nx)]
    pairs = [(j * nx + i, j * nx + i + 1) for j in range(ny) for i in range(nx - 1)]
    pairs += [(j * nx + i, (j + 1) * nx + i) for j in range(ny - 1) for i in range(nx)]
    return hand_model(polys, pairs)


def shear_wave_settings(nx: int, ny: int, free_field: bool = True, duration: float = 0.25,
                        sxx: float = SIG0, component: str = "x", freq: float = FREQ,
                        safety: float | None = 0.5) -> Settings:
    """The base row driven along ``component`` by a Ricker velocity (the other translation and the
    rotation held), in-situ σ_xx = ``sxx``, σ_yy = σ₀ (the top loaded by σ₀: the joints stay
    closed and stuck), no gravity; monitors on the top row's middle and side blocks."""
    base = "blocks:" + ",".join(str(i) for i in range(nx))
    top = (ny - 1) * nx
    return Settings(
        joints={"default": Coulomb(KN, KS, 40.0)}, material=Material(RHO, K_ROCK, G_ROCK),
        gravity_m_s2=(0.0, 0.0), insitu=InSituStress(sxx_pa=sxx, syy_pa=SIG0),
        boundary_stress=(BoundaryStress(("top",), syy_pa=SIG0),),
        fixes=(Fix(base, "yr" if component == "x" else "xr"),),
        velocity_inputs=(VelocityInput(base, component, Ricker(V_PEAK, freq)),),
        free_field=FreeField(("left", "right")) if free_field else None, time_step_safety=safety,
        stages=(Stage("sv", "dynamic", duration_s=duration, history_every=1, frames=0),),
        monitors=(Monitor("mid", block=top + nx // 2), Monitor("side", block=top)))


def column_response(n_above: int, m: float, k: float, times, freq: float = FREQ):
    """Velocity of the top mass of a chain (masses ``m``, springs ``k`` per unit width, free top)
    on a base moving at the Ricker velocity, by DOP853 (rtol 1e-10)."""
    from scipy.integrate import solve_ivp

    history = Ricker(V_PEAK, freq)

    def rhs(t, y):
        u, v = y[:n_above + 1], y[n_above + 1:]
        tau = k * np.diff(u)                       # joint stresses, base to top
        a = np.zeros(n_above + 1)
        a[1:] = (np.append(tau[1:], 0.0) - tau) / m
        v = v.copy()
        v[0] = float(history(t))                   # the base follows the input
        return np.concatenate([v, a])

    sol = solve_ivp(rhs, (0.0, float(times[-1])), np.zeros(2 * (n_above + 1)), t_eval=times,
                    method="DOP853", rtol=1e-10, atol=1e-14)
    return sol.y[-1]


def compare_to_column(result, k_column: float, ny: int, s: float = 1.0, component: str = "x",
                      freq: float = FREQ) -> dict:
    """{monitor: (relative error of the peak velocity, relative L2 error of the record)} against
    :func:`column_response`."""
    h = result.history
    reference = column_response(ny - 1, RHO * s, k_column, h["time_s"], freq)
    peak = np.abs(reference).max()
    out = {}
    for name in ("mid", "side"):
        v = h[f"{name}_v{component}_m_s"]
        out[name] = (np.abs(v).max() / peak - 1,
                     np.linalg.norm(v - reference) / np.linalg.norm(reference))
    return out


def slab_shear_speed(s: float = 1.0, w: float = 1.0) -> float:
    """Shear wave speed of a slab of w × s bricks: the equivalent continuum's spring per row,
    1/k = 1/k_s + s/(k_s w) (docs/dem.md §14.1), on masses ρ s: c = √(k s/ρ)."""
    return math.sqrt(s / (RHO * (1.0 / KS + s / (KS * w))))


def top_pulse_settings(nx: int = 3, ny: int = 60, freq: float = 40.0,
                       impedance: str = "rock_mass", free_field: bool = True,
                       safety: float | None = 0.5) -> Settings:
    """The seed's set-up turned over: a shear pulse (Ricker) driven into the top row of an
    ``nx`` × ``ny`` slab of 1 m bricks leaves through a quiet base, the free-field columns beside it
    (driven at their top by the same input) through their own foot dashpots; monitors on the
    middle and side blocks of row 30. ``impedance`` is the rule of both the base and the free field
    (``"tuned"``: the slab's own wave speeds, √(k_n/ρ) and :func:`slab_shear_speed`)."""
    top = "blocks:" + ",".join(str((ny - 1) * nx + i) for i in range(nx))
    c = slab_shear_speed()
    if impedance == "tuned":
        speeds = dict(p_wave_speed_m_s=math.sqrt(KN / RHO), s_wave_speed_m_s=c)
        quiet = QuietBoundary(("bottom",), **speeds)
        sides = FreeField(("left", "right"), **speeds)
    else:
        quiet = QuietBoundary(("bottom",), impedance=impedance)
        sides = FreeField(("left", "right"), impedance=impedance)
    return Settings(
        joints={"default": Coulomb(KN, KS, 40.0)}, material=Material(RHO, K_ROCK, G_ROCK),
        gravity_m_s2=(0.0, 0.0), insitu=InSituStress(sxx_pa=SIG0, syy_pa=SIG0),
        boundary_stress=(BoundaryStress(("bottom",), syy_pa=SIG0),),
        fixes=(Fix(top, "yr"),), velocity_inputs=(VelocityInput(top, "x", Ricker(V_PEAK, freq)),),
        quiet=quiet, free_field=sides if free_field else None, time_step_safety=safety,
        monitors=(Monitor("mid", block=30 * nx + 1), Monitor("side", block=30 * nx)),
        stages=(Stage("sv", "dynamic", duration_s=3.0 / freq + 2.0 * ny / c, history_every=1,
                      frames=0),))


def top_pulse_reflection(nx: int = 3, ny: int = 60, freq: float = 40.0, **kwargs) -> dict:
    """Run :func:`top_pulse_settings`; reflected energy Σv²(after)/Σv²(before) at the middle and
    side monitors of row 30, split between the incident pulse and its reflection, with ``steps``
    and ``wall_s`` (the run alone)."""
    settings = top_pulse_settings(nx, ny, freq, **kwargs)
    model = brick_slab(nx, ny)
    t0 = time.perf_counter()
    result = run(model, settings)
    wall = time.perf_counter() - t0
    if result.status != "ok":
        raise RuntimeError(f"top-pulse run stopped: {result.diagnostic}")
    h = result.history
    c = slab_shear_speed()
    t_split = (ny - 1 - 30) / c + 0.5 * (3.0 / freq + 2 * 30 / c)
    out = {"steps": len(h["time_s"]), "wall_s": wall}
    for name in ("mid", "side"):
        v = h[f"{name}_vx_m_s"]
        out[name] = float((v[h["time_s"] >= t_split] ** 2).sum()
                          / (v[h["time_s"] < t_split] ** 2).sum())
    return out


# ------------------------------------------------------------------------------ tables --
def _safety_name(safety) -> str:
    return "default" if safety is None else f"{safety:g}"


def quiet_rows(quick: bool = False) -> list[dict]:
    cases = [(comp, imp, 150.0, S_CHAIN, 0.5) for comp in ("y", "x") for imp in IMPEDANCES]
    if not quick:
        cases += [(comp, "rock_mass", f, S_CHAIN, 0.5) for comp in ("y", "x")
                  for f in (75.0, 300.0, 600.0)]
        cases += [(comp, "rock_mass", 150.0, s, 0.5) for comp in ("y", "x") for s in (0.25, 1.0)]
        cases += [(comp, "rock_mass", 150.0, S_CHAIN, sf) for comp in ("y", "x") for sf in (None, 0.1)]
    rows = []
    for comp, imp, freq, s, safety in cases:
        r = pulse_reflection(comp, imp, freq, s, safety, reference=True)
        rows.append({"wave": "P" if comp == "y" else "S", "impedance": imp, "block_m": s,
                     "freq_hz": freq, "blocks_per_wavelength": r["blocks_per_wavelength"],
                     "safety": _safety_name(safety), "omega_dt": r["omega_dt"],
                     "z_ratio": r["ratio"], "reflected_pct": 100 * r["measured"],
                     "by_difference_pct": 100 * r["by_difference"],
                     "chain_pct": 100 * r["predicted"], "ledger_pct": 100 * r["ledger"],
                     "steps": r["steps"], "wall_s": r["wall_s"]})
    return rows


def _column_row(case, nx, ny, k_column, free_field=True, sxx=SIG0, component="x", freq=FREQ,
                safety=0.5, duration=0.25):
    settings = shear_wave_settings(nx, ny, free_field, duration, sxx, component, freq, safety)
    t0 = time.perf_counter()
    result = run(brick_slab(nx, ny), settings)
    wall = time.perf_counter() - t0
    if result.status != "ok":
        raise RuntimeError(f"{case}: run stopped: {result.diagnostic}")
    err = compare_to_column(result, k_column, ny, component=component, freq=freq)
    c = math.sqrt(k_column / RHO)  # 1 m bricks: c = √(k s/ρ), s = 1
    worst = max(err.values(), key=lambda e: abs(e[0]))
    return {"case": case, "sides": "free field" if free_field else "free", "impedance": "rock_mass",
            "freq_hz": freq, "blocks_per_wavelength": c / freq, "safety": _safety_name(safety),
            "peak_err_pct": 100 * worst[0], "l2_err_pct": 100 * max(e[1] for e in err.values()),
            "reflected_pct": None, "steps": len(result.history["time_s"]), "wall_s": wall}


def free_field_rows(quick: bool = False) -> list[dict]:
    slab_k = 1.0 / (1.0 / KS + 1.0 / KS)  # 1 m square bricks: k_s / 2
    rows = [_column_row("SV, column 1 x 30", 1, 30, KS),
            _column_row("SV, column 1 x 30", 1, 30, KS, free_field=False),
            _column_row("SV, slab 3 x 30", 3, 30, slab_k),
            _column_row("SV, slab 3 x 30", 3, 30, slab_k, free_field=False, sxx=0.0),
            _column_row("P, slab 3 x 30", 3, 30, KN, component="y", duration=0.2)]
    if not quick:
        rows += [_column_row("SV, slab 3 x 30", 3, 30, slab_k, freq=40.0),
                 _column_row("SV, slab 3 x 30", 3, 30, slab_k, safety=None),
                 _column_row("SV, slab 3 x 30", 3, 30, slab_k, safety=0.1)]
    pulses = [("rock_mass", True, 0.5)]
    if not quick:
        pulses += [("tuned", True, 0.5), ("rock", True, 0.5), ("rock_mass", False, 0.5),
                   ("rock_mass", True, None)]
    for imp, ff, safety in pulses:
        r = top_pulse_reflection(impedance=imp, free_field=ff, safety=safety)
        rows.append({"case": "SV pulse out of a 3 x 60 slab", "sides": "free field" if ff else "free",
                     "impedance": imp, "freq_hz": 40.0,
                     "blocks_per_wavelength": slab_shear_speed() / 40.0,
                     "safety": _safety_name(safety), "peak_err_pct": None, "l2_err_pct": None,
                     "reflected_pct": 100 * max(r["mid"], r["side"]), "steps": r["steps"],
                     "wall_s": r["wall_s"]})
    return rows


QUIET_COLUMNS = [("wave", "s"), ("impedance", "s"), ("block_m", "g"), ("freq_hz", "g"),
                 ("blocks_per_wavelength", ".1f"), ("safety", "s"), ("omega_dt", ".3f"),
                 ("z_ratio", ".3f"), ("reflected_pct", ".3f"), ("by_difference_pct", ".3f"),
                 ("chain_pct", ".3f"), ("ledger_pct", ".3f"), ("steps", "d"), ("wall_s", ".2f")]
FREE_FIELD_COLUMNS = [("case", "s"), ("sides", "s"), ("impedance", "s"), ("freq_hz", "g"),
                      ("blocks_per_wavelength", ".0f"), ("safety", "s"), ("peak_err_pct", "+.3f"),
                      ("l2_err_pct", ".3f"), ("reflected_pct", ".3f"), ("steps", "d"),
                      ("wall_s", ".2f")]


def main(quick: bool = False) -> None:
    print(header("bench_boundaries: quiet and free-field boundaries, error against run time"))
    t0 = time.perf_counter()
    pulse_reflection("y", freq=600.0)  # compile outside the timings
    _column_row("warm-up", 1, 5, KS, duration=0.01)
    compile_s = time.perf_counter() - t0
    print(f"first run (compiles the solver): {compile_s:.1f} s\n")
    quiet = quiet_rows(quick)
    print("Table 1 — a Ricker pulse down a 160-block chain column (ρ 2600 kg/m³, k_n 20, k_s 10 "
          "GPa/m) into a quiet base;\nreflected energy at a monitor 60 blocks up (target < 2 % "
          "with the rock-mass impedance)")
    print(table(quiet, QUIET_COLUMNS))
    ff = free_field_rows(quick)
    print("\nTable 2 — free-field sides: top-row velocity against the 1D column (DOP853), worst of "
          "the middle and side monitors\n(target: peak and L2 within 2 %); a pulse leaving a "
          "3 x 60 slab through a quiet base (target < 2 % reflected)")
    print(table(ff, FREE_FIELD_COLUMNS))
    path = save("bench_boundaries", {"compile_s": compile_s, "quiet": quiet, "free_field": ff})
    print(f"\nrows written to {path}")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv)
