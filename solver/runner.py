"""``run(model, settings) -> Result``: the stages of a DEM run, one after the other.

Per stage: remove the excavated blocks, set the degrees of freedom (velocity inputs are held fixed
in static stages and prescribed in dynamic ones), choose the time step (automatic: safety × the
Gershgorin bound of :meth:`Engine.stable_time_step`; a user value above the bound is refused),
then step in chunks (the kernel returns for a contact rebuild, convergence, an overlap above the
limit or a non-finite value). Between chunks the monitors, frames and peak block velocities are
recorded. A failed stage (overlap, non-finite state) ends the run; the state of the last good chunk
is kept and every report is written with a ``status`` and a diagnostic.

Energy ledger per stage (J per metre of thickness): work in = gravity work + boundary work
(tractions, and work done by prescribed blocks through their contacts); it must equal
Δ kinetic + Δ strain + slip dissipation + breakage + damping dissipation; the residual is reported.
Kinetic energy is that of the half-step velocities and the strain change in the residual is the
leapfrog's 'shadow' form (½ F_n·u_{n+1}), which makes the discrete ledger exact for elastic contacts
(residual at round-off) instead of O(F v Δt); ``strain_start_j`` / ``strain_end_j`` report the
plain Σ ½F²/K of the contact state.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable

import numpy as np

from . import _kernels as K
from . import tolerances as T
from .engine import FIXED, Engine
from .failure import FailureWatch
from .bolts import bolt_energy, bolt_table, install_bolts
from .deformable import piece_near_centre, zone_model, zone_table
from .free_field import set_free_field
from .loading import apply_boundary_stress, apply_insitu, quiet_edge_table
from .monitoring import boundary_points, point_displacement_from
from .result import (FAILED_STATUSES, STATUS_FAILED_BLOCKS, STATUS_OK, EnergyLedger, Frame, Result,
                     StageResult)
from .selectors import block_at_point, require_point_in_domain
from .settings import Settings, Stage, same_history
from .wavelength import warn_coarse_zones, wave_checks

__all__ = ["reference_stage", "run"]




def _rayleigh(stage: Stage) -> tuple[float, float]:
    """(α, β) of C = αM + βK giving ξ at f, with ξ(ω) = ½(α/ω + βω) (docs/dem.md §8, eq. (8.3)):
    both terms (minimum ξ at f): α = ξω, β = ξ/ω; mass only: α = 2ξω; stiffness only: β = 2ξ/ω."""
    if stage.kind != "dynamic" or stage.rayleigh_ratio <= 0:
        return 0.0, 0.0
    omega = 2 * math.pi * stage.rayleigh_frequency_hz
    xi = stage.rayleigh_ratio
    if stage.rayleigh_mode == "mass":
        return 2 * xi * omega, 0.0
    if stage.rayleigh_mode == "stiffness":
        return 0.0, 2 * xi / omega
    return xi * omega, xi / omega


def _reference_inputs(settings: Settings, stage: Stage) -> tuple[int, int]:
    """Columns of the prescribed-velocity table (the indices of ``settings.velocity_inputs``) that
    the mass-proportional damping of ``stage`` is relative to, in x and y (-1: absolute
    velocity). With ``rayleigh_reference="inputs"`` the first input of each component; the
    others of that component must prescribe the same history (checked by
    :func:`rockmass.solver.settings._check_settings`)."""
    if stage.rayleigh_reference != "inputs":
        return -1, -1
    first = {}
    for i, inp in enumerate(settings.velocity_inputs):
        first.setdefault(inp.component, i)
    return first.get("x", -1), first.get("y", -1)


def _overlap_diagnostic(eng: Engine, pair: int, overlap: float, dt: float) -> str:
    a, b = int(eng.pa[pair]), int(eng.pb[pair])
    slot = eng.S[pair, 0] if eng.S[pair, 0, K.OVL] >= eng.S[pair, 1, K.OVL] else eng.S[pair, 1]
    x, y = slot[K.PX], slot[K.PY]
    prop = eng.props[eng.pprop[pair]]
    sig = slot[K.FN] / max(slot[K.LEN], 1e-300)
    speed = float(np.hypot(*(eng.vel[b] - eng.vel[a])))
    causes = []
    if sig > 0 and sig / prop[K.P_KN] > 0.25 * eng.overlap_limit_m:
        causes.append(f"the joint normal stiffness is low for the load: σ_n/k_n = "
                      f"{sig / prop[K.P_KN]:.3g} m — raise k_n or lower the load")
    if speed * dt > 0.1 * eng.overlap_limit_m:
        causes.append(f"the blocks approach at {speed:.3g} m/s, {speed * dt:.3g} m a step — lower "
                      "the time step or the input velocity")
    if not causes:
        causes.append("a block passing a corner of a small neighbour (sliver) — increase "
                      "rounding_m or merge small blocks in blockgen")
    return (f"overlap {overlap:.4g} m between blocks {a} and {b} at ({x:.4g}, {y:.4g}) m exceeds the "
            f"limit {eng.overlap_limit_m:.4g} m (half the rounding length); likely cause: "
            + "; ".join(causes))


class _Recorder:
    """Histories of monitored blocks, frames and peak block velocities."""

    def __init__(self, eng: Engine, settings: Settings):
        self.eng = eng
        self.monitors = []
        for m in settings.monitors:
            if m.block is None:
                require_point_in_domain(eng.model, m.name, m.point_xy_m)
            if m.block is not None and eng.zoned is not None:  # a zoned block: its middle piece
                block = piece_near_centre(eng.zoned, eng.model, m.block)
            else:
                block = m.block if m.block is not None else block_at_point(eng.model,
                                                                           m.point_xy_m)
            if not 0 <= block < eng.nb:
                raise ValueError(f"monitor {m.name!r}: block {block} out of range")
            self.monitors.append((m.name, block))
        self.rows = []
        self.frames = []
        self.peak_v = np.zeros(eng.nb)

    def record(self, stage: str, ratio: float):
        e = self.eng
        row = {"time_s": e.time_s, "stage": stage, "unbalanced_ratio": ratio,
               "kinetic_energy_j": e.kinetic_energy()}
        for name, b in self.monitors:
            row[f"{name}_ux_m"] = e.pos[b, 0] - e.pos0[b, 0]
            row[f"{name}_uy_m"] = e.pos[b, 1] - e.pos0[b, 1]
            row[f"{name}_rotation_rad"] = e.rot[b]
            row[f"{name}_vx_m_s"] = e.vel[b, 0]
            row[f"{name}_vy_m_s"] = e.vel[b, 1]
            force = e.contact_force_on(b)
            row[f"{name}_contact_fx_n"] = force[0]
            row[f"{name}_contact_fy_n"] = force[1]
        self.rows.append(row)

    def frame(self, stage: str, step: int):
        e = self.eng
        zones = None
        if e.zoned is not None:
            z = e.zone_state
            zones = {"nodes_m": z["xy"].copy(), "stress_pa": -z["sig"],
                     "plastic_state": z["state"].copy(), "triangles": z["tri"],
                     "zone_block": z["zone_block"]}
        self.frames.append(Frame(stage, step, e.time_s, e.pos.copy(), e.rot.copy(), e.vel.copy(),
                                 e.active.copy(), e.failed.copy(), zones))

    def track_peaks(self):
        e = self.eng
        speed = np.hypot(e.vel[:, 0], e.vel[:, 1]) + np.abs(e.omg) * e.radius
        np.maximum(self.peak_v, np.where(e.active, speed, 0.0), out=self.peak_v)

    def history(self) -> dict:
        if not self.rows:
            return {}
        return {k: np.array([r[k] for r in self.rows]) for k in self.rows[0]}


def _contact_counts(eng: Engine):
    S = eng.S
    act = S[:, :, K.ACT] != 0
    slipping = int((act & (S[:, :, K.SLIP] != 0)).sum())
    closed = np.zeros(len(eng.init_key), bool)
    has = eng.pinit >= 0
    closed[eng.pinit[has]] = (act & (S[:, :, K.FN] > 0)).any(axis=1)[has]
    a, b = np.divmod(eng.init_key, eng.nb)
    live = eng.active[a] & eng.active[b]
    broken = eng.init_brk.copy()
    broken[eng.pinit[has]] = np.maximum(broken[eng.pinit[has]], S[has, :, K.BRK].max(axis=1))
    broken = (broken > 0) & eng.bonds(eng.init_prop)  # only a bond breaks (docs/dem.md §7)
    return slipping, int((live & ~closed).sum()), int(broken.sum())


def _boundary_blocks(eng: Engine, removed: np.ndarray) -> np.ndarray:
    """Active blocks that shared a contact with an excavated block."""
    cb = eng.model.contact_blocks
    inner = cb[:, 1] >= 0
    a, b = cb[inner, 0], cb[inner, 1]
    mask = np.zeros(eng.nb, bool)
    mask[a[removed[b]]] = True
    mask[b[removed[a]]] = True
    return mask & eng.active


def _detached(eng: Engine, removed: np.ndarray) -> int:
    """Active blocks whose centroid now lies inside the excavated space."""
    if not removed.any():
        return 0
    import shapely

    polys = eng.model.to_shapely()[removed]
    opening = shapely.union_all(polys)
    inside = shapely.contains_xy(opening, eng.pos[:, 0], eng.pos[:, 1])
    return int((inside & eng.active).sum())


def _bolt_strain(eng: Engine, dt: float) -> tuple[float, float]:
    """(elastic energy of the bolts, its leapfrog 'shadow' form): the bolts' forces are all
    incremental, so both lag the positions by a step at a chunk's end and at a stage's start
    (docs/dem.md §15)."""
    elastic, work = bolt_energy(eng, dt)
    return elastic, elastic + 0.5 * work


def _energy_ledger(eng: Engine, dt: float, ke0: float, se0: float, se0_shadow: float,
                   removed_j: float, bolts0: tuple[float, float] = (0.0, 0.0)) -> EnergyLedger:
    """The stage's energy ledger so far (module docstring); ``removed_j``: kinetic and strain
    energy that left with blocks taken out during the stage (failed blocks); ``bolts0``: the
    bolts' elastic energy at the stage's start, plain and shadow (:func:`_bolt_strain`)."""
    wn, ws = eng.contact_increment_work(dt)
    ke1, se1 = eng.kinetic_energy(), eng.strain_energy()
    se1_shadow = se1 + 0.5 * (wn + ws)
    be1, be1_shadow = _bolt_strain(eng, dt)
    E = eng.E
    work_in = E[K.E_GRAVITY] + E[K.E_EXTERNAL] - E[K.E_CONTACT_PRESC] + E[K.E_ZONE_MIXED]
    damping = -(E[K.E_LOCAL_DAMP] + E[K.E_VISCOUS] + E[K.E_QUIET])
    stored = ((ke1 - ke0) + (se1_shadow - se0_shadow) + E[K.E_SLIP] + E[K.E_BROKEN] + damping
              + removed_j + (be1_shadow - bolts0[1]) + E[K.E_BOLT_SLIP] + E[K.E_BOLT_YIELD]
              + E[K.E_ZONE_PLASTIC])
    terms = dict(work_gravity_j=E[K.E_GRAVITY], work_boundary_j=E[K.E_EXTERNAL] - E[K.E_CONTACT_PRESC],
                 kinetic_start_j=ke0, kinetic_end_j=ke1, strain_start_j=se0, strain_end_j=se1,
                 slip_dissipation_j=E[K.E_SLIP], breakage_dissipation_j=E[K.E_BROKEN],
                 damping_dissipation_j=damping, local_damping_j=-E[K.E_LOCAL_DAMP],
                 viscous_damping_j=-E[K.E_VISCOUS], quiet_boundary_j=-E[K.E_QUIET],
                 removed_blocks_j=removed_j, residual_j=work_in - stored,
                 bolt_strain_start_j=bolts0[0], bolt_strain_end_j=be1,
                 bolt_slip_dissipation_j=E[K.E_BOLT_SLIP], bolt_yield_dissipation_j=E[K.E_BOLT_YIELD],
                 zone_plastic_dissipation_j=E[K.E_ZONE_PLASTIC],
                 zone_mixed_work_j=E[K.E_ZONE_MIXED])
    return EnergyLedger(**{k: float(v) for k, v in terms.items()})


def _remove_failed(eng: Engine, watch: FailureWatch, ids: np.ndarray) -> tuple[list, float]:
    """Take failing blocks out of the model; their reports and the energy that left with them."""
    failed = watch.classify(ids)
    before = eng.kinetic_energy() + eng.strain_energy()
    eng.remove_blocks(ids)
    eng.failed[ids] = True
    eng.rebuild()
    eng.detect()
    return failed, before - (eng.kinetic_energy() + eng.strain_energy())


def _new_contact_w2(dt: float, safety: float) -> float:
    """ω² above which a contact that forms stops the kernel (``RC_STIFF``): (2 safety / Δt)², the
    ω_max the step was chosen for (safety 1 for a user's step: its true limit)."""
    return (2.0 * safety / dt) ** 2


def _auto_time_step(eng: Engine, safety: float, beta: float) -> tuple[float, float]:
    """(Δt, stable limit) for the present contacts: safety × the limit; without any contact the
    limit is infinite and Δt only sets the record interval (the caller's fallback)."""
    limit = eng.stable_time_step(beta)
    return safety * limit, limit


def _warn_stiffness_damping_step(stage: Stage, beta: float, limit: float,
                                 without_beta: float) -> None:
    """A ``UserWarning`` when the stiffness-proportional Rayleigh term β K cuts the stable step
    ``without_beta`` to ``limit`` by more than
    :data:`~rockmass.solver.tolerances.DAMPED_STEP_WARN_FACTOR`. By eq. (2.6) of docs/dem.md,
    Δt/Δt₀ = 2/(√(4 + x²) + x) with x = βω_max: the stiffest contacts and the smallest zones are
    overdamped at their own frequency (x > 1.5 for a halving), and the stage takes that many more
    steps to damp vibrations no input carries. Points at the caller of :func:`run` (warn <- this
    <- _first_time_step <- _StageRun <- run <- caller)."""
    if not (math.isfinite(limit) and math.isfinite(without_beta)) or (
            limit * T.DAMPED_STEP_WARN_FACTOR >= without_beta):
        return
    warnings.warn(
        f"stage {stage.name!r}: the stiffness-proportional part of the Rayleigh damping "
        f"(beta = {beta:.4g} s, rayleigh_mode = {stage.rayleigh_mode!r}) cuts the stable time step "
        f"from {without_beta:.4g} s to {limit:.4g} s ({without_beta / limit:.1f} times as many "
        f"steps): it overdamps the stiffest contacts or zones; rayleigh_mode = \"mass\" keeps the "
        f"step without it (at the same rayleigh_ratio its mass term is twice as large)",
        UserWarning, stacklevel=5)


def _monitor_displacements(points, eng: Engine, ref) -> dict:
    """Displacement (m) of each boundary point from the reference placement; a point whose block
    was taken out (failed) is left out — the stage's ``failed_blocks`` name that block."""
    kept = [p for p in points if eng.active[p.block]]
    if not kept:
        return {}
    disp = point_displacement_from(kept, eng.pos, eng.rot, *ref)
    return {p.name: float(disp[f"{p.name}_u_m"]) for p in kept}


class _StageRun:
    """One stage, in named steps: :meth:`__init__` sets it up (excavation, degrees of freedom, time
    step, budgets, the energy reference), :meth:`run` steps it chunk by chunk — each chunk is
    advanced (:meth:`_advance`), then checked (:meth:`_after_chunk`: a contact the step cannot
    resolve, a non-finite value, the periodic time-step and energy guard, overlap, convergence,
    failing blocks) — and :meth:`result` reports it. ``self.status`` / ``self.diagnostic`` say why
    it stopped."""

    def __init__(self, eng: Engine, stage: Stage, settings: Settings, rec: _Recorder, ref,
                 progress=None, points=()):
        self.eng, self.stage, self.settings, self.rec, self.ref = eng, stage, settings, rec, ref
        self.progress, self.points = progress, points
        self.wall0 = time.perf_counter()
        eng.excavate(list(stage.excavate))
        self.dynamic = dynamic = stage.kind == "dynamic"
        eng.set_stage_modes(dynamic)
        eng.rebuild()
        eng.detect()
        self.alpha_mass, self.beta = _rayleigh(stage)
        self.safety = settings.step_safety(dynamic)
        self.ref_inputs = _reference_inputs(settings, stage)
        eng.quiet_edges = (quiet_edge_table(eng, settings.quiet) if dynamic and settings.quiet
                           else np.zeros((0, 8)))  # before the step limit: the dashpots lower it
        set_free_field(eng, settings.free_field if dynamic else None)  # docs/dem.md §14.2
        install_bolts(eng, settings, stage.name)  # docs/dem.md §15, before the step limit
        eng.scale_block_masses(static=not dynamic)  # docs/dem.md §10.4, before the step limit
        eng.scale_node_masses(static=not dynamic)  # docs/dem.md §16.6, after the blocks'
        self.dt, self.limit = self._first_time_step()
        self.n_steps = math.ceil(stage.duration_s / self.dt) if dynamic else stage.max_steps
        self.inputs = settings.velocity_inputs if dynamic else ()
        # inputs that share a history (a shake table's base and sides) sample it once per chunk
        self.first_of_history = [next(j for j in range(i + 1)
                                      if same_history(self.inputs[j].history, inp.history))
                                 for i, inp in enumerate(self.inputs)]
        if stage.history_every:
            self.chunk = stage.history_every
        else:
            self.chunk = max(1, self.n_steps // T.DYNAMIC_RECORDS) if dynamic else T.STATIC_CHUNK
        self.frame_every = max(1, self.n_steps // stage.frames) if (dynamic and stage.frames) else 0

        self.stage_pos, self.stage_rot = eng.pos.copy(), eng.rot.copy()
        self.stage_t0 = eng.time_s  # velocity histories run on the stage's own clock
        eng.E[:] = 0.0
        # strain energies in the leapfrog's own ('shadow') form, so the ledger closes to O((ωΔt)²):
        # at the start the normal part is at p_0 and the shear part lags at p_-1; at the end both
        # are at p_N-1 while the positions are p_N (see Engine.contact_increment_work)
        wn, ws = eng.contact_increment_work(self.dt)
        self.ke0, self.se0 = eng.kinetic_energy(), eng.strain_energy()
        self.se0_shadow = self.se0 - 0.5 * wn + 0.5 * ws
        self.bolts0 = _bolt_strain(eng, self.dt)
        self.out = np.zeros(8)
        self.out[7] = math.inf  # kinetic energy of the previous convergence check
        self.done = 0
        self.status = "max_steps" if not dynamic else "completed"
        self.diagnostic = None
        self.ratio = math.inf
        self.rebuilds0 = eng.n_rebuilds
        rec.record(stage.name, 0.0)  # ratio unknown before the first step
        if stage.frames:
            rec.frame(stage.name, 0)
        self.tol = stage.tolerance if not dynamic else 0.0
        self.alpha_local = stage.local_damping if not dynamic else 0.0
        self.sleep_ratio = (T.SLEEP_RATIO_OF_TOLERANCE * stage.tolerance
                            if (settings.sleep and not dynamic) else 0.0)
        self.watch = None if dynamic else FailureWatch(
            eng, settings.failure_displacement_m or T.FAILURE_ROUNDINGS * eng.rounding_m,
            settings.failure_checks, settings.sliver_area_m2)
        self.failed, self.removed_j = [], 0.0
        self.step_cuts = 0
        self.guarded = 0  # step of the last time-step and energy check

    def _first_time_step(self) -> tuple[float, float]:
        """(Δt, stable limit): automatic, or the stage's own (refused above the limit), or a
        fraction of the duration when nothing is in contact (free flight). An automatic step cut
        sharply by the stiffness-proportional damping warns
        (:func:`_warn_stiffness_damping_step`)."""
        stage = self.stage
        dt, limit = _auto_time_step(self.eng, self.safety, self.beta)
        if stage.time_step_s is not None:
            if stage.time_step_s > limit:
                raise ValueError(f"stage {stage.name!r}: time_step_s = {stage.time_step_s:.6g} s exceeds "
                                 f"the stable limit {limit:.6g} s (2/ω_max of the contact stiffnesses"
                                 f"{' with Rayleigh damping' if self.beta else ''}); use at most that")
            dt = stage.time_step_s
        elif not math.isfinite(limit):  # no contact at all: free flight
            dt = (stage.duration_s or 1.0) / T.FREE_FLIGHT_STEPS
        if self.beta > 0 and stage.time_step_s is None:
            _warn_stiffness_damping_step(stage, self.beta, limit, self.eng.stable_time_step())
        return dt, limit

    def run(self) -> StageResult:
        """Step until the budget is spent or a chunk says stop, then report."""
        while self.done < self.n_steps:
            if not self._chunk():
                break
        if self.stage.frames:
            self.rec.frame(self.stage.name, self.done)
        return self.result()

    def _stop(self, status: str, diagnostic: str | None) -> bool:
        self.status, self.diagnostic = status, diagnostic
        return False

    def _advance(self, todo: int) -> int:
        """Advance ``todo`` steps (or fewer: the kernel returns early); its return code."""
        eng, stage, dt = self.eng, self.stage, self.dt
        t_half = eng.time_s - self.stage_t0 + (np.arange(todo) + 0.5) * dt
        presc = np.zeros((todo, max(1, len(self.inputs))))
        for i, inp in enumerate(self.inputs):
            first = self.first_of_history[i]
            presc[:, i] = inp.history(t_half) if first == i else presc[:, first]
        return eng.advance(todo, presc, self.out, dt, alpha_local=self.alpha_local,
                           alpha_mass=self.alpha_mass, ref_inputs=self.ref_inputs,
                           beta=self.beta, tol_ratio=self.tol,
                           block_tol=stage.block_tolerance, sleep_ratio=self.sleep_ratio,
                           sleep_speed=T.SLEEP_CREEP * eng.rounding_m / (T.SLEEP_STEPS * dt),
                           w2_new=_new_contact_w2(dt, self.safety
                                                  if stage.time_step_s is None else 1.0))

    def _shorter_step(self, new_dt: float, new_limit: float, kept: int) -> None:
        """Continue with the step ``new_dt``; a dynamic stage keeps its duration (``kept`` steps of
        the current chunk stand)."""
        if self.dynamic:
            left = self.stage.duration_s - (self.eng.time_s + kept * self.dt - self.stage_t0)
            self.n_steps = self.done + kept + max(0, math.ceil(left / new_dt))
        self.dt, self.limit = new_dt, new_limit
        self.step_cuts += 1

    def _chunk(self) -> bool:
        """One chunk of steps and what follows from it; False when the stage stops."""
        eng, stage, out = self.eng, self.stage, self.out
        done = self.done
        todo = min(self.chunk - done % self.chunk, self.n_steps - done)
        snap = eng.snapshot()
        ke_check = out[7]
        rc = self._advance(todo)
        steps = int(out[0])
        dt_used = self.dt
        if rc == K.RC_STIFF:  # a contact formed that this step cannot resolve: shorter step
            new_dt, new_limit = _auto_time_step(eng, self.safety, self.beta)
            eng.restore(snap)
            out[7] = ke_check
            if stage.time_step_s is not None or not new_dt < self.dt:
                return self._stop("unstable", (
                    f"a contact that formed during the stage needs a time step below "
                    f"{new_limit:.4g} s; the step is {self.dt:.4g} s"
                    f"{' (the stage time_step_s)' if stage.time_step_s else ''}; the "
                    f"state of step {done} is kept"))
            if self.dynamic:
                self.n_steps = done + max(1, math.ceil((stage.duration_s - (eng.time_s - self.stage_t0))
                                                       / new_dt))
            self.dt, self.limit = new_dt, new_limit
            self.step_cuts += 1
            return True
        if rc == K.RC_NONFINITE:
            eng.restore(snap)
            return self._stop("unstable", (
                f"a non-finite value appeared within steps {done}..{done + steps} at "
                f"Δt = {self.dt:.4g} s (stable limit {self.limit:.4g} s); the state of step {done} is "
                "kept — lower the time step or check the joint stiffnesses"))
        # the step follows the contacts: one that formed in this chunk may be stiffer (or its
        # blocks lighter) than any at the chunk's start. Above the stable limit the chunk is done
        # again with the new step; within it (the safety factor's margin) the new step applies
        # from here on
        guard = (rc in (K.RC_CONVERGED, K.RC_OVERLAP) or done + steps >= self.n_steps
                 or done + steps - self.guarded >= T.GUARD_EVERY)
        if guard:
            self.guarded = done + steps
            new_dt, new_limit = _auto_time_step(eng, self.safety, self.beta)
            redo = math.isfinite(new_limit) and self.dt > new_limit
            if redo and stage.time_step_s is not None:
                eng.restore(snap)
                return self._stop("unstable", (
                    f"contacts that formed during the stage lower the stable time step "
                    f"to {new_limit:.4g} s, below the stage's time_step_s = {self.dt:.4g} s; "
                    f"the state of step {done} is kept"))
            if (stage.time_step_s is None and math.isfinite(new_limit)
                    and self.dt > new_dt * (1 + T.STEP_CUT_SLACK)):
                self._shorter_step(new_dt, new_limit, kept=0 if redo else steps)
                if redo:
                    eng.restore(snap)
                    out[7] = ke_check
                    return True
        return self._after_chunk(rc, steps, dt_used, guard)

    def _after_chunk(self, rc: int, steps: int, dt_used: float, guard: bool) -> bool:
        """Book the chunk's steps; record; stop on overlap, a ledger that does not close or
        convergence; take out failing blocks. False when the stage stops."""
        eng, stage, rec = self.eng, self.stage, self.rec
        self.done += steps
        done = self.done
        eng.time_s += steps * dt_used
        if self.progress is not None:
            self.progress(done, self.n_steps, stage.name)
        self.ratio = self.out[1]
        if self.dynamic:
            rec.track_peaks()
        if rc == K.RC_OVERLAP:
            return self._stop("overlap", _overlap_diagnostic(eng, int(self.out[3]), self.out[2], self.dt))
        if rc == K.RC_REBUILD:
            eng.rebuild()
        if done % self.chunk == 0 or done == self.n_steps or rc == K.RC_CONVERGED:
            rec.record(stage.name, self.ratio)
        if guard and not self._ledger_closes():
            return False
        if self.frame_every and done % self.frame_every == 0 and done < self.n_steps:
            rec.frame(stage.name, done)
        if rc == K.RC_CONVERGED:
            return self._stop("converged", None)
        if self.watch is not None and done % self.chunk == 0:
            going = self.watch.check()
            if len(going):
                gone, energy_out = _remove_failed(eng, self.watch, going)
                self.failed += gone
                self.removed_j += energy_out
                self.out[7] = math.inf
        return True

    def _ledger_closes(self) -> bool:
        """The energy guard: False (status ``unstable``) when the residual exceeds the tolerance."""
        energy = _energy_ledger(self.eng, self.dt, self.ke0, self.se0, self.se0_shadow, self.removed_j,
                                self.bolts0)
        err = energy.relative_error
        if err <= self.settings.energy_tolerance:
            return True
        return self._stop("unstable", (
            f"the energy ledger does not close after {self.done} steps: residual "
            f"{energy['residual_j']:.4g} J is {err:.3g} of the energy turned over "
            f"(tolerance {self.settings.energy_tolerance}); Δt = {self.dt:.4g} s, stable "
            f"limit {self.limit:.4g} s — a block was thrown by a contact the time step "
            "did not resolve; lower time_step_safety"))

    def _final_status(self, worst_block: int, worst_ratio: float) -> tuple[str, str | None, bool]:
        """(status, diagnostic, converged apart from the failed blocks)."""
        status, diagnostic, failed = self.status, self.diagnostic, self.failed
        converged_rest = status == "converged"
        if failed and status in ("converged", "max_steps"):
            diagnostic = (f"{len(failed)} block(s) kept moving and were taken out: "
                          + ", ".join(f"{f.block} ({f.mechanism}, {f.area_m2:.3g} m²)"
                                      for f in failed[:10]) + (" …" if len(failed) > 10 else "")
                          + ("; the rest reached equilibrium" if status == "converged" else
                             "; the rest did not reach equilibrium within max_steps"))
            status = "failed_blocks"
        if status == "max_steps":
            diagnostic = (f"no equilibrium within max_steps = {self.done} steps: model ratio "
                          f"{self.ratio:.3g} (tolerance {self.stage.tolerance}), worst block "
                          f"{worst_block} at {worst_ratio:.3g} (block tolerance "
                          f"{self.stage.block_tolerance})")
        return status, diagnostic, converged_rest

    def result(self) -> StageResult:
        """The stage's report: status, steps, displacements, contacts, energy."""
        eng, stage, settings, ref = self.eng, self.stage, self.settings, self.ref
        removed = ~eng.active & (eng.model.region > 0) & ~eng.failed
        disp_ref = eng.vertex_displacement(*ref)
        disp_stage = eng.vertex_displacement(self.stage_pos, self.stage_rot)
        live = eng.active
        counted = live & (eng.model.area_m2 >= settings.sliver_area_m2)
        boundary = _boundary_blocks(eng, removed)
        slipping, n_open, n_broken = _contact_counts(eng)
        energy = _energy_ledger(eng, self.dt, self.ke0, self.se0, self.se0_shadow, self.removed_j,
                                self.bolts0)
        worst_block, worst_ratio = int(self.out[6]), float(self.out[5])
        status, diagnostic, converged_rest = self._final_status(worst_block, worst_ratio)
        ratio, limit = self.ratio, self.limit
        return StageResult(
            name=stage.name, kind=stage.kind, status=status, steps=self.done, time_step_s=float(self.dt),
            stable_time_step_s=float(limit) if math.isfinite(limit) else 0.0,
            simulated_time_s=float(eng.time_s - self.stage_t0),
            converged=converged_rest if not self.dynamic else None,
            unbalanced_ratio=float(ratio) if math.isfinite(ratio) else 0.0,
            max_displacement_m=float(disp_ref[live].max(initial=0.0)),
            max_displacement_boundary_m=float(disp_ref[boundary].max(initial=0.0)),
            max_displacement_stage_m=float(disp_stage[live].max(initial=0.0)),
            max_displacement_equilibrium_m=float(disp_ref[counted].max(initial=0.0)),
            max_displacement_boundary_equilibrium_m=float(disp_ref[boundary & counted].max(initial=0.0)),
            monitors=_monitor_displacements(self.points, eng, ref),
            worst_block=worst_block, worst_ratio=min(worst_ratio, 1e300),
            failed_blocks=[f.to_dict() for f in self.failed],
            slipping_contacts=slipping, open_contacts=n_open,
            newly_broken_contacts=int(eng.E[K.E_NEW_BROKEN]), broken_contacts=n_broken,
            detached_blocks=_detached(eng, removed), blocks_removed=int(removed.sum()),
            energy=energy, wall_time_s=time.perf_counter() - self.wall0,
            contact_rebuilds=int(eng.n_rebuilds - self.rebuilds0), diagnostic=diagnostic,
            time_step_cuts=self.step_cuts)


def reference_stage(settings: Settings) -> int | None:
    """The stage whose end is the reference state of the run's displacements (and of the cracks
    a study counts as new): the first, when it is static, excavates nothing and other stages
    follow — the initial equilibrium under gravity and in-situ stress; None: the start."""
    first = settings.stages[0]
    if first.kind == "static" and not first.excavate and len(settings.stages) > 1:
        return 0
    return None


def run(model, settings: Settings, *,
        progress: Callable[[int, int, str], None] | None = None) -> Result:
    """Solve a :class:`~rockmass.blockgen.BlockModel` stage by stage (see the module docstring).

    ``progress(done, total, stage_name)``, if given, is called after every chunk of steps (a few
    hundred) with the steps done in the current stage, its step budget (a static stage may converge
    before it) and the stage's name.

    Raises ``ValueError`` for settings that do not fit the model (a selector choosing no block, a
    time step above the stable limit, quiet boundaries without moduli); a run that fails while
    stepping returns a Result with ``status`` ``overlap`` or ``unstable`` and a diagnostic.
    """
    zoned = zone_model(model, settings)
    if zoned is not None:  # docs/dem.md §16.8: the deformable blocks' zones are pieces
        model = zoned.model
    waves = wave_checks(zoned, settings)  # docs/dem.md §16.9: zones per wavelength
    warn_coarse_zones(waves)
    eng = Engine(model, settings, zoned)
    eng.detect()
    if settings.insitu is not None:
        apply_insitu(eng, settings.insitu)
    apply_boundary_stress(eng, settings.boundary_stress, settings.insitu)
    rec = _Recorder(eng, settings)
    ref = (eng.pos0.copy(), np.zeros(eng.nb))
    stages = []
    status, diagnostic = STATUS_OK, None
    dug: list[int] = []
    points = []
    for i, stage in enumerate(settings.stages):
        new = [r for r in stage.excavate if r not in dug]
        if new:  # the opening grew: its crown, walls and invert are found again
            dug += new
            points = boundary_points(model, dug)
        res = _StageRun(eng, stage, settings, rec, ref, progress, points).run()
        stages.append(res)
        if res.status in FAILED_STATUSES:
            status, diagnostic = res.status, res.diagnostic
            break
        if res.failed_blocks and status == STATUS_OK:
            status, diagnostic = STATUS_FAILED_BLOCKS, res.diagnostic
        if i == reference_stage(settings):
            ref = (eng.pos.copy(), eng.rot.copy())  # displacements after initial equilibrium
    mass = eng.mass[:, 0]
    block_energy = {"volume_m3": model.area_m2.copy(), "mass_kg": mass.copy(),
                    "peak_velocity_m_s": rec.peak_v.copy(),
                    "peak_kinetic_energy_j": 0.5 * mass * rec.peak_v ** 2}
    info = {"blocks": eng.nb, "rounding_m": eng.rounding_m, "contact_tolerance_m": eng.ctol_m,
            "overlap_limit_m": eng.overlap_limit_m, "pairs": int(len(eng.pa)),
            "fixed_dofs": int((eng.base_mode == FIXED).sum())}
    if zoned is not None:
        info.update(monitor_blocks={name: int(b) for name, b in rec.monitors},
                    zones=int(len(zoned.tri)), nodes=int(len(zoned.nodes)),
                    deformable_blocks=int(len(np.unique(zoned.parent[zoned.zone_of >= 0]))))
    if waves:
        info["wave_checks"] = waves
    return Result(stages=stages, displacement_m=eng.pos - eng.pos0, rotation_rad=eng.rot.copy(),
                  velocity_m_s=eng.vel.copy(), active=eng.active.copy(), history=rec.history(),
                  contacts=eng.contact_table(),
                  frames=rec.frames, block_energy=block_energy, status=status,
                  diagnostic=diagnostic, info=info, failed=eng.failed.copy(),
                  bolts=bolt_table(eng), zones=zone_table(eng),
                  pieces=model if zoned is not None else None)
