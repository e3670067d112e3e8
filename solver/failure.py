"""Blocks that keep moving in a static stage: detected, classified and taken out of the model.

A static stage asks for equilibrium. A keyblock falling from the roof or sliding down a joint into
the opening never gets there: with local damping α a free block still accelerates at (1 − α) g, so
the distance it covers grows with the square of the step count and any "maximum displacement"
measured at a step cap is set by the cap, not by the rock (issue 14). UDEC leaves this judgement
to the user (histories of velocity at chosen points: a velocity that keeps rising means failure;
Itasca, UDEC manual, "Problem solving with UDEC"); here it is automatic:

A block is **failing** when, at ``checks`` consecutive checks (one per chunk of steps), its speed
|v| + |ω| r has not fallen (≥ ``_NOT_SLOWING`` × its value at the check before) and it has moved
more than ``failure_displacement_m`` since the stage began. Blocks in equilibrium lose their speed
quickly under local damping and move by elastic amounts (σ/k_n per joint: millimetres for the
cavern samples), so neither test alone but both together single out blocks that are still going.

Each failing block is classified by how it moved since the stage began:

- ``rotation``: the arc of its rim, |Δθ| r, exceeds half its centroid's translation (a block
  toppling about a corner moves its centroid by about that arc; a sliding or falling block hardly
  turns);
- ``fall``: otherwise, when its contacts carry less than ``_FALL_SUPPORT`` of its weight;
- ``slide``: otherwise (it moves while in contact: along a joint).

The runner removes failing blocks from the model (as an excavation removes blocks: inactive, no
contacts) and lets the rest of the stage go on to equilibrium; the stage reports them by id,
area, mechanism, displacement and position, and its displacement measures are taken over the
blocks that remain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FailureWatch", "FailedBlock"]

_NOT_SLOWING = 0.9   # speed at a check at least this fraction of the one before: not settling
_FALL_SUPPORT = 0.05  # contacts carrying less than this fraction of the weight: free fall


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

    def to_dict(self) -> dict:
        return {"block": self.block, "area_m2": self.area_m2, "mechanism": self.mechanism,
                "displacement_m": self.displacement_m, "x_m": self.x_m, "y_m": self.y_m,
                "sliver": self.sliver}


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
        self.speed = np.zeros(engine.nb)
        self.run = np.zeros(engine.nb, np.int64)

    def check(self) -> np.ndarray:
        """Update the counters with the present state; the ids of blocks whose failure is
        established (active, movable, not slowing for ``checks`` checks, moved far enough)."""
        e = self.eng
        speed = np.hypot(e.vel[:, 0], e.vel[:, 1]) + np.abs(e.omg) * e.radius
        going = e.movable & e.active & (speed > 0) & (speed >= _NOT_SLOWING * self.speed)
        self.run = np.where(going, self.run + 1, 0)
        self.speed = speed
        cand = np.flatnonzero(self.run >= self.checks)
        if not len(cand):
            return cand
        moved = e.vertex_displacement(self.start_pos, self.start_rot)[cand]
        return cand[moved > self.displacement_m]

    def classify(self, ids: np.ndarray) -> list[FailedBlock]:
        """Mechanism, displacement and position of each block in ``ids`` (call before removing
        them: the contact forces of the last step are read)."""
        e = self.eng
        disp = e.vertex_displacement(self.start_pos, self.start_rot)
        out = []
        for b in ids:
            b = int(b)
            translation = float(np.hypot(*(e.pos[b] - self.start_pos[b])))
            arc = abs(float(e.rot[b] - self.start_rot[b])) * float(e.radius[b])
            support = float(np.hypot(*e.contact_force_on(b)[:2]))
            weight = float(e.mass[b, 0] * np.hypot(*e.gravity))
            if arc > 0.5 * translation:
                mechanism = "rotation"
            elif support < _FALL_SUPPORT * weight:
                mechanism = "fall"
            else:
                mechanism = "slide"
            area = float(e.model.area_m2[b])
            out.append(FailedBlock(block=b, area_m2=area, mechanism=mechanism,
                                   displacement_m=float(disp[b]), x_m=float(e.pos[b, 0]),
                                   y_m=float(e.pos[b, 1]), sliver=area < self.sliver_area_m2))
        return out
