"""Blocks that keep moving in a static stage: detected, classified and taken out of the model.

A static stage asks for equilibrium. A keyblock falling from the roof or sliding down a joint into
the opening never gets there: with local damping α a free block still accelerates at (1 − α) g, so
the distance it covers grows with the square of the step count and any "maximum displacement"
measured at a step cap is set by the cap, not by the rock (issue 14). UDEC leaves this judgement
to the user (histories of velocity at chosen points: a velocity that keeps rising means failure;
Itasca, UDEC manual, "Problem solving with UDEC"); here it is automatic:

A block is **failing** when it has moved more than ``failure_displacement_m`` since the stage
began and its motion is not dying out: over the last ``checks`` checks (one per chunk of steps) it
moved at least ``FAIL_KEEP_GOING`` (:mod:`.tolerances`) times as far as over the ``checks``
checks before, and at least a tenth of the threshold. Blocks on their way to equilibrium move
less and less under local damping (and by elastic amounts: σ/k_n per joint, millimetres for the
cavern samples); a block that falls, slides or creeps in stick-slip keeps covering ground. Measuring distance over windows of checks,
not the speed at one instant, keeps a chattering slide from resetting the count.

Each failing block is classified by how it moved since the stage began:

- ``rotation``: the arc of its rim, |Δθ| r, exceeds half its centroid's translation (a block
  toppling about a corner moves its centroid by about that arc; a sliding or falling block hardly
  turns);
- ``fall``: otherwise, when its contacts carry less than ``FALL_SUPPORT`` of its weight;
- ``slide``: otherwise (it moves while in contact: along a joint).

The runner removes failing blocks from the model (as an excavation removes blocks: inactive, no
contacts) and lets the rest of the stage go on to equilibrium; the stage reports them by id,
area, mechanism, displacement and position, and its displacement measures are taken over the
blocks that remain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .tolerances import FAIL_KEEP_GOING, FAIL_MIN_RECENT, FAIL_ROTATION_ARC, FALL_SUPPORT

__all__ = ["FailureWatch", "FailedBlock", "MECHANISMS", "mechanism_counts"]

#: The mechanisms a failed block is classified by, in the order reports list them.
MECHANISMS = ("fall", "slide", "rotation")



@dataclass(frozen=True)
class FailedBlock:
    """One block taken out of a static stage because it kept moving."""

    block: int
    area_m2: float
    mechanism: str
    displacement_m: float
    x_m: float
    y_m: float
    sliver: bool
    time_s: float  # simulated time when it was taken out (the run's clock)

    def to_dict(self) -> dict:
        return {"block": self.block, "area_m2": self.area_m2, "mechanism": self.mechanism,
                "displacement_m": self.displacement_m, "x_m": self.x_m, "y_m": self.y_m,
                "sliver": self.sliver, "time_s": self.time_s}


class FailureWatch:
    """Tracks the blocks of one static stage from check to check (see the module docstring).

    Parameters
    ----------
    engine : Engine
        The DEM state (positions, velocities, contact forces of the last step).
    displacement_m : float
        A block must have moved this far in the stage to count as failing.
    checks : int
        Consecutive checks without slowing down that establish the failure.
    sliver_area_m2 : float
        Failing blocks smaller than this are flagged ``sliver`` (reported apart).
    """

    def __init__(self, engine, displacement_m: float, checks: int, sliver_area_m2: float):
        self.eng = engine
        self.displacement_m = displacement_m
        self.checks = checks
        self.sliver_area_m2 = sliver_area_m2
        self.start_pos = engine.pos.copy()
        self.start_rot = engine.rot.copy()
        self.track = []  # displacement from the stage start at each check (last 2·checks + 1)

    def check(self) -> np.ndarray:
        """Record the present displacements; the ids of blocks whose failure is established
        (active, movable, moved far enough and not slowing down, see the module docstring)."""
        e = self.eng
        self.track.append(e.vertex_displacement(self.start_pos, self.start_rot))
        self.track = self.track[-(2 * self.checks + 1):]
        if len(self.track) < 2 * self.checks + 1:
            return np.zeros(0, np.int64)
        now, mid, old = self.track[-1], self.track[-1 - self.checks], self.track[0]
        recent = now - mid
        going = (e.movable & e.active & (now > self.displacement_m)
                 & (recent >= FAIL_KEEP_GOING * (mid - old))
                 & (recent > FAIL_MIN_RECENT * self.displacement_m))
        if e.zoned is not None:  # a deformable block fails whole, when all its zones keep going
            going = _whole_blocks(going, e.zoned.parent, e.zone_of >= 0, e.active)
        return np.flatnonzero(going)

    def classify(self, ids: np.ndarray) -> list[FailedBlock]:
        """Mechanism, displacement and position of each block in ``ids`` (call right after the
        :meth:`check` that named them, before removing them: its displacements and the contact
        forces of the last step are read)."""
        e = self.eng
        disp = self.track[-1]
        out = []
        if e.zoned is not None:  # one report per deformable block: its zone nearest its middle
            ids = _one_piece_per_block(ids, e)
        for b in ids:
            b = int(b)
            translation = float(np.hypot(*(e.pos[b] - self.start_pos[b])))
            arc = abs(float(e.rot[b] - self.start_rot[b])) * float(e.radius[b])
            support = float(np.hypot(*e.contact_force_on(b)[:2]))
            weight = float(e.mass[b, 0] * np.hypot(*e.gravity))
            if arc > FAIL_ROTATION_ARC * translation:
                mechanism = "rotation"
            elif support < FALL_SUPPORT * weight:
                mechanism = "fall"
            else:
                mechanism = "slide"
            area = float(e.model.area_m2[b])
            if e.zoned is not None and e.zone_of[b] >= 0:  # the whole deformable block's
                area = float(e.model.area_m2[e.zoned.parent == e.zoned.parent[b]].sum())
            out.append(FailedBlock(block=b, area_m2=area, mechanism=mechanism,
                                   displacement_m=float(disp[b]), x_m=float(e.pos[b, 0]),
                                   y_m=float(e.pos[b, 1]), sliver=area < self.sliver_area_m2,
                                   time_s=float(e.time_s)))
        return out


def _whole_blocks(going: np.ndarray, parent: np.ndarray, zoned: np.ndarray,
                  active: np.ndarray) -> np.ndarray:
    """Zones fail only with their whole block: a zone keeps its flag when every active zone of
    its block keeps going (a block falling or sliding as a whole), else it is cleared (zones of a
    block that yields and creeps near a wall deform; they do not fall)."""
    out = going.copy()
    z = np.flatnonzero(zoned & active)
    if not len(z):
        return out
    blocks = parent[z]
    still = np.zeros(int(parent.max()) + 1, bool)
    still[blocks[~going[z]]] = True
    out[z] = going[z] & ~still[blocks]
    return out


def _one_piece_per_block(ids: np.ndarray, e) -> np.ndarray:
    """Rigid ids as they are; of the zones of one deformable block, the one nearest its middle."""
    from .deformable import piece_near_centre

    rigid = ids[e.zone_of[ids] < 0]
    blocks = np.unique(e.zoned.parent[ids[e.zone_of[ids] >= 0]])
    return np.concatenate([rigid, [piece_near_centre(e.zoned, e.model, b) for b in blocks]]
                          ).astype(np.int64)


def mechanism_counts(failed: list[dict]) -> dict[str, int]:
    """Failed blocks per mechanism (:data:`MECHANISMS` order, mechanisms with none left out) from
    :meth:`FailedBlock.to_dict` records."""
    counts = {m: sum(f["mechanism"] == m for f in failed) for m in MECHANISMS}
    return {m: n for m, n in counts.items() if n}
