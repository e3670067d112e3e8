"""Numeric policy of the DEM solver: every tolerance, guard and safety factor, with its reason.

Lengths are given in rounding lengths d (the corner rounding of docs/dem.md §3), so they scale with
the model; forces and energies as fractions. The values here are read by :mod:`.engine` and
:mod:`.runner`; the ones the numba kernels use reach them at run time through the parameter vector
(``PRM_*`` of :mod:`._kernels`, filled by :meth:`rockmass.solver.engine.Engine.kernel_params`), so
editing a value here takes effect without a stale compiled kernel (numba's on-disk cache only
watches the file a kernel is defined in).

This module imports nothing heavy: it is safe to read at CLI start-up.
"""

from __future__ import annotations

__all__ = [
    "BOND_GAP_ROUNDINGS", "CHECK_EVERY", "COLLINEAR_ROUNDINGS", "CY_PROBE_FLOOR_PA", "CY_PROBE_STRESS_FACTOR",
    "CY_REVERSAL_CLAMP", "CY_SLIPPING_F", "DEGENERATE_DISTANCE", "DOMAIN_EDGE_FRACTION",
    "DYNAMIC_RECORDS", "DYNAMIC_STEP_SAFETY", "FACE_MIN_FRACTION", "FACING_COS",
    "FAILURE_ROUNDINGS", "FAIL_KEEP_GOING", "FAIL_MIN_RECENT", "FAIL_ROTATION_ARC", "FALL_SUPPORT",
    "FREE_FLIGHT_STEPS", "GUARD_EVERY", "HYSTERESIS_ROUNDINGS", "MARGIN_EDGE_FRACTION",
    "MARGIN_TOLERANCES", "NO_DILATION_LIMIT_M", "OVERLAP_LIMIT_ROUNDINGS",
    "REBUILD_MARGIN_FRACTION", "SLEEP_CREEP", "SLEEP_RATIO_OF_TOLERANCE", "SLEEP_STEPS",
    "STATIC_CHUNK", "STATIC_STEP_SAFETY", "STEP_CUT_SLACK", "TINY", "WAKE_FACTOR",
]

# --- contact geometry (docs/dem.md §3) ---------------------------------------------------------

#: Largest admissible overlap of two rounded blocks, in rounding lengths d. Beyond d/2 a corner has
#: pushed past the arc that rounds it and the contact normal no longer follows the geometry, so
#: the run stops with a diagnostic naming the two blocks (UDEC's rule, Cundall 1988).
OVERLAP_LIMIT_ROUNDINGS = 0.5

#: Hysteresis of the reference-edge choice, in d: the other block's edge takes over as reference
#: only when it separates better by this much, so coincident faces (both score ≈ 0) do not flip
#: the normal every step. Far above round-off of the separations (~1e-16 of the model size), far
#: below any real rotation of a contact.
HYSTERESIS_ROUNDINGS = 0.01

#: A block vertex less than this many d off the straight line through its two neighbours is a
#: straight-on vertex (a T-junction kept by blockgen, or one snapped to within round-off) and is
#: dropped from the contact geometry (:func:`rockmass.solver.engine.strip_collinear`): the contact
#: model resolves nothing finer than d, and such a vertex splits one face into collinear pieces.
#: The 1e-9 relative turn used before missed the round-off of snapped vertices 100 m from the
#: origin (turns of 4e-7 on a 10⁴-block trace map), whose pieces then touched at a point.
COLLINEAR_ROUNDINGS = 0.01

#: Cosine below which two edge normals count as facing each other (anti-parallel within about 8°).
#: Only such edges compete to be the incident edge by their overlap with the reference edge; it
#: keeps a snapped, near-collinear piece of a face from winning by a hair.
FACING_COS = -0.99

#: A corner that activates a slot with a gap of less than this many d counts as touching from the
#: start (a bond of the block model), not as a new touch across a gap (which starts broken).
BOND_GAP_ROUNDINGS = 1e-6

#: A clipped overlap shorter than this fraction of the reference edge's length is a point, not a
#: face: the contact is treated as a rounded corner (one slot).
FACE_MIN_FRACTION = 1e-12

#: Distance between the inner polygons of two rounded blocks below this fraction of (radii + edge
#: length) has no direction: the sharp separation along the reference normal is used instead.
DEGENERATE_DISTANCE = 1e-9

#: Guard of divisions by a length or stress that can be exactly 0 (clipped edges of zero extent,
#: slots of zero length): far below any physical length or stress, far above the smallest normal
#: double (2.2e-308).
TINY = 1e-300

#: The broad phase grows bounding boxes by a margin of this many contact tolerances (plus joint
#: opening and dilation) ...
MARGIN_TOLERANCES = 2.0

#: ... and by at least this fraction of the median edge, so that a model with a tiny tolerance
#: still finds its neighbours and does not rebuild the pair list every few steps.
MARGIN_EDGE_FRACTION = 0.02

#: The pair list is rebuilt when a block has moved (centroid shift + radius × rotation) more than
#: this fraction of the margin since the last broad phase: two blocks approaching each other then
#: close at most one margin, so no contact is missed.
REBUILD_MARGIN_FRACTION = 0.5

#: Tolerance of the domain-edge selectors (``left``, ``top``, …), as a fraction of the median block
#: edge: points within it of the domain's bounding box lie on that side.
DOMAIN_EDGE_FRACTION = 1e-6

#: Stand-in for an unlimited dilation (max_dilation_m = inf): the kernels use finite numbers only.
NO_DILATION_LIMIT_M = 1e300

# --- joint laws (docs/dem.md §5–§6) ------------------------------------------------------------

#: Upper clamp of the continuously yielding joint's reversal ratio r (eq. (6.4)): F = (1 − τ/τ_m)
#: / (1 − r) would divide by 0 at r = 1 (a reversal exactly at the bounding strength).
CY_REVERSAL_CLAMP = 0.999999

#: A continuously yielding slot whose stiffness factor F (eq. (6.4)) is below this counts as
#: slipping in the reports; the law itself has no sharp yield point.
CY_SLIPPING_F = 0.05

#: The time-step bound takes a continuously yielding joint's tangent stiffness a σ^e at this
#: multiple of its present normal stress (the stress can rise within the next chunk) ...
CY_PROBE_STRESS_FACTOR = 2.0

#: ... and at no less than this stress (Pa), so that an unloaded contact with e > 0 still counts.
CY_PROBE_FLOOR_PA = 1.0

# --- stepping, guards and records (docs/dem.md §2.3, §10) --------------------------------------

#: Default fraction of the stable step (the Gershgorin limit 2/ω_g ≤ 2/ω_max of docs/dem.md §2.3)
#: in static stages: only the equilibrium matters there, and half the limit leaves room for
#: contacts that form within a chunk.
STATIC_STEP_SAFETY = 0.5

#: Default fraction of the stable step in dynamic stages. The central-difference scheme meets a
#: contact that closes or opens within a step with the wrong phase, and an elastic impact gains
#: or loses energy of order (ωΔt)² (docs/dem.md §2.4; measured by benchmarks/bench_dynamics.py:
#: ±4.5 % per impact at 0.5, ±0.3 % at 0.2). 0.2 keeps a typical impact within 1 %, at 2.5×
#: the steps of 0.5; UDEC's rigid-block step is more cautious still (docs/dem.md §2.4).
DYNAMIC_STEP_SAFETY = 0.2

#: Static stages test for equilibrium every this many steps (the kinetic energy must not have grown
#: since the previous test, so the interval must span several steps of a block's oscillation).
CHECK_EVERY = 10

#: Steps between records (history row, failure watch) in static stages.
STATIC_CHUNK = 500

#: Records per dynamic stage when the stage gives no ``history_every``.
DYNAMIC_RECORDS = 400

#: Steps between the time-step and energy-ledger guards (also run at a stage's end, at convergence
#: and at an overlap): often enough to catch a contact the step cannot resolve before it throws a
#: block, rarely enough to cost < 1 % of the stepping.
GUARD_EVERY = 200

#: The step is cut when the safe step has fallen by more than this fraction; smaller drops are
#: within the safety factor's margin and do not restart the chunk.
STEP_CUT_SLACK = 0.01

#: Steps of a stage with no contact at all (free flight): the step only sets the record interval.
FREE_FLIGHT_STEPS = 1000

#: A dynamic stage with an automatic step warns when the stiffness-proportional Rayleigh term cuts
#: its stable time step by more than this factor (docs/dem.md §8.2; βω_max > 1.5): the run is then
#: that many times slower for damping frequencies no input carries.
DAMPED_STEP_WARN_FACTOR = 2.0

#: Default failure displacement of the static failure watch, in rounding lengths d: well above the
#: elastic closure of a joint under load, well below any real fall or slide.
FAILURE_ROUNDINGS = 0.25

#: A block is still going (not settling) when over the last window of checks it moved at least this
#: fraction of what it moved over the window before: under local damping a settling block's
#: motion shrinks geometrically, a falling or sliding one's does not (:mod:`.failure`).
FAIL_KEEP_GOING = 0.5

#: ... and at least this fraction of the failure displacement over the last window (elastic
#: creep of a block at rest does not count).
FAIL_MIN_RECENT = 0.1

#: A failing block rotates when the arc of its rim, |Δθ| r, exceeds this fraction of its centroid's
#: translation (a block toppling about a corner moves its centroid by about that arc).
FAIL_ROTATION_ARC = 0.5

#: A failing block that does not rotate falls when its contacts carry less than this fraction of its
#: weight; otherwise it slides.
FALL_SUPPORT = 0.05

# --- sleeping blocks (docs/dem.md §10.2) ---------------------------------------------------------

#: A block sleeps once its own unbalanced-force ratio stays below this fraction of the stage's
#: tolerance ...
SLEEP_RATIO_OF_TOLERANCE = 0.1

#: ... for this many consecutive steps ...
SLEEP_STEPS = 100

#: ... while moving less than this fraction of d over those steps (its speed limit).
SLEEP_CREEP = 1e-3

#: A sleeping block wakes when its ratio exceeds this multiple of the sleep ratio: a neighbour has
#: moved. The gap between the two thresholds keeps a block from toggling every step.
WAKE_FACTOR = 10.0

# --- rock bolts (docs/dem.md §15) ----------------------------------------------------------------

#: A pattern bolt's head starts this fraction of its length inside the rock: on the wall itself,
#: round-off can leave it in the opening, where no block hosts it.
BOLT_HEAD_INSET = 1e-6
