"""Numba kernels of the DEM: world vertices, broad phase, narrow phase, joint laws, stepping.

All kernels take plain C-contiguous arrays (float64 values, int64 indices), or named tuples of
them, write into arrays the caller allocated and do no checks; :mod:`rockmass.solver.engine` is
the typed wrapper that owns the arrays and builds the tuples. One file, because numba's on-disk
cache does not see edits to jitted helpers (or to module constants) in other files; the numeric
policy (:mod:`rockmass.solver.tolerances`) therefore reaches the kernels at run time, in the
parameter vector ``prm`` (indices ``PRM_*``), not as frozen globals.

The formulation the kernels implement is docs/dem.md; section and equation numbers below refer
to it.

Data layout
-----------
Blocks ``b`` (:class:`Blocks`): vertices ``loc[off[b]:off[b+1]]`` relative to the centroid (CCW),
centroid ``pos[b]``, rotation ``rot[b]``, velocities ``vel[b]``, ``omg[b]``; per degree of freedom
(x, y, rotation) ``mode[b, d]`` 0 free, 1 fixed, 2 prescribed (velocity from
``presc_val[step, dof_input[b, d]]``).

Pairs ``p`` (:class:`Pairs`, candidate contacts from the broad phase): blocks ``pa[p] < pb[p]``,
joint model row ``pprop[p]`` of ``props`` (columns ``P_*``), reference side ``pref[p]`` (0: an
edge of ``pa`` carries the normal, 1: of ``pb``), index of the block-model contact ``pinit[p]``
(-1 if the two blocks were not neighbours). Each pair has two *slots* (the two ends of an
edge-to-edge contact, UDEC's two vertex-edge sub-contacts; a corner contact uses one) with state
``S[p, slot, column]``.

Contact state ``S[p, k, :]`` (docs/dem.md §4, Table 4.1)
--------------------------------------------------------
Signs: the unit normal n points from ``pa`` to ``pb``, the tangent is t = (−n_y, n_x); normal
quantities are positive in compression (closure), shear quantities positive when ``pb`` moves
along +t relative to ``pa``. Forces are per metre of thickness (2D, unit thickness).

======  =====  =====================================================================  ==========
column  sym.   meaning                                                                unit
======  =====  =====================================================================  ==========
ACT            1: slot in contact (active); 0: open (every other column then stale)   flag
U0      u_0    normal closure offset added to the geometric overlap, set by the       m
               in-situ stress (u_n(σ₀) − δ on faces, −δ on corner touches); else 0
DIL     u_d    dilation: normal closure added by plastic shear (tan ψ or CY angle i)  m, ≥ 0
TAU     τ      shear stress                                                           Pa
PHIM    φ_m    continuously yielding: mobilised friction angle (φ_m⁰ at activation)   rad
RREV    r      continuously yielding: τ d/τ_m at the last shear reversal, d the new   1, < 1
               direction (0 before the first; used capped below 1)
DIR            continuously yielding: sign of the last shear increment (0: none yet)  ±1 or 0
COORD          slot point's coordinate along t about ``pa``'s centroid (matches a     m
               one-slot contact to the slot it used before)
BRK            1: broken — a bond that failed, or a contact that was never bonded     flag
LEN     l      contact length the slot stands for (half a face, or a corner's share)  m
FN      F_n    normal force σ_n l, compression positive                               N/m
FS      F_s    shear force τ l (sign of TAU)                                          N/m
SLIP           1: slipping at the last update (Coulomb at its strength under          flag
               compression; continuously yielding with F < ``CY_SLIPPING_F``)
OVL     δ      geometric overlap of the rounded blocks (negative: a gap)              m
PX, PY  x_c    contact point (world frame)                                            m
NX, NY  n      unit normal, from ``pa`` to ``pb``                                     1
USP     u_p    accumulated plastic shear displacement Σ|Δu_s^p|                       m, ≥ 0
NEW            1: activated since :func:`advance` last checked its stiffness          flag
FNA            F_n applied at the last update, dashpots included (deformable blocks   N/m
               take their contact forces from it, docs/dem.md §16.8)
FSA            F_s applied at the last update, dashpots included                      N/m
======  =====  =====================================================================  ==========

The normal closure the joint law sees is u_n = δ + u_0 + u_d (eq. (4.3)). Forces (eq. (4.5)): on
``pa`` −F_n n + F_s t, on ``pb`` +F_n n − F_s t, at the contact point.
"""

import math
from collections import namedtuple

import numpy as np
from numba import njit, types

# --- slot state columns (table above) -----------------------------------------------------------
(ACT, U0, DIL, TAU, PHIM, RREV, DIR, COORD, BRK, LEN, FN, FS, SLIP, OVL, PX, PY, NX, NY, USP,
 NEW, FNA, FSA) = range(22)
N_SLOT_COLUMNS = 22

# --- world vertex table columns (world_vertices) ------------------------------------------------
W_X, W_Y, W_NX, W_NY, W_CX, W_CY, W_TAN, W_RAD = range(8)
N_WV_COLUMNS = 8

# --- joint model table columns (rockmass.solver.engine.joint_table) -----------------------------
(P_MODEL, P_KN, P_KS, P_TANPHI, P_COH, P_TEN, P_TANPSI, P_TANPHIR, P_MAXDIL,
 P_EN, P_ES, P_PHIM0, P_PHIB, P_ROUGH) = range(14)
N_PROP_COLUMNS = 14
MODEL_COULOMB, MODEL_CY = 0, 1

# --- free-field column element table columns (free_field_step; rockmass.solver.free_field) -----
(FF_M, FF_KX, FF_KY, FF_ABOVE, FF_CX, FF_CY, FF_MODE_X, FF_MODE_Y, FF_IN_X, FF_IN_Y) = range(10)
N_FF_COLUMNS = 10

# --- bolt node table columns (bolt_step; rockmass.solver.bolts; docs/dem.md §15) ---------------
(BN_HOST, BN_RX, BN_RY, BN_AX, BN_AY, BN_M, BN_KG, BN_SG, BN_NEXT, BN_KA, BN_NT,
 BN_NC) = range(12)
N_BN_COLUMNS = 12
# --- bolt state columns: node (axial displacement, velocity, grout force and slip), and the
# segment from the node to the next (axial force, plastic elongation, yield flags)
(BS_U, BS_V, BS_G, BS_SLIP, BS_SLIPPING, BS_N, BS_EP, BS_YIELD, BS_YIELDED) = range(9)
N_BS_COLUMNS = 9

# --- energy accumulator entries (docs/dem.md §11) -----------------------------------------------
(E_GRAVITY, E_EXTERNAL, E_LOCAL_DAMP, E_VISCOUS, E_QUIET, E_CONTACT_FREE, E_CONTACT_PRESC,
 E_SLIP, E_BROKEN, E_NEW_BROKEN, E_NEW_SLOTS, E_BOLT_SLIP, E_BOLT_YIELD, E_ZONE_INTERNAL,
 E_ZONE_PLASTIC, E_ZONE_MIXED) = range(16)
N_ENERGY = 16

# --- return codes of advance() ------------------------------------------------------------------
RC_DONE, RC_REBUILD, RC_CONVERGED, RC_OVERLAP, RC_NONFINITE, RC_STIFF = range(6)

# --- the parameter vector prm (float64): the scalars of a call, then the numeric policy ----------
(PRM_DT,            # time step Δt (s); 0 for a detection pass without motion
 PRM_CTOL,          # contact detection gap (m)
 PRM_HYST,          # hysteresis of the reference edge (m)
 PRM_ROUNDING,      # rounding length d (m)
 PRM_OVL_LIMIT,     # overlap that stops the run (m)
 PRM_MARGIN,        # broad-phase margin of the present pair list (m)
 PRM_ALPHA_LOCAL,   # local damping coefficient α
 PRM_ALPHA_MASS,    # mass-proportional Rayleigh coefficient α_M (1/s)
 PRM_BETA,          # stiffness-proportional Rayleigh coefficient β (s)
 PRM_TOL_RATIO,     # model unbalanced-force ratio for equilibrium (0: no test, dynamic)
 PRM_BLOCK_TOL,     # every block's own ratio for equilibrium
 PRM_CHECK_EVERY,   # steps between equilibrium tests (integer value)
 PRM_SLEEP_RATIO,   # a block's ratio below which it may sleep (0: no sleeping)
 PRM_SLEEP_STEPS,   # calm steps before a block sleeps (integer value)
 PRM_SLEEP_SPEED,   # speed below which a block counts as calm (m/s)
 PRM_W2_NEW,        # ω² a new contact may have on its own (1/s²)
 PRM_WAKE,          # tolerances.WAKE_FACTOR
 PRM_REBUILD,       # tolerances.REBUILD_MARGIN_FRACTION
 PRM_CY_CLAMP,      # tolerances.CY_REVERSAL_CLAMP
 PRM_CY_SLIP_F,     # tolerances.CY_SLIPPING_F
 PRM_CY_PROBE,      # tolerances.CY_PROBE_STRESS_FACTOR
 PRM_CY_PROBE_FLOOR,  # tolerances.CY_PROBE_FLOOR_PA
 PRM_FACING_COS,    # tolerances.FACING_COS
 PRM_BOND_GAP,      # tolerances.BOND_GAP_ROUNDINGS
 PRM_FACE_MIN,      # tolerances.FACE_MIN_FRACTION
 PRM_DEGENERATE,    # tolerances.DEGENERATE_DISTANCE
 PRM_TINY,          # tolerances.TINY
 PRM_REF_X,         # presc_val column whose velocity the mass damping is relative to in x (-1: 0)
 PRM_REF_Y,         # the same in y
 ) = range(29)
N_PRM = 29

#: Per-block arrays (the blocks' geometry, inertia, degrees of freedom and motion) and the world
#: vertex scratch table ``wv`` (columns ``W_*``) the kernels fill. A block that is a zone of a
#: deformable block has its zone's index in ``zone_of`` (else -1): its vertices, centroid
#: motion, spin and strain rate ``srate`` (ε̇_xx, ε̇_yy, ε̇_xy) follow the zone's nodes
#: (:class:`Zoning`, docs/dem.md §16.8).
Blocks = namedtuple("Blocks", ["loc", "lgeo", "off", "radius", "mass", "inv_mass", "mode",
                               "dof_input", "active", "movable", "pos", "rot", "vel", "omg",
                               "asleep", "calm", "wv", "zone_of", "srate"])

#: The pair list with its slot state ``S``, joint-model table ``props``, per-pair forces ``fpair``
#: (fx_a, fy_a, m_a, fx_b, fy_b, m_b), the per-block CSR ``bp_ptr``/``bp_idx`` of
#: :func:`block_pair_index`, broken flags ``init_brk`` of the block-model contacts, and the block
#: placement ``ref_pos``/``ref_rot`` at the broad phase that made the list.
Pairs = namedtuple("Pairs", ["pa", "pb", "pprop", "pref", "pinit", "init_brk", "props", "S",
                             "fpair", "bp_ptr", "bp_idx", "ref_pos", "ref_rot"])

#: Applied loads: gravity (2,), external force ``ext_f`` (B, 2) and the two moment terms
#: ``ext_a``, ``ext_b`` (B,), quiet-boundary edges (Q, 8) (:func:`quiet_forces`), the
#: prescribed velocities ``presc_val`` (steps, inputs) at the half steps, the free-field
#: edges (F, 9), column elements (E, ``N_FF_COLUMNS``) and their state (E, 4)
#: (:func:`free_field_step`), and the bolt nodes (N, ``N_BN_COLUMNS``) and their state
#: (N, ``N_BS_COLUMNS``) (:func:`bolt_step`).
Loads = namedtuple("Loads", ["gravity", "ext_f", "ext_a", "ext_b", "quiet_edges", "presc_val",
                             "ff_edges", "ff_elem", "ff_state", "bolt_node", "bolt_state"])

#: The zones of deformable blocks (docs/dem.md §16): nodes (positions ``xy``, velocities, true and
#: integration masses, dof modes 0 free / 1 fixed / 2 prescribed with the ``presc_val`` column in
#: ``node_input``, external forces ``fext``), zones (``tri``, material row ``zmat`` of ``mtab``,
#: stress ``sig`` (``ZS_*``), strain, plastic state and strain, ``live`` flag, the block that
#: stands for each zone in the contact search ``zone_block``), ``mixed`` (1,) the nodal mixed
#: discretisation flag, and scratch (``fint``, ``fcon``, ``fabs``, ``node_ev``, ``node_a``,
#: ``presc``). Empty arrays when the model has no deformable block.
Zoning = namedtuple("Zoning", ["xy", "vel", "mass", "inv_mass", "mode", "node_input", "fext",
                               "tri", "zmat", "mtab", "sig", "strain", "state", "eps_p", "live",
                               "zone_block", "mixed", "fint", "fcon", "fabs", "node_ev", "node_a",
                               "presc"])


@njit(cache=True)
def world_vertices(loc, lgeo, off, pos, rot, active, wv):
    """World vertex table of the active blocks (columns ``W_*``): the vertex pos[b] + R(rot[b])
    loc[k], the outward unit normal R lgeo[k, :2] of the edge starting at it, its rounded corner's
    arc centre pos[b] + R lgeo[k, 2:4], tangent length lgeo[k, 4] and radius lgeo[k, 5]
    (:func:`rockmass.solver.engine.rounded_corners`)."""
    for b in range(len(off) - 1):
        if not active[b]:
            continue
        c = math.cos(rot[b])
        s = math.sin(rot[b])
        for k in range(off[b], off[b + 1]):
            wv[k, W_X] = pos[b, 0] + c * loc[k, 0] - s * loc[k, 1]
            wv[k, W_Y] = pos[b, 1] + s * loc[k, 0] + c * loc[k, 1]
            wv[k, W_NX] = c * lgeo[k, 0] - s * lgeo[k, 1]
            wv[k, W_NY] = s * lgeo[k, 0] + c * lgeo[k, 1]
            wv[k, W_CX] = pos[b, 0] + c * lgeo[k, 2] - s * lgeo[k, 3]
            wv[k, W_CY] = pos[b, 1] + s * lgeo[k, 2] + c * lgeo[k, 3]
            wv[k, W_TAN] = lgeo[k, 4]
            wv[k, W_RAD] = lgeo[k, 5]


@njit(types.int64[::1](types.float64[::1], types.int64), cache=True)
def _stable_argsort(keys, n):
    """Indices that sort keys[:n] (float64) ascending, ties in their input order, NaN last: what
    ``np.argsort(keys[:n], kind="mergesort")`` gives, as a bottom-up merge sort in plain loops
    (numba's own mergesort takes seconds to compile). ``fractal._kernels._sorted_ids`` is the
    same merge on integer ids (each kernel file stands alone)."""
    order = np.empty(n, np.int64)
    tmp = np.empty(n, np.int64)
    for i in range(n):
        order[i] = i
    width = 1
    while width < n:
        for lo in range(0, n, 2 * width):
            mid = min(lo + width, n)
            hi = min(lo + 2 * width, n)
            i = lo
            j = mid
            for k in range(lo, hi):
                if i < mid and j < hi:
                    a = keys[order[i]]
                    b = keys[order[j]]
                    # right before left only when strictly less (NaN counts as largest): stable
                    take_right = b < a or (a != a and b == b)
                else:
                    take_right = i >= mid
                if take_right:
                    tmp[k] = order[j]
                    j += 1
                else:
                    tmp[k] = order[i]
                    i += 1
        order, tmp = tmp, order
        width *= 2
    return order


@njit(cache=True)
def broad_phase(wv, off, active, movable, group, margin):
    """Candidate pairs (a < b) whose bounding boxes, grown by ``margin``, overlap (sweep and prune
    along x). Pairs of two blocks that cannot move are left out, and pairs of one ``group`` ≥ 0
    (the zones of one deformable block, held together by their nodes). Returns sorted (pa, pb)."""
    nb = len(off) - 1
    lo = np.empty((nb, 2))
    hi = np.empty((nb, 2))
    ids = np.empty(nb, np.int64)
    m = 0
    for b in range(nb):
        if not active[b]:
            continue
        x0 = np.inf
        y0 = np.inf
        x1 = -np.inf
        y1 = -np.inf
        for k in range(off[b], off[b + 1]):
            x0 = min(x0, wv[k, 0])
            x1 = max(x1, wv[k, 0])
            y0 = min(y0, wv[k, 1])
            y1 = max(y1, wv[k, 1])
        lo[b, 0] = x0 - margin
        lo[b, 1] = y0 - margin
        hi[b, 0] = x1 + margin
        hi[b, 1] = y1 + margin
        ids[m] = b
        m += 1
    x_lo = np.empty(m)
    for i in range(m):
        x_lo[i] = lo[ids[i], 0]
    srt = _stable_argsort(x_lo, m)
    order = np.empty(m, np.int64)
    for i in range(m):
        order[i] = ids[srt[i]]
    cap = 8 * m + 16
    pa = np.empty(cap, np.int64)
    pb = np.empty(cap, np.int64)
    n = 0
    for i in range(m):
        a = order[i]
        for j in range(i + 1, m):
            b = order[j]
            if lo[b, 0] > hi[a, 0]:
                break
            if lo[b, 1] > hi[a, 1] or lo[a, 1] > hi[b, 1]:
                continue
            if not movable[a] and not movable[b]:
                continue
            if group[a] >= 0 and group[a] == group[b]:
                continue
            if n == cap:
                cap *= 2
                pa2 = np.empty(cap, np.int64)
                pb2 = np.empty(cap, np.int64)
                for q in range(n):
                    pa2[q] = pa[q]
                    pb2[q] = pb[q]
                pa = pa2
                pb = pb2
            pa[n] = min(a, b)
            pb[n] = max(a, b)
            n += 1
    # sorted by (pa, pb), i.e. by the unique key pa nb + pb: two stable counting sorts, by pb
    # then by pa (the pairs are unique, so this is the order any sort of the key gives)
    cnt = np.zeros(nb + 1, np.int64)
    tmp = np.empty(n, np.int64)
    for q in range(n):
        cnt[pb[q] + 1] += 1
    for b in range(nb):
        cnt[b + 1] += cnt[b]
    for q in range(n):
        tmp[cnt[pb[q]]] = q
        cnt[pb[q]] += 1
    for b in range(nb + 1):
        cnt[b] = 0
    for q in range(n):
        cnt[pa[q] + 1] += 1
    for b in range(nb):
        cnt[b + 1] += cnt[b]
    out_a = np.empty(n, np.int64)
    out_b = np.empty(n, np.int64)
    for r in range(n):
        q = tmp[r]
        k = cnt[pa[q]]
        cnt[pa[q]] += 1
        out_a[k] = pa[q]
        out_b[k] = pb[q]
    return out_a, out_b


# explicit signatures for helpers that callers pass literal arguments (0, 1, -1): without them numba
# compiles one version per literal (C arrays: _WV the world vertex table, _OFF the offsets)
_WV = types.float64[:, ::1]
_OFF = types.int64[::1]


@njit(types.Tuple((types.float64,) * 6 + (types.int64,))(_WV, _OFF, types.int64, types.int64),
      cache=True)
def _edge(wv, off, b, i):
    """Start, unit direction, outward unit normal and end vertex of edge i (global index)."""
    j = i + 1
    if j == off[b + 1]:
        j = off[b]
    nx = wv[i, 2]
    ny = wv[i, 3]
    return wv[i, 0], wv[i, 1], -ny, nx, nx, ny, j


@njit(cache=True)
def _max_separation(wv, off, a, b, stop, eps):
    """Separating-axis test over the edges of block a: the largest over a's edges of the smallest
    signed distance of b's vertices to the edge's line; stops early once above ``stop``.

    Ties within ``eps`` (common when blocks share a face: the edges next to the face pass through
    the shared corner and also score 0) go to the edge whose two nearest vertices of b are closest
    together in distance, i.e. the edge that faces an edge of b. Returns (sep, edge).

    An edge is left as soon as one vertex of b lies more than ``eps`` below the best separation
    so far: its smallest distance can only fall further, so it cannot be chosen (the result is
    the same; on blocks of 5-6 vertices most edges face away from b and are left after a vertex).
    """
    best = -np.inf
    best_gap = np.inf
    best_edge = -1
    for i in range(off[a], off[a + 1]):
        x0 = wv[i, 0]
        y0 = wv[i, 1]
        nx = wv[i, 2]
        ny = wv[i, 3]
        low = np.inf
        low2 = np.inf
        floor = best - eps
        for k in range(off[b], off[b + 1]):
            d = (wv[k, 0] - x0) * nx + (wv[k, 1] - y0) * ny
            if d < low:
                if d < floor:  # this edge can no longer be chosen
                    low = d
                    break
                low2 = low
                low = d
            elif d < low2:
                low2 = d
        if low < floor:
            continue
        gap = low2 - low
        if low > best + eps or (low >= best - eps and gap < best_gap):
            best = low
            best_gap = gap
            best_edge = i
            if best > stop:
                break
    return best, best_edge


# ------------------------------------------------------------------------------------------------
# Joint laws (docs/dem.md §5–§7). Each takes one slot's state row and the joint model row ``prop``
# and updates σ_n, τ, the flags and the dissipation accumulators ``E``.
# ------------------------------------------------------------------------------------------------


@njit(cache=True)
def _cy_normal_stress(an, en, un):
    """σ_n(u_n) for k_n = a_n σ_n^e_n integrated from σ = 0 at u = 0: ((1 − e) a u)^(1/(1 − e))
    (docs/dem.md §6, eq. (6.2))."""
    if un <= 0.0:
        return 0.0
    if en == 0.0:
        return an * un
    return ((1.0 - en) * an * un) ** (1.0 / (1.0 - en))


@njit(cache=True, inline="always")
def _is_bond(prop):
    """A joint model with cohesion or tensile strength: an intact contact of it is a bond
    (glued contact) that can fail (docs/dem.md §7)."""
    return prop[P_COH] > 0.0 or prop[P_TEN] > 0.0


@njit(cache=True, inline="always")
def _break_bond(S, p, k, E):
    """Mark slot k of pair p broken and count it (docs/dem.md §7); the caller books the energy."""
    S[p, k, BRK] = 1.0
    E[E_NEW_BROKEN] += 1.0


@njit(cache=True, inline="always")
def _slip_dissipation(tau_old, tau, dus, ks):
    """Energy per unit area dissipated by one slipping increment: the work of the mean shear stress
    over the step minus the change of elastic shear energy (docs/dem.md §11, eq. (11.3))."""
    return 0.5 * (tau_old + tau) * dus - 0.5 * (tau * tau - tau_old * tau_old) / ks


@njit(cache=True, inline="always")
def _coulomb_law(S, p, k, prop, un, dus, length, E):
    """Coulomb slip with cohesion, tension, dilation and residual friction (docs/dem.md §5,
    eqs. (5.1)–(5.7); a bond's failure, §7, eqs. (7.1)–(7.2)). ``un`` normal closure (m), ``dus``
    shear displacement increment (m)."""
    kn = prop[P_KN]
    ks = prop[P_KS]
    sig = kn * un  # eq. (5.1)
    intact = S[p, k, BRK] == 0.0
    ten = prop[P_TEN] if intact else 0.0
    if sig < -ten:  # eq. (5.3): the joint opens; an intact bond fails in tension, eq. (7.2)
        released = 0.5 * S[p, k, TAU] ** 2 / ks * length
        if intact and ten > 0.0:
            _break_bond(S, p, k, E)
            E[E_BROKEN] += 0.5 * sig * sig / kn * length + released
        else:
            E[E_SLIP] += released  # shear spring unloaded as the joint opens
        S[p, k, FN] = 0.0
        S[p, k, FS] = 0.0
        S[p, k, TAU] = 0.0
        return
    tanphi = prop[P_TANPHI] if intact else prop[P_TANPHIR]
    coh = prop[P_COH] if intact else 0.0
    tmax = max(coh + sig * tanphi, 0.0)  # eq. (5.4)
    tau_old = S[p, k, TAU]
    tau = tau_old + ks * dus  # eq. (5.2), elastic trial
    if abs(tau) > tmax:
        if intact and _is_bond(prop):  # eq. (7.1): the bond fails in shear, residual strength
            _break_bond(S, p, k, E)
            tmax = max(sig * prop[P_TANPHIR], 0.0)
        sgn = 1.0 if tau > 0 else -1.0
        dup = (abs(tau) - tmax) / ks  # eq. (5.5), plastic shear increment
        tau = sgn * tmax
        released = _slip_dissipation(tau_old, tau, dus, ks)
        ddil = 0.0
        if prop[P_TANPSI] > 0.0 and S[p, k, DIL] < prop[P_MAXDIL]:  # eq. (5.6), capped
            ddil = min(prop[P_TANPSI] * dup, prop[P_MAXDIL] - S[p, k, DIL])
            S[p, k, DIL] += ddil
        S[p, k, USP] += dup
        S[p, k, SLIP] = 1.0 if sig > 0.0 else 0.0  # an unloaded touch is not a slipping joint
        E[E_SLIP] += (released - sig * ddil) * length  # eq. (11.3)
    S[p, k, TAU] = tau
    S[p, k, FN] = sig * length  # eq. (4.4)
    S[p, k, FS] = tau * length


@njit(cache=True, inline="always")
def _cy_law(S, p, k, prop, un, dus, length, clamp, slipping_f, E):
    """Continuously yielding joint (docs/dem.md §6, eqs. (6.1)–(6.8); Cundall & Hart 1984).
    ``clamp`` caps the reversal ratio r below 1, ``slipping_f`` is the F below which the slot is
    reported as slipping (:mod:`rockmass.solver.tolerances`)."""
    sig = _cy_normal_stress(prop[P_KN], prop[P_EN], un)  # eq. (6.2)
    if sig <= 0.0:  # open: no stress, the reversal memory is cleared
        S[p, k, FN] = 0.0
        S[p, k, FS] = 0.0
        S[p, k, TAU] = 0.0
        S[p, k, RREV] = 0.0
        S[p, k, DIR] = 0.0
        return
    ks = prop[P_KS] * sig ** prop[P_ES] if prop[P_ES] != 0.0 else prop[P_KS]  # eq. (6.1)
    tau = S[p, k, TAU]
    tau_old = tau
    if dus != 0.0:
        d = 1.0 if dus > 0.0 else -1.0
        phim = S[p, k, PHIM]
        tm = sig * math.tan(phim)  # eq. (6.3), bounding strength
        if S[p, k, DIR] != 0.0 and S[p, k, DIR] != d:  # a reversal: r = τ/τ_m, eq. (6.5)
            S[p, k, RREV] = tau * d / tm
        S[p, k, DIR] = d
        r = min(S[p, k, RREV], clamp)
        f = (1.0 - tau * d / tm) / (1.0 - r)  # eq. (6.4)
        f = min(max(f, 0.0), 1.0)
        tau += f * ks * dus  # eq. (6.4)
        if tau * d > tm:
            tau = d * tm
        dup = (1.0 - f) * abs(dus)  # eq. (6.6)
        if dup > 0.0:
            phib = prop[P_PHIB]
            # eq. (6.7), integrated exactly over the increment
            S[p, k, PHIM] = phib + (phim - phib) * math.exp(-dup / prop[P_ROUGH])
            ang = math.atan(abs(tau) / sig) - phib  # eq. (6.8), dilation angle i
            ddil = math.tan(ang) * dup if ang > 0.0 else 0.0
            S[p, k, DIL] += ddil
            S[p, k, USP] += dup
            released = _slip_dissipation(tau_old, tau, dus, ks)
            E[E_SLIP] += (released - sig * ddil) * length  # eq. (11.3)
        if f < slipping_f:
            S[p, k, SLIP] = 1.0
    S[p, k, TAU] = tau
    S[p, k, FN] = sig * length  # eq. (4.4)
    S[p, k, FS] = tau * length


@njit(cache=True)
def _update_slot(S, p, k, prop, delta, dus, length, cy_clamp, cy_slipping_f, E):
    """Advance the joint law of slot k of pair p by one step: geometric overlap ``delta`` (m),
    shear displacement increment ``dus`` (m). Writes σ_n, τ and the flags; adds dissipation to E."""
    S[p, k, LEN] = length
    S[p, k, OVL] = delta
    S[p, k, SLIP] = 0.0
    un = delta + S[p, k, U0] + S[p, k, DIL]  # eq. (4.3)
    if prop[P_MODEL] == MODEL_COULOMB:
        _coulomb_law(S, p, k, prop, un, dus, length, E)
    else:
        _cy_law(S, p, k, prop, un, dus, length, cy_clamp, cy_slipping_f, E)


@njit(types.void(types.float64[:, :, ::1], types.int64, types.int64, types.float64[::1],
                 types.int64[::1], types.float64[::1], types.float64[::1]), cache=True)
def _open_slot(S, p, k, prop, pinit, init_brk, E):
    """Open slot k of pair p: the blocks moved apart beyond the detection gap there (or the
    contact no longer uses the slot).

    A bond still intact (tension or cohesion > 0) has failed (docs/dem.md §7, eq. (7.3)): a bond
    that separates beyond the tolerance cannot hold (with T/k_n above the tolerance it would
    otherwise open before its tension is exceeded, and bond again on closing). It is marked broken
    and counted, and its elastic energy at the last update is booked as breakage (the energy
    ledger stays closed). A broken slot of a block-model contact is remembered in ``init_brk``, so
    the contact comes back broken when it closes again (:func:`_activate_slot`), not intact.
    """
    if S[p, k, BRK] == 0.0 and _is_bond(prop):
        _break_bond(S, p, k, E)
        length = S[p, k, LEN]
        if length > 0.0:
            sig = S[p, k, FN] / length
            E[E_BROKEN] += 0.5 * (sig * sig / prop[P_KN] + S[p, k, TAU] ** 2 / prop[P_KS]) * length
    if S[p, k, BRK] != 0.0 and pinit[p] >= 0:
        init_brk[pinit[p]] = 1.0
    S[p, k, ACT] = 0.0
    S[p, k, FN] = 0.0
    S[p, k, FS] = 0.0
    S[p, k, TAU] = 0.0
    S[p, k, U0] = 0.0
    S[p, k, DIL] = 0.0
    S[p, k, SLIP] = 0.0
    S[p, k, OVL] = 0.0


@njit(cache=True)
def _open_pair(S, p, prop, pinit, init_brk, E):
    for k in range(2):
        if S[p, k, ACT] != 0.0:
            _open_slot(S, p, k, prop, pinit, init_brk, E)


@njit(cache=True)
def _activate_slot(S, p, k, prop, broken):
    """A slot comes into contact: fresh joint state (docs/dem.md §4), broken or intact."""
    S[p, k, ACT] = 1.0
    S[p, k, U0] = 0.0
    S[p, k, DIL] = 0.0
    S[p, k, TAU] = 0.0
    S[p, k, RREV] = 0.0
    S[p, k, DIR] = 0.0
    S[p, k, PHIM] = prop[P_PHIM0]
    S[p, k, BRK] = broken
    S[p, k, NEW] = 1.0


# ------------------------------------------------------------------------------------------------
# Kinematics and assembly (docs/dem.md §4, §8)
# ------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _relative_motion(xa, ya, vxa, vya, wa, xb, yb, vxb, vyb, wb, px, py, tx, ty, dt):
    """Velocity of block b (centroid (xb, yb), velocity (vxb, vyb), ω_b = wb) relative to block a
    at the contact point (px, py), and the shear displacement increment along t over one step
    (docs/dem.md §4, eqs. (4.1)–(4.2)). Returns (v_x, v_y, Δu_s). Scalars only: it runs once per
    slot and step."""
    rax = px - xa
    ray = py - ya
    rbx = px - xb
    rby = py - yb
    vrx = vxb - wb * rby - vxa + wa * ray
    vry = vyb + wb * rbx - vya - wa * rax
    return vrx, vry, (vrx * tx + vry * ty) * dt


@njit(cache=True, inline="always")
def _strain_rate_velocity(srate, a, b, pos, px, py):
    """The part of b's velocity relative to a's at (px, py) that comes from the strain rates of
    zones (docs/dem.md §16.8): ε̇_b (p − c_b) − ε̇_a (p − c_a), ε̇ = ``srate`` rows (xx, yy, xy);
    rigid blocks have zero rows."""
    rax = px - pos[a, 0]
    ray = py - pos[a, 1]
    rbx = px - pos[b, 0]
    rby = py - pos[b, 1]
    dvx = (srate[b, 0] * rbx + srate[b, 2] * rby) - (srate[a, 0] * rax + srate[a, 2] * ray)
    dvy = (srate[b, 2] * rbx + srate[b, 1] * rby) - (srate[a, 2] * rax + srate[a, 1] * ray)
    return dvx, dvy


@njit(cache=True, inline="always")
def _stiffness_dashpot(prop, length, beta, vrx, vry, nx, ny, tx, ty, dt, fn, fs, slipping, E):
    """Add the stiffness-proportional Rayleigh dashpots β K v_rel to a slot's forces (docs/dem.md
    §8, eq. (8.4)) and book their work; returns the damped (F_n, F_s). A slipping slot gets no
    shear dashpot: its shear force is the joint's strength, and a viscous force on top of it
    would make the strength grow with the slip rate."""
    vn = vrx * nx + vry * ny
    vt = 0.0 if slipping else vrx * tx + vry * ty
    fn -= beta * prop[P_KN] * length * vn
    fs += beta * prop[P_KS] * length * vt
    E[E_VISCOUS] -= beta * length * (prop[P_KN] * vn * vn + prop[P_KS] * vt * vt) * dt
    return fn, fs


@njit(cache=True)
def _add_slot_force(fpair, p, fn, fs, nx, ny, px, py, ax, ay, bx, by):
    """Add a slot's force (−F_n n + F_s t on block a at (px, py), the opposite on b; docs/dem.md
    §4, eq. (4.5)) and its moments about the centroids (ax, ay), (bx, by) to ``fpair[p]``."""
    fx = -fn * nx - fs * ny
    fy = -fn * ny + fs * nx
    fpair[p, 0] += fx
    fpair[p, 1] += fy
    fpair[p, 2] += (px - ax) * fy - (py - ay) * fx
    fpair[p, 3] -= fx
    fpair[p, 4] -= fy
    fpair[p, 5] -= (px - bx) * fy - (py - by) * fx


@njit(cache=True)
def _forces_from_slots(S, p, ax, ay, bx, by, fpair):
    """Force and moment on both blocks of pair p from its slots' stored F_n, F_s (no dashpots)."""
    for k in range(2):
        if S[p, k, ACT] != 0.0:
            _add_slot_force(fpair, p, S[p, k, FN], S[p, k, FS], S[p, k, NX], S[p, k, NY],
                            S[p, k, PX], S[p, k, PY], ax, ay, bx, by)


@njit(cache=True)
def _closest_on_segment(px, py, ax, ay, bx, by):
    """Squared distance from (px, py) to the segment a–b and the closest point on it."""
    ex = bx - ax
    ey = by - ay
    ee = ex * ex + ey * ey
    lam = 0.0
    if ee > 0.0:
        lam = min(max(((px - ax) * ex + (py - ay) * ey) / ee, 0.0), 1.0)
    qx = ax + lam * ex
    qy = ay + lam * ey
    return (px - qx) ** 2 + (py - qy) ** 2, qx, qy


@njit(cache=True)
def _next_vertex(off, b, i):
    return off[b] if i + 1 == off[b + 1] else i + 1


@njit(cache=True)
def _prev_vertex(off, b, i):
    return off[b + 1] - 1 if i == off[b] else i - 1


@njit(types.UniTuple(types.float64, 5)(_WV, _OFF, types.int64, types.int64, types.int64,
                                        types.int64), cache=True)
def _rounded_corner(wv, off, rb, e, ib, inc):
    """Distance between the inner polygons (arc centres, columns ``W_CX, W_CY``) of blocks rb and
    ib near a contact, and its two closest points (on rb's, then on ib's).

    The candidates are the local features: the two inner vertices of the incident edge ``inc``
    against rb's inner edges before, along and after the reference edge ``e``, and the two inner
    vertices of ``e`` against ib's inner edges around ``inc``. The rounded blocks are the inner
    polygons grown by their radii, so their gap is this distance minus the two radii, along the
    line through the two points: a corner against a face gives the face's normal, a corner against
    a corner the line of the two arc centres, and the normal turns smoothly between the two as a
    block rolls over a corner.
    """
    best = np.inf
    rx = 0.0
    ry = 0.0
    qx = 0.0
    qy = 0.0
    for side in range(2):
        own = ib if side == 0 else rb  # the block whose inner vertices are tested
        other = rb if side == 0 else ib
        v = inc if side == 0 else e
        f = _prev_vertex(off, other, e if side == 0 else inc)
        for _vv in range(2):
            px = wv[v, W_CX]
            py = wv[v, W_CY]
            s0 = f
            for _ee in range(3):
                s1 = _next_vertex(off, other, s0)
                d2, cx, cy = _closest_on_segment(px, py, wv[s0, W_CX], wv[s0, W_CY], wv[s1, W_CX],
                                                 wv[s1, W_CY])
                if d2 < best:
                    best = d2
                    if side == 0:
                        rx, ry, qx, qy = cx, cy, px, py
                    else:
                        rx, ry, qx, qy = px, py, cx, cy
                s0 = s1
            v = _next_vertex(off, own, v)
    return math.sqrt(best), rx, ry, qx, qy


# ------------------------------------------------------------------------------------------------
# Narrow phase, step by step (docs/dem.md §3)
# ------------------------------------------------------------------------------------------------


@njit(cache=True)
def contact_forces(blocks, pairs, still, prm, E):
    """Narrow phase and joint laws for every pair; writes per-pair force/moment on both blocks
    (``pairs.fpair[p] = fx_a, fy_a, m_a, fx_b, fy_b, m_b``) and returns (max overlap, its pair).

    Per pair, in the numbered steps of the body (docs/dem.md §3–§8): bounding circles; (1) the
    separating-axis test on both polygons (the sharp polygons contain the rounded blocks, so a pair
    the test separates is apart) and the reference edge, switching side only when the other is
    better by the hysteresis; (2) the incident edge of the other block; (3) the incident edge
    clipped to the reference edge's extent; (4) *face* or *rounded corner*: a face while both
    clipped ends are within the gap and the flat parts of the two edges overlap; (5) the slots'
    points: a face has two, at the clipped ends, each of length half the clipped overlap; a corner
    contact one, whose gap, normal and point come from the arcs of radius ``W_RAD``
    (:func:`_rounded_corner`), of length the face part it stands for (at least the rounding d);
    (6) the slots they go to; (7) per slot the kinematics (:func:`_relative_motion`), the joint
    law (:func:`_update_slot`), the stiffness-proportional Rayleigh dashpots
    (:func:`_stiffness_dashpot`, when β > 0) and the assembly (:func:`_add_slot_force`).

    Pairs of two ``still`` blocks (asleep or fixed) do not move: their slots keep their state and
    only the forces are re-assembled from it. Scalars from ``prm``: Δt (0 for a detection pass),
    the detection gap, the hysteresis, d, β and the geometric tolerances.

    The geometric steps (1)–(6) stay in this body on purpose: as separate jitted helpers, even
    inlined by numba, they made the narrow phase 25–40 % slower (measured on 3000 blocks).
    """
    (_loc, _lgeo, off, radius, _mass, _inv_mass, _mode, _dof_input, _active, _movable, pos, _rot,
     vel, omg, _asleep, _calm, wv, zone_of, srate) = blocks
    pa, pb, pprop, pref, pinit, init_brk, props, S, fpair, _ptr, _idx, _rpos, _rrot = pairs
    dt, ctol, hyst, rounding = prm[PRM_DT], prm[PRM_CTOL], prm[PRM_HYST], prm[PRM_ROUNDING]
    beta, tiny = prm[PRM_BETA], prm[PRM_TINY]
    cy_clamp, cy_slipping_f = prm[PRM_CY_CLAMP], prm[PRM_CY_SLIP_F]
    facing_cos, bond_gap = prm[PRM_FACING_COS], prm[PRM_BOND_GAP]
    face_min, degenerate = prm[PRM_FACE_MIN], prm[PRM_DEGENERATE]
    max_ovl = 0.0
    max_pair = -1
    cx = np.empty(2)  # scratch for the two clipped points, allocated once
    cy = np.empty(2)
    csep = np.empty(2)
    ptx = np.empty(2)
    pty = np.empty(2)
    pco = np.empty(2)
    pdel = np.empty(2)
    slot_of = np.empty(2, np.int64)
    for p in range(len(pa)):
        a = pa[p]
        b = pb[p]
        prop = props[pprop[p]]
        for q in range(6):
            fpair[p, q] = 0.0
        if still[a] != 0 and still[b] != 0:
            _forces_from_slots(S, p, pos[a, 0], pos[a, 1], pos[b, 0], pos[b, 1], fpair)
            continue
        extra = 0.0
        for k in range(2):
            if S[p, k, ACT] != 0.0:
                extra = max(extra, S[p, k, U0] + S[p, k, DIL])
        tol = ctol + extra
        dx = pos[b, 0] - pos[a, 0]
        dy = pos[b, 1] - pos[a, 1]
        reach = radius[a] + radius[b] + tol
        if dx * dx + dy * dy > reach * reach:  # bounding circles apart: no contact
            _open_pair(S, p, prop, pinit, init_brk, E)
            continue
        # (1) separating-axis test both ways and the reference side (§3.3): the side switches only
        # when the other separates better by the hysteresis (no flicker on coincident faces)
        sep_a, e_a = _max_separation(wv, off, a, b, tol, hyst)
        sep_b = np.inf
        e_b = -1
        if sep_a <= tol:
            sep_b, e_b = _max_separation(wv, off, b, a, tol, hyst)
        if sep_a > tol or sep_b > tol:
            _open_pair(S, p, prop, pinit, init_brk, E)
            continue
        ref = pref[p]
        if ref == 0 and sep_b > sep_a + hyst:
            ref = 1
        elif ref == 1 and sep_a > sep_b + hyst:
            ref = 0
        pref[p] = ref
        rb = a if ref == 0 else b
        ib = b if ref == 0 else a
        e = e_a if ref == 0 else e_b
        x0, y0, ux, uy, nrx, nry, jref = _edge(wv, off, rb, e)
        lref = (wv[jref, 0] - x0) * ux + (wv[jref, 1] - y0) * uy
        # (2) incident edge (§3.4): among the edges of the other block facing the reference edge
        # (normals within ~8° of anti-parallel) the one overlapping it most along the edge
        # (snapped near-collinear pieces must not win by a hair); otherwise the most anti-parallel
        best = np.inf
        inc = -1
        best_cover = 0.0
        facing = -1
        for i in range(off[ib], off[ib + 1]):
            d = wv[i, 2] * nrx + wv[i, 3] * nry
            if d < best:
                best = d
                inc = i
            if d < facing_cos:
                j = i + 1 if i + 1 < off[ib + 1] else off[ib]
                s0 = (wv[i, 0] - x0) * ux + (wv[i, 1] - y0) * uy
                s1 = (wv[j, 0] - x0) * ux + (wv[j, 1] - y0) * uy
                cover = min(lref, max(s0, s1)) - max(0.0, min(s0, s1))
                if cover > best_cover:
                    best_cover = cover
                    facing = i
        if facing >= 0:
            inc = facing
        ix0, iy0, iux, iuy, _inx, _iny, ij = _edge(wv, off, ib, inc)
        ix1 = wv[ij, 0]
        iy1 = wv[ij, 1]
        # (3) the incident edge clipped to the reference edge (Box2D-style manifold): its two ends
        # within the gap
        t0 = (ix0 - x0) * ux + (iy0 - y0) * uy
        t1 = (ix1 - x0) * ux + (iy1 - y0) * uy
        tlo = max(0.0, min(t0, t1))
        thi = min(lref, max(t0, t1))
        nsharp = 0
        if thi >= tlo:
            for m in range(2):
                tt = tlo if m == 0 else thi
                lam = (tt - t0) / (t1 - t0) if abs(t1 - t0) > tiny else 0.0
                px = ix0 + lam * (ix1 - ix0)
                py = iy0 + lam * (iy1 - iy0)
                csep[m] = (px - x0) * nrx + (py - y0) * nry
                if csep[m] <= tol:
                    cx[nsharp] = px
                    cy[nsharp] = py
                    csep[nsharp] = csep[m]
                    nsharp += 1
        # (4) a face while both ends touch and the flat parts of the two edges (between the
        # tangent points of the rounded corners) overlap; otherwise a rounded corner contact
        face = nsharp == 2 and thi - tlo > face_min * lref
        if face:
            cu = iux * ux + iuy * uy
            f0 = t0 + wv[inc, W_TAN] * cu
            f1 = t1 - wv[ij, W_TAN] * cu
            face = (min(lref - wv[jref, W_TAN], max(f0, f1))
                    > max(wv[e, W_TAN], min(f0, f1)))
        # (5) the slots' points, overlaps, normal and length (§3.4)
        if face:
            nkeep = 2
            length = 0.5 * (thi - tlo)  # each end carries half of the face
            nx = nrx if ref == 0 else -nrx
            ny = nry if ref == 0 else -nry
            for q in range(2):
                ptx[q] = cx[q] - 0.5 * csep[q] * nrx
                pty[q] = cy[q] - 0.5 * csep[q] * nry
                pdel[q] = -csep[q]
        else:
            dist, rx, ry, qx, qy = _rounded_corner(wv, off, rb, e, ib, inc)
            r_ref = wv[off[rb], W_RAD]
            rsum = r_ref + wv[off[ib], W_RAD]
            if dist > degenerate * (rsum + lref):
                gx = (qx - rx) / dist
                gy = (qy - ry) / dist
                sep = dist - rsum
            else:  # inner polygons meet (overlap > the radii): sharp measure along the ref normal
                gx = nrx
                gy = nry
                sep = min(max(sep_a, sep_b), -rsum)
            if sep > tol:
                _open_pair(S, p, prop, pinit, init_brk, E)
                continue
            nkeep = 1
            # the face parts it stands for (lift-off: one end, sliding off a corner: both)
            length = max(0.5 * max(thi - tlo, 0.0) * nsharp, rounding)
            nx = gx if ref == 0 else -gx
            ny = gy if ref == 0 else -gy
            ptx[0] = rx + (r_ref + 0.5 * sep) * gx
            pty[0] = ry + (r_ref + 0.5 * sep) * gy
            pdel[0] = -sep
        tx = -ny
        ty = nx
        # (6) slot assignment (§3.5) by the coordinate along t about block a's centroid
        for q in range(nkeep):
            pco[q] = (ptx[q] - pos[a, 0]) * tx + (pty[q] - pos[a, 1]) * ty
        if nkeep == 2:
            if pco[0] <= pco[1]:
                slot_of[0] = 0
                slot_of[1] = 1
            else:
                slot_of[0] = 1
                slot_of[1] = 0
        else:
            act0 = S[p, 0, ACT] != 0.0
            act1 = S[p, 1, ACT] != 0.0
            if act0 and act1:
                near0 = abs(pco[0] - S[p, 0, COORD]) <= abs(pco[0] - S[p, 1, COORD])
                slot_of[0] = 0 if near0 else 1
            elif act1:
                slot_of[0] = 1
            else:
                slot_of[0] = 0
        used0 = False
        used1 = False
        for q in range(nkeep):
            if slot_of[q] == 0:
                used0 = True
            else:
                used1 = True
        if not used0 and S[p, 0, ACT] != 0.0:
            _open_slot(S, p, 0, prop, pinit, init_brk, E)
        if not used1 and S[p, 1, ACT] != 0.0:
            _open_slot(S, p, 1, prop, pinit, init_brk, E)
        # (7) per slot: activation, kinematics (§4.2), joint law (§§5-7), Rayleigh dashpots (§8.2),
        # assembly (§4.3)
        broken = init_brk[pinit[p]] if pinit[p] >= 0 else 0.0
        for q in range(nkeep):
            k = slot_of[q]
            if S[p, k, ACT] == 0.0:
                # a corner that comes into contact across a gap is a new touch, not a bond
                bonded = face or pdel[q] >= -bond_gap * rounding
                _activate_slot(S, p, k, prop, broken if bonded else 1.0)
                E[E_NEW_SLOTS] += 1.0
            px = ptx[q]
            py = pty[q]
            vrx, vry, dus = _relative_motion(pos[a, 0], pos[a, 1], vel[a, 0], vel[a, 1], omg[a],
                                             pos[b, 0], pos[b, 1], vel[b, 0], vel[b, 1], omg[b],
                                             px, py, tx, ty, dt)
            if zone_of[a] >= 0 or zone_of[b] >= 0:  # a zone's velocity also strains (§16.8)
                dvx, dvy = _strain_rate_velocity(srate, a, b, pos, px, py)
                vrx += dvx
                vry += dvy
                dus += (dvx * tx + dvy * ty) * dt
            _update_slot(S, p, k, prop, pdel[q], dus, length, cy_clamp, cy_slipping_f, E)
            S[p, k, COORD] = pco[q]
            S[p, k, PX] = px
            S[p, k, PY] = py
            S[p, k, NX] = nx
            S[p, k, NY] = ny
            fn = S[p, k, FN]
            fs = S[p, k, FS]
            if beta > 0.0 and fn != 0.0:  # closed contacts, glued ones in tension included
                fn, fs = _stiffness_dashpot(prop, length, beta, vrx, vry, nx, ny, tx, ty, dt, fn,
                                            fs, S[p, k, SLIP] != 0.0, E)
            S[p, k, FNA] = fn
            S[p, k, FSA] = fs
            _add_slot_force(fpair, p, fn, fs, nx, ny, px, py, pos[a, 0], pos[a, 1], pos[b, 0],
                            pos[b, 1])
            if pdel[q] > max_ovl:
                max_ovl = pdel[q]
                max_pair = p
    return max_ovl, max_pair


@njit(cache=True)
def block_pair_index(pa, pb, nb):
    """CSR of the pairs of each block: entries ``2 p + role`` (role 0: block is pa, 1: pb)."""
    cnt = np.zeros(nb + 1, np.int64)
    for p in range(len(pa)):
        cnt[pa[p] + 1] += 1
        cnt[pb[p] + 1] += 1
    for b in range(nb):
        cnt[b + 1] += cnt[b]
    fill = np.empty(nb, np.int64)
    for b in range(nb):
        fill[b] = cnt[b]
    idx = np.empty(2 * len(pa), np.int64)
    for p in range(len(pa)):
        idx[fill[pa[p]]] = 2 * p
        fill[pa[p]] += 1
        idx[fill[pb[p]]] = 2 * p + 1
        fill[pb[p]] += 1
    return cnt, idx


@njit(cache=True)
def remap_pairs(old_pa, old_pb, old_S, old_pref, old_pinit, new_pa, new_pb, nb, S, pref, pinit,
                pprop, init_key, init_prop, default_prop, init_brk):
    """Carry slot state of surviving pairs into the new pair list; new pairs get the joint model of
    their block-model contact (binary search in sorted ``init_key``) or ``default_prop``. Broken
    slots of pairs that leave the list are remembered in ``init_brk``."""
    i = 0
    n_old = len(old_pa)
    for p in range(len(new_pa)):
        key = new_pa[p] * nb + new_pb[p]
        while i < n_old and old_pa[i] * nb + old_pb[i] < key:
            if old_pinit[i] >= 0 and (old_S[i, 0, BRK] != 0.0 or old_S[i, 1, BRK] != 0.0):
                init_brk[old_pinit[i]] = 1.0
            i += 1
        if i < n_old and old_pa[i] * nb + old_pb[i] == key:
            for k in range(S.shape[1]):
                for c in range(S.shape[2]):
                    S[p, k, c] = old_S[i, k, c]
            pref[p] = old_pref[i]
            pinit[p] = old_pinit[i]
            i += 1
        else:
            j = 0  # binary search: the first init_key >= key (np.searchsorted, side left)
            hi = len(init_key)
            while j < hi:
                mid = (j + hi) >> 1
                if init_key[mid] < key:
                    j = mid + 1
                else:
                    hi = mid
            if j < len(init_key) and init_key[j] == key:
                pinit[p] = j
            else:
                pinit[p] = -1
            pref[p] = 0
        pprop[p] = init_prop[pinit[p]] if pinit[p] >= 0 else default_prop
    while i < n_old:
        if old_pinit[i] >= 0 and (old_S[i, 0, BRK] != 0.0 or old_S[i, 1, BRK] != 0.0):
            init_brk[old_pinit[i]] = 1.0
        i += 1


@njit(cache=True, inline="always")
def _edge_dashpot(edges, e, pos, vel, omg, rot, vref_x, vref_y, sxy, qf):
    """Dashpots and a shear traction on boundary edge ``e`` (a row of :func:`quiet_forces`): adds
    −L(ρC_p Δv_n n + ρC_s Δv_t t) + L σ_xy (n_y, n_x) at the edge midpoint into qf, with Δv the
    midpoint velocity less (vref_x, vref_y) and σ_xy a (tension-positive) shear stress acting on
    the edge (docs/dem.md §9.4, eq. (9.1); §14.2, eq. (14.4))."""
    b = int(edges[e, 0])
    c = math.cos(rot[b])
    s = math.sin(rot[b])
    rx = c * edges[e, 1] - s * edges[e, 2]
    ry = s * edges[e, 1] + c * edges[e, 2]
    nx = c * edges[e, 3] - s * edges[e, 4]
    ny = s * edges[e, 3] + c * edges[e, 4]
    vx = vel[b, 0] - omg[b] * ry - vref_x
    vy = vel[b, 1] + omg[b] * rx - vref_y
    vn = vx * nx + vy * ny
    vt = -vx * ny + vy * nx
    fx = -edges[e, 5] * (edges[e, 6] * vn * nx - edges[e, 7] * vt * ny - sxy * ny)
    fy = -edges[e, 5] * (edges[e, 6] * vn * ny + edges[e, 7] * vt * nx - sxy * nx)
    qf[b, 0] += fx
    qf[b, 1] += fy
    qf[b, 2] += rx * fy - ry * fx


@njit(cache=True)
def quiet_forces(edges, pos, vel, omg, rot, qf):
    """Viscous boundary forces. ``edges[e] = block, rx, ry (local midpoint), nx, ny (outward),
    length, ρC_p, ρC_s``; adds −L(ρC_p v_n n + ρC_s v_s t) at the edge midpoint into qf."""
    for e in range(len(edges)):
        _edge_dashpot(edges, e, pos, vel, omg, rot, 0.0, 0.0, 0.0, qf)


@njit(cache=True)
def free_field_step(edges, elem, state, presc_val, step, dt, pos, vel, omg, rot, qf):
    """One step of the free-field columns and their forces on the model (docs/dem.md §14.2).

    ``elem[i]`` (columns ``FF_*``): a column element of mass ρh per unit width, the joint to the
    element above (``FF_ABOVE``, -1 at the top) of shear and normal stiffness k_x, k_y (Pa/m), a
    dashpot c_x, c_y at a quiet end, and per component its mode (0 free, 1 fixed, 2 prescribed:
    ``presc_val[step, FF_IN_*]``). ``state[i] = u_x, u_y, v_x, v_y`` (displacements at the whole
    step, velocities at the half step before it). ``edges[e]``: a row of :func:`quiet_forces` and
    the element it faces (column 8).

    Joint stresses τ = k_x (u_x,above − u_x), σ = k_y (u_y,above − u_y) (tension positive); an
    element moves by ρh dv/dt = τ_top − τ_bottom − c v (central differences, eqs. (2.2)–(2.3));
    the stress under the lowest element is what moves it, τ_bottom = τ_top − ρh Δv/Δt (a support's
    reaction, or its dashpot's c v). The element's shear stress σ_xy^ff = (τ_top + τ_bottom)/2 acts
    on the model's edges facing it with the dashpots to its velocity (:func:`_edge_dashpot`;
    docs/dem.md eqs. (14.4)–(14.5)), before the column steps: forces at step n from u^n and
    v^(n−1/2), like the model's own."""
    ne = len(elem)
    tau_top = np.zeros(ne)
    tau_bot = np.zeros(ne)
    sig_top = np.zeros(ne)
    sig_bot = np.zeros(ne)
    lowest = np.ones(ne, np.bool_)
    for i in range(ne):
        j = int(elem[i, FF_ABOVE])
        if j >= 0:
            tau = elem[i, FF_KX] * (state[j, 0] - state[i, 0])
            sig = elem[i, FF_KY] * (state[j, 1] - state[i, 1])
            tau_top[i] = tau
            tau_bot[j] = tau
            sig_top[i] = sig
            sig_bot[j] = sig
            lowest[j] = False
    v_new = np.empty((ne, 2))
    for i in range(ne):
        m = elem[i, FF_M]
        for d in range(2):
            v_old = state[i, 2 + d]
            mode = elem[i, FF_MODE_X + d]
            if mode == 1.0:
                v = 0.0
            elif mode == 2.0:
                v = presc_val[step, int(elem[i, FF_IN_X + d])]
            else:
                f = ((tau_top[i] - tau_bot[i]) if d == 0 else (sig_top[i] - sig_bot[i]))
                v = v_old + (f - elem[i, FF_CX + d] * v_old) / m * dt
            v_new[i, d] = v
        if lowest[i]:  # the reaction under the column's foot
            tau_bot[i] = tau_top[i] - m * (v_new[i, 0] - state[i, 2]) / dt
    for e in range(len(edges)):
        i = int(edges[e, 8])
        _edge_dashpot(edges, e, pos, vel, omg, rot, state[i, 2], state[i, 3],
                      0.5 * (tau_top[i] + tau_bot[i]), qf)
    for i in range(ne):
        for d in range(2):
            state[i, 2 + d] = v_new[i, d]
            state[i, d] += v_new[i, d] * dt


@njit(cache=True, inline="always")
def _elastoplastic_spring(force, k, increment, lower, upper):
    """(force, plastic increment, dissipated energy) of a spring of stiffness k after the
    displacement increment ``increment``, its force held within [lower, upper] (docs/dem.md §15,
    eqs. (15.2)–(15.3)); the dissipation is that of a slipping joint (eq. (11.3))."""
    trial = force + k * increment
    new = min(max(trial, lower), upper)
    if new == trial:
        return new, 0.0, 0.0
    return new, (trial - new) / k, _slip_dissipation(force, new, increment, k)


@njit(cache=True)
def bolt_step(node, state, pos, vel, omg, rot, active, dt, alpha_local, alpha_mass, vref_x, vref_y,
              E, bf):
    """One step of the bolts (UDEC cable elements; docs/dem.md §15, eqs. (15.1)–(15.5)).

    ``node[i]`` (columns ``BN_*``): host block (-1: none) and the node's anchor point in the host's
    frame, the bolt's unit axis a, the node's mass, its grout spring's stiffness k_bond l_i and
    strength s_bond l_i (l_i its share of the bolt), the next node of the bolt (-1 at the end) and
    the segment to it: stiffness EA/h, tensile and compressive yield forces. ``state[i]``
    (columns ``BS_*``): the node's axial displacement u and velocity v (half step), its grout
    force G (on the node, along a) and accumulated slip, and the segment's axial force N (tension
    positive), plastic elongation and yield flags. ``vref_x``, ``vref_y``: the velocity the
    mass-proportional damping α_M is relative to (docs/dem.md §8.2).

    From the increments of the last half step (host anchor Δw = (v_b + ω × r)·a Δt, node Δu = v Δt):
    G ← G + k_g (Δw − Δu) within ±s_g (slip), N ← N + k_a (Δu_next − Δu) within [−N_c, N_t]
    (yield); the node moves by m dv/dt = G + N_i − N_(i−1) − α_M m (v − v_ref·a) (local damping
    ``alpha_local`` too, eq. (8.1)), the host takes −G a at the anchor into ``bf`` (B, 3). A node
    whose host is gone (excavated, taken out) releases its grout spring (its energy booked as
    slip). Dissipation goes to ``E_BOLT_SLIP``, ``E_BOLT_YIELD``, the damping to ``E_LOCAL_DAMP``
    and ``E_VISCOUS``. Returns, for the equilibrium test (docs/dem.md §10.1), the nodes'
    Σ|unbalanced force|, Σ applied force (|G| + |N_i| + |N_(i−1)|) and kinetic energy: they enter
    the model's ratio and the kinetic-energy test, not the blocks' own ratios (a node at a free
    end, held by one spring, has a ratio of 1 whatever its force). No checks: nodes of a bolt are
    consecutive."""
    n = len(node)
    applied = np.zeros(n)
    du = np.empty(n)
    force = np.zeros(n)
    for i in range(n):
        du[i] = state[i, BS_V] * dt
    for i in range(n):
        b = int(node[i, BN_HOST])
        ax = node[i, BN_AX]
        ay = node[i, BN_AY]
        kg = node[i, BN_KG]
        if b >= 0 and active[b]:
            c = math.cos(rot[b])
            s = math.sin(rot[b])
            rx = c * node[i, BN_RX] - s * node[i, BN_RY]
            ry = s * node[i, BN_RX] + c * node[i, BN_RY]
            dw = ((vel[b, 0] - omg[b] * ry) * ax + (vel[b, 1] + omg[b] * rx) * ay) * dt
            sg = node[i, BN_SG]
            g, slip, lost = _elastoplastic_spring(state[i, BS_G], kg, dw - du[i], -sg, sg)
            state[i, BS_G] = g
            state[i, BS_SLIP] += abs(slip)
            state[i, BS_SLIPPING] = 1.0 if slip != 0.0 else 0.0
            E[E_BOLT_SLIP] += lost
            bf[b, 0] -= g * ax
            bf[b, 1] -= g * ay
            bf[b, 2] -= g * (rx * ay - ry * ax)
        elif state[i, BS_G] != 0.0:  # the host is gone: the grout lets go
            E[E_BOLT_SLIP] += 0.5 * state[i, BS_G] ** 2 / kg
            state[i, BS_G] = 0.0
        force[i] += state[i, BS_G]
        applied[i] += abs(state[i, BS_G])
        j = int(node[i, BN_NEXT])
        if j >= 0:
            nn, plastic, lost = _elastoplastic_spring(state[i, BS_N], node[i, BN_KA], du[j] - du[i],
                                                      -node[i, BN_NC], node[i, BN_NT])
            state[i, BS_N] = nn
            state[i, BS_EP] += plastic
            state[i, BS_YIELD] = 1.0 if plastic != 0.0 else 0.0
            if plastic != 0.0:
                state[i, BS_YIELDED] = 1.0
            E[E_BOLT_YIELD] += lost
            force[i] += nn
            force[j] -= nn
            applied[i] += abs(nn)
            applied[j] += abs(nn)
    sum_unb = 0.0
    sum_app = 0.0
    ke = 0.0
    for i in range(n):
        sum_unb += abs(force[i])
        sum_app += applied[i]
        v_old = state[i, BS_V]
        m = node[i, BN_M]
        fv = -alpha_mass * m * (v_old - vref_x * node[i, BN_AX] - vref_y * node[i, BN_AY])
        f = force[i] + fv
        fd = 0.0
        if alpha_local > 0.0 and v_old != 0.0:  # eq. (8.1)
            fd = -alpha_local * abs(f) * (1.0 if v_old > 0 else -1.0)
        v_new = v_old + (f + fd) / m * dt
        E[E_LOCAL_DAMP] += fd * 0.5 * (v_old + v_new) * dt
        E[E_VISCOUS] += fv * 0.5 * (v_old + v_new) * dt
        state[i, BS_V] = v_new
        state[i, BS_U] += v_new * dt
        ke += 0.5 * m * v_new * v_new
    return sum_unb, sum_app, ke


@njit(cache=True)
def _stiffest_new_slot(S, pa, pb, pprop, props, pos, inv_mass, cy_probe, cy_floor, tiny):
    """Largest ω² = k l gᵀM⁻¹g over the slots flagged ``NEW`` (and clear the flags): the
    eigenvalue of one slot's stiffness alone, g its relative-displacement row over the six dofs of
    its two blocks (normal with k_n, tangential with k_s; a continuously-yielding joint at its
    tangent stiffness at ``cy_probe`` × its stress, at least ``cy_floor``). The system's ω_max² is
    at least this large (docs/dem.md §2.3)."""
    w2 = 0.0
    for p in range(len(pa)):
        for k in range(2):
            if S[p, k, NEW] == 0.0:
                continue
            S[p, k, NEW] = 0.0
            if S[p, k, ACT] == 0.0:
                continue
            prop = props[pprop[p]]
            length = S[p, k, LEN]
            kn = prop[P_KN]
            ks = prop[P_KS]
            if prop[P_MODEL] == MODEL_CY:
                sig = max(cy_probe * S[p, k, FN] / max(length, tiny), cy_floor)
                kn *= sig ** prop[P_EN]
                ks *= sig ** prop[P_ES]
            a = pa[p]
            b = pb[p]
            nx = S[p, k, NX]
            ny = S[p, k, NY]
            rax = S[p, k, PX] - pos[a, 0]
            ray = S[p, k, PY] - pos[a, 1]
            rbx = S[p, k, PX] - pos[b, 0]
            rby = S[p, k, PY] - pos[b, 1]
            for m in range(2):
                dx = nx if m == 0 else -ny
                dy = ny if m == 0 else nx
                stiff = kn if m == 0 else ks
                ga = rax * dy - ray * dx
                gb = rbx * dy - rby * dx
                g2 = (dx * dx * inv_mass[a, 0] + dy * dy * inv_mass[a, 1] + ga * ga * inv_mass[a, 2]
                      + dx * dx * inv_mass[b, 0] + dy * dy * inv_mass[b, 1] + gb * gb * inv_mass[b, 2])
                w2 = max(w2, stiff * length * g2)
    return w2


@njit(cache=True, inline="always")
def _put_to_sleep(b, mass, vel, omg, E):
    """Block b sleeps: its velocity is zeroed and its kinetic energy booked as damping
    (docs/dem.md §10.2)."""
    E[E_LOCAL_DAMP] -= 0.5 * (mass[b, 0] * vel[b, 0] ** 2 + mass[b, 1] * vel[b, 1] ** 2
                              + mass[b, 2] * omg[b] ** 2)
    vel[b, 0] = 0.0
    vel[b, 1] = 0.0
    omg[b] = 0.0


@njit(cache=True)
def advance(n_steps, blocks, pairs, loads, zoning, prm, E, out):
    """Central-difference steps (docs/dem.md §2, eqs. (2.1)–(2.4)). Stops early with a return
    code: converged, rebuild needed (a block moved more than ``PRM_REBUILD`` × the margin since the
    last broad phase), overlap above the limit, a non-finite value, or a new contact too stiff for
    the step (``RC_STIFF``: a slot that formed in this step has ω² above ``prm[PRM_W2_NEW]`` on its
    own, :func:`_stiffest_new_slot`; the step is not integrated and the caller redoes the chunk
    with a shorter Δt). ``out`` receives [steps done, unbalanced ratio, max overlap, pair of max
    overlap, max velocity, worst block ratio, worst block, kinetic energy at the last check]; its
    entry 7 is also read as the kinetic energy of the previous check (``inf`` at a stage's start).

    Arguments: ``blocks`` (:class:`Blocks`), ``pairs`` (:class:`Pairs`), ``loads``
    (:class:`Loads`), ``zoning`` (:class:`Zoning`: the deformable blocks' zones and nodes, stepped
    by :func:`zone_step`; their blocks are not integrated as rigid bodies; or None when the model
    has none, which compiles a version without the zone kernels), the float64 parameter
    vector ``prm`` (indices ``PRM_*``), the energy
    accumulators ``E`` (``E_*``) and ``out`` (8,).

    Equilibrium (static stages, tested every ``PRM_CHECK_EVERY`` steps; docs/dem.md §10) needs all
    three of: the model's ratio Σ_b|F_unb,b| / Σ_b F_app,b below ``PRM_TOL_RATIO``; every block's
    own ratio max(|F_unb|, |M_unb|/r_b) / F_app,b below ``PRM_BLOCK_TOL`` (F_app,b = Σ|contact
    forces| + |m g| + |external force| on block b, r_b its circumradius, so the moment is weighed
    like a force at the block's rim); and a kinetic energy no larger than at the previous test.
    The mean ratio alone lets one falling block hide among thousands at rest.

    Forces on block b: contacts (gathered over its pairs in a fixed order: deterministic), gravity
    m g, external forces ``ext_f`` with moment cos θ·ext_a + sin θ·ext_b (constant tractions on
    edges that rotate with the block), quiet-boundary dashpots and free-field forces (booked as
    ``E_QUIET``), the bolts' grout forces (:func:`bolt_step`, counted with the contact forces;
    the bolt nodes enter the model's ratio and the kinetic energy), mass-proportional Rayleigh damping
    −α_M m (v − v_ref) (v_ref: the prescribed velocity in column ``PRM_REF_X`` / ``PRM_REF_Y`` of
    ``presc_val``, or 0), local non-viscous damping −α|F|sign(v) per degree of freedom (docs/dem.md §8).

    Sleeping (``PRM_SLEEP_RATIO`` > 0, static stages; docs/dem.md §10.2): a block whose own
    unbalanced-force ratio stays below the sleep ratio and whose speed (including ω × radius)
    stays below ``PRM_SLEEP_SPEED`` for ``PRM_SLEEP_STEPS`` steps is put to sleep (velocity
    zeroed, its kinetic energy booked as damping); a sleeping block is not integrated and pairs of
    two sleeping or fixed blocks skip the narrow phase; it wakes when its ratio exceeds
    ``PRM_WAKE`` × the sleep ratio (a neighbour moved). ``asleep`` must be 1 for blocks that cannot
    move.
    """
    (loc, lgeo, off, radius, mass, inv_mass, mode, dof_input, active, movable, pos, rot, vel, omg,
     asleep, calm, wv, zone_of, _srate) = blocks
    pa, pb, pprop, _pref, _pinit, _brk, props, S, fpair, bp_ptr, bp_idx, ref_pos, ref_rot = pairs
    (gravity, ext_f, ext_a, ext_b, quiet_edges, presc_val, ff_edges, ff_elem, ff_state,
     bolt_node, bolt_state) = loads
    dt, ovl_limit, margin = prm[PRM_DT], prm[PRM_OVL_LIMIT], prm[PRM_MARGIN]
    alpha_local, alpha_mass = prm[PRM_ALPHA_LOCAL], prm[PRM_ALPHA_MASS]
    tol_ratio, block_tol = prm[PRM_TOL_RATIO], prm[PRM_BLOCK_TOL]
    check_every = int(prm[PRM_CHECK_EVERY])
    sleep_ratio, sleep_speed = prm[PRM_SLEEP_RATIO], prm[PRM_SLEEP_SPEED]
    sleep_steps = int(prm[PRM_SLEEP_STEPS])
    w2_new, wake, rebuild_fraction = prm[PRM_W2_NEW], prm[PRM_WAKE], prm[PRM_REBUILD]
    ref_col = (int(prm[PRM_REF_X]), int(prm[PRM_REF_Y]), -1)
    nb = len(off) - 1
    qf = np.zeros((nb, 3))
    bf = np.zeros((nb, 3))  # bolt forces on the blocks (docs/dem.md §15)
    fc = np.zeros(3)
    fg = np.zeros(3)
    fe = np.zeros(3)
    ratio = np.inf
    ke_prev = out[7]
    # zoning None (no deformable block): numba prunes the zone branches, so this specialisation
    # compiles none of the zone kernels (the `zoning is not None` tests below do that pruning)
    zoned = zoning is not None and len(zoning.tri) > 0
    for step in range(n_steps):
        world_vertices(loc, lgeo, off, pos, rot, active, wv)
        if zoned and zoning is not None:
            zone_world_vertices(zoning, off, lgeo, wv)
        max_ovl, max_pair = contact_forces(blocks, pairs, asleep, prm, E)
        if max_ovl > ovl_limit:
            out[0] = step
            out[2] = max_ovl
            out[3] = max_pair
            return RC_OVERLAP
        if E[E_NEW_SLOTS] != 0.0:
            E[E_NEW_SLOTS] = 0.0
            if _stiffest_new_slot(S, pa, pb, pprop, props, pos, inv_mass, prm[PRM_CY_PROBE],
                                  prm[PRM_CY_PROBE_FLOOR], prm[PRM_TINY]) > w2_new:
                out[0] = step
                return RC_STIFF
        if len(quiet_edges) or len(ff_elem):
            qf[:] = 0.0
            quiet_forces(quiet_edges, pos, vel, omg, rot, qf)
            if len(ff_elem):  # docs/dem.md §14.2
                free_field_step(ff_edges, ff_elem, ff_state, presc_val, step, dt, pos, vel, omg,
                                rot, qf)
        sum_unb = 0.0
        sum_app = 0.0
        worst = 0.0
        worst_b = -1
        ke = 0.0
        if len(bolt_node):  # docs/dem.md §15: from the half-step velocities, before they move
            bf[:] = 0.0
            sum_unb, sum_app, ke = bolt_step(
                bolt_node, bolt_state, pos, vel, omg, rot, active, dt, alpha_local, alpha_mass,
                presc_val[step, ref_col[0]] if ref_col[0] >= 0 else 0.0,
                presc_val[step, ref_col[1]] if ref_col[1] >= 0 else 0.0, E, bf)
        moved = False
        vmax = 0.0
        if zoned and zoning is not None:  # docs/dem.md §16.8
            z_unb, z_app, z_ke, z_vmax, moved = zone_step(
                zoning, blocks, pairs, presc_val, step, gravity, alpha_local, alpha_mass, ref_col,
                dt, rebuild_fraction * margin, bf if len(bolt_node) else bf[:0], E)
            sum_unb += z_unb
            sum_app += z_app
            ke += z_ke
            vmax = z_vmax
        for b in range(nb):
            if not active[b] or not movable[b] or zone_of[b] >= 0:
                continue
            # contact forces gathered over the block's pairs in the fixed CSR order (deterministic)
            fc[0] = bf[b, 0]  # bolts act like contacts: in the contact force and its work
            fc[1] = bf[b, 1]
            fc[2] = bf[b, 2]
            fabs = math.sqrt(bf[b, 0] ** 2 + bf[b, 1] ** 2)  # Σ|contact force|: the applied load
            for q in range(bp_ptr[b], bp_ptr[b + 1]):
                e = bp_idx[q]
                p = e >> 1
                o = 3 * (e & 1)
                fc[0] += fpair[p, o]
                fc[1] += fpair[p, o + 1]
                fc[2] += fpair[p, o + 2]
                fabs += math.sqrt(fpair[p, o] ** 2 + fpair[p, o + 1] ** 2)
            c = math.cos(rot[b])
            s = math.sin(rot[b])
            fg[0] = mass[b, 0] * gravity[0]
            fg[1] = mass[b, 1] * gravity[1]
            fg[2] = 0.0
            fe[0] = ext_f[b, 0]
            fe[1] = ext_f[b, 1]
            fe[2] = c * ext_a[b] + s * ext_b[b]
            app = fabs + math.sqrt(fg[0] ** 2 + fg[1] ** 2) + math.sqrt(fe[0] ** 2 + fe[1] ** 2)
            if asleep[b] != 0:
                fx = fc[0] + fg[0] + fe[0] + qf[b, 0]
                fy = fc[1] + fg[1] + fe[1] + qf[b, 1]
                force = math.sqrt(fx * fx + fy * fy)
                own = force  # the block's own ratio weighs its moment too, as for awake blocks
                if mode[b, 2] == 0:
                    own = max(own, abs(fc[2] + fe[2] + qf[b, 2]) / radius[b])
                sum_unb += force
                sum_app += app
                if own <= wake * sleep_ratio * app:
                    if own > worst * app:
                        worst = own / app
                        worst_b = b
                    continue
                asleep[b] = 0
                calm[b] = 0
            unb = 0.0
            unb_m = 0.0
            for d in range(3):  # eqs. (2.1)-(2.2) per degree of freedom
                v_old = vel[b, d] if d < 2 else omg[b]
                if mode[b, d] == 1:
                    continue
                if mode[b, d] == 2:  # prescribed velocity, docs/dem.md §9.2
                    v_new = presc_val[step, dof_input[b, d]]
                    E[E_CONTACT_PRESC] += fc[d] * 0.5 * (v_old + v_new) * dt
                else:
                    v_ref = presc_val[step, ref_col[d]] if ref_col[d] >= 0 else 0.0
                    fv = -alpha_mass * mass[b, d] * (v_old - v_ref)  # eq. (8.2), mass part
                    f = fc[d] + fg[d] + fe[d] + qf[b, d] + fv
                    if d < 2:
                        unb += f * f
                    else:
                        unb_m = abs(f) / radius[b]
                    fd = 0.0
                    if alpha_local > 0.0 and v_old != 0.0:  # eq. (8.1)
                        fd = -alpha_local * abs(f) * (1.0 if v_old > 0 else -1.0)
                    v_new = v_old + (f + fd) * inv_mass[b, d] * dt
                    w = 0.5 * (v_old + v_new) * dt  # eq. (11.2)
                    E[E_CONTACT_FREE] += fc[d] * w
                    E[E_GRAVITY] += fg[d] * w
                    E[E_EXTERNAL] += fe[d] * w
                    E[E_QUIET] += qf[b, d] * w
                    E[E_VISCOUS] += fv * w
                    E[E_LOCAL_DAMP] += fd * w
                if d < 2:
                    vel[b, d] = v_new
                    pos[b, d] += v_new * dt
                    if abs(v_new) > vmax:
                        vmax = abs(v_new)
                else:
                    omg[b] = v_new
                    rot[b] += v_new * dt
                if mode[b, d] == 0:
                    ke += 0.5 * mass[b, d] * v_new * v_new
            sum_unb += math.sqrt(unb)
            sum_app += app
            own = max(math.sqrt(unb), unb_m)
            if own > worst * app:
                worst = own / app if app > 0.0 else np.inf
                worst_b = b
            if sleep_ratio > 0.0:
                speed = math.sqrt(vel[b, 0] ** 2 + vel[b, 1] ** 2) + abs(omg[b]) * radius[b]
                if math.sqrt(unb) < sleep_ratio * app and speed < sleep_speed:
                    calm[b] += 1
                else:
                    calm[b] = 0
                if calm[b] >= sleep_steps:
                    asleep[b] = 1
                    _put_to_sleep(b, mass, vel, omg, E)
            dx = pos[b, 0] - ref_pos[b, 0]
            dy = pos[b, 1] - ref_pos[b, 1]
            if (math.sqrt(dx * dx + dy * dy) + radius[b] * abs(rot[b] - ref_rot[b])
                    > rebuild_fraction * margin):
                moved = True
        ratio = sum_unb / sum_app if sum_app > 0.0 else 0.0
        if not math.isfinite(ratio) or not math.isfinite(vmax):
            out[0] = step + 1
            return RC_NONFINITE
        out[0] = step + 1
        out[1] = ratio
        out[4] = vmax
        out[5] = worst
        out[6] = worst_b
        if tol_ratio > 0.0 and (step + 1) % check_every == 0:  # docs/dem.md §10.1
            falling = ke <= ke_prev
            ke_prev = ke
            out[7] = ke
            if ratio < tol_ratio and worst < block_tol and falling and not moved:
                return RC_CONVERGED
        if moved:
            return RC_REBUILD
    out[0] = n_steps
    out[1] = ratio
    return RC_DONE


# ------------------------------------------------------------------------------------------------
# Deformable blocks: constant-strain triangular zones (docs/dem.md §16). Stresses here are tension
# positive, as everywhere inside the solver; columns ``ZS_*`` of the zone stress, ``ZM_*`` of the
# zone-material table (rockmass.solver.zones.material_table).
# ------------------------------------------------------------------------------------------------

(ZS_XX, ZS_YY, ZS_ZZ, ZS_XY) = range(4)
N_ZS_COLUMNS = 4
(ZM_MODEL, ZM_K, ZM_G, ZM_NPHI, ZM_COH, ZM_NPSI, ZM_TEN, ZM_SIGCI, ZM_MB, ZM_S, ZM_A,
 ZM_MIXED) = range(12)
N_ZM_COLUMNS = 12
ZMODEL_ELASTIC, ZMODEL_MC, ZMODEL_HB = 0, 1, 2
#: plastic state bits of a zone: yielding in shear / tension at the last step, and ever
ZST_SHEAR_NOW, ZST_TENSION_NOW, ZST_SHEAR_PAST, ZST_TENSION_PAST = 1, 2, 4, 8
#: Hoek–Brown: linearisations of the yield curve per return at most (docs/dem.md §16.4); they stop
#: once the minor principal stress moves by less than 1e-10 of the stress scale
HB_ITERATIONS = 50
#: Mohr–Coulomb: corrections per return at most (a correction that reorders the principal
#: stresses is followed by another; two suffice for the small increments of a step)
MC_CORRECTIONS = 20


@njit(cache=True, inline="always")
def _zone_gradients(xy, tri, z):
    """Area A and the shape-function gradients (∂N_i/∂x, ∂N_i/∂y) of zone z from the present
    node positions (docs/dem.md §16.2, eq. (16.1)): 2A = (x_j − x_i)(y_k − y_i) − (x_k − x_i)
    (y_j − y_i), ∂N_i/∂x = (y_j − y_k)/2A, ∂N_i/∂y = (x_k − x_j)/2A, cyclic in (i, j, k)."""
    i = tri[z, 0]
    j = tri[z, 1]
    k = tri[z, 2]
    xi, yi = xy[i, 0], xy[i, 1]
    xj, yj = xy[j, 0], xy[j, 1]
    xk, yk = xy[k, 0], xy[k, 1]
    a2 = (xj - xi) * (yk - yi) - (xk - xi) * (yj - yi)
    inv = 1.0 / a2
    return (0.5 * a2, (yj - yk) * inv, (xk - xj) * inv, (yk - yi) * inv, (xi - xk) * inv,
            (yi - yj) * inv, (xj - xi) * inv)


@njit(cache=True, inline="always")
def _principal_in_plane(sxx, syy, sxy):
    """Centre c, radius r of Mohr's circle and (cos 2θ, sin 2θ) of the major in-plane direction."""
    c = 0.5 * (sxx + syy)
    h = 0.5 * (sxx - syy)
    r = math.sqrt(h * h + sxy * sxy)
    if r > 0.0:
        return c, r, h / r, sxy / r
    return c, 0.0, 1.0, 0.0


@njit(cache=True)
def _mc_correct(s, m, nphi, coh, npsi, ten):
    """One Mohr–Coulomb correction of the stress ``s`` (tension positive, columns ``ZS_*``) in
    place; returns the plastic state bits (0: inside the surface). See :func:`_mc_return`."""
    kk = m[ZM_K]
    gg = m[ZM_G]
    a1 = kk + 4.0 * gg / 3.0
    a2 = kk - 2.0 * gg / 3.0
    c, r, cos2, sin2 = _principal_in_plane(s[ZS_XX], s[ZS_YY], s[ZS_XY])
    lo = c - r
    hi = c + r
    szz = s[ZS_ZZ]
    # order the three principal values; zpos: where σ_zz sits (0: σ₁, 1: σ₂, 2: σ₃)
    if szz <= lo:
        s1, s2, s3, zpos = szz, lo, hi, 0
    elif szz >= hi:
        s1, s2, s3, zpos = lo, hi, szz, 2
    else:
        s1, s2, s3, zpos = lo, szz, hi, 1
    rn = math.sqrt(nphi)
    fs = s1 - s3 * nphi + 2.0 * coh * rn
    ft = ten - s3
    scale = 1e-12 * (abs(s1) + abs(s3) + coh + ten)
    if fs >= -scale and ft >= -scale:
        return 0
    alpha_p = math.sqrt(1.0 + nphi * nphi) + nphi
    sigma_p = ten * nphi - 2.0 * coh * rn
    h = s3 - ten + alpha_p * (s1 - sigma_p)
    bits = 0
    if fs < 0.0 and h <= 0.0:
        lam = fs / ((a1 - a2 * npsi) - (a2 - a1 * npsi) * nphi)
        s1 -= lam * (a1 - a2 * npsi)
        s2 -= lam * a2 * (1.0 - npsi)
        s3 -= lam * (a2 - a1 * npsi)
        bits = ZST_SHEAR_NOW
    else:
        lam = ft / a1
        s1 += lam * a2
        s2 += lam * a2
        s3 += lam * a1
        bits = ZST_TENSION_NOW
    if zpos == 0:
        szz, lo, hi = s1, s2, s3
    elif zpos == 2:
        lo, hi, szz = s1, s2, s3
    else:
        lo, szz, hi = s1, s2, s3
    # the in-plane pair keeps its directions (lo along the minor axis, hi along the major)
    c = 0.5 * (lo + hi)
    r = 0.5 * (hi - lo)
    s[ZS_XX] = c + r * cos2
    s[ZS_YY] = c - r * cos2
    s[ZS_XY] = r * sin2
    s[ZS_ZZ] = szz
    return bits


@njit(cache=True)
def _mc_return(s, m, nphi, coh, npsi, ten):
    """Elastic–perfectly-plastic Mohr–Coulomb with a tension cut-off, one zone's trial stress
    ``s`` (tension positive, columns ``ZS_*``) corrected in place (docs/dem.md §16.3, after Itasca's
    FLAC formulation in principal stresses). Returns the plastic state bits of the correction.

    Principal stresses σ₁ ≤ σ₂ ≤ σ₃ (σ₁ the most compressive; σ_zz is one of them in plane strain).
    Shear yield f_s = σ₁ − σ₃N_φ + 2c√N_φ < 0, tension f_t = σ_t − σ₃ < 0, the region chosen by
    h = σ₃ − σ_t + α_P(σ₁ − σ_P) (α_P = √(1 + N_φ²) + N_φ, σ_P = σ_t N_φ − 2c√N_φ). Shear flow with
    N_ψ: λ = f_s/((α₁ − α₂N_ψ) − (α₂ − α₁N_ψ)N_φ), σ₁ −= λ(α₁ − α₂N_ψ), σ₂ −= λα₂(1 − N_ψ),
    σ₃ −= λ(α₂ − α₁N_ψ); tension: σ₃ = σ_t, σ₁,₂ += α₂(σ_t − σ₃)/α₁ (α₁ = K + 4G/3, α₂ = K − 2G/3).
    A correction that reorders the principal stresses (near the edges σ₁ = σ₂ or σ₂ = σ₃ of the
    pyramid) is followed by another from the result, up to ``MC_CORRECTIONS`` in all, so the
    stress ends on the surface.
    """
    bits = 0
    for _ in range(MC_CORRECTIONS):
        now = _mc_correct(s, m, nphi, coh, npsi, ten)
        if now == 0:
            break
        bits |= now
    return bits


@njit(cache=True)
def _hb_return(s, m, npsi, trial):
    """Generalised Hoek–Brown, σ₁' = σ₃' + σ_ci(m_b σ₃'/σ_ci + s)^a (compression positive,
    Hoek, Carranza-Torres & Corkum 2002), corrected by Mohr–Coulomb returns on the curve's tangent
    at the present minor stress, re-linearised from the trial stress until the minor stress settles
    (at most ``HB_ITERATIONS`` times)
    (docs/dem.md §16.4): N_φ = 1 + a m_b (m_b σ₃'/σ_ci + s)^(a−1), the tangent's uniaxial strength
    σ₁'(σ₃') − N_φσ₃' = 2c√N_φ, and the tension cut-off at the curve's tensile strength s σ_ci/m_b.
    ``trial`` is scratch (4,). Returns the plastic state bits."""
    sci = m[ZM_SIGCI]
    mb = m[ZM_MB]
    ss = m[ZM_S]
    aa = m[ZM_A]
    ten = ss * sci / mb
    floor = 1e-6 * ten  # tangent taken just inside the tensile apex (the slope is infinite there)
    for q in range(4):
        trial[q] = s[q]
    c, r, _c2, _s2 = _principal_in_plane(s[ZS_XX], s[ZS_YY], s[ZS_XY])
    s3 = max(c + r, s[ZS_ZZ])  # the least compressive principal stress (tension positive)
    bits = 0
    for _it in range(HB_ITERATIONS):
        minor = max(-s3, -ten + floor)  # σ₃' compression positive, inside the apex
        base = mb * minor / sci + ss
        nphi = 1.0 + aa * mb * base ** (aa - 1.0)
        ucs = minor + sci * base ** aa - nphi * minor
        coh = ucs / (2.0 * math.sqrt(nphi))
        for q in range(4):
            s[q] = trial[q]
        bits = _mc_return(s, m, nphi, coh, npsi, ten)
        if bits == 0:
            return 0
        c, r, _c2, _s2 = _principal_in_plane(s[ZS_XX], s[ZS_YY], s[ZS_XY])
        s3_new = max(c + r, s[ZS_ZZ])
        if abs(s3_new - s3) <= 1e-10 * (abs(s3) + sci):
            break
        s3 = s3_new
    return bits


@njit(cache=True)
def zone_stress_update(xy, vel, tri, zmat, mtab, sig, strain, state, eps_p, live, dt, mixed,
                       node_ev, node_a, E):
    """The stress update of every zone after the nodes moved by ``vel`` Δt (docs/dem.md §16.2–
    §16.4). Books the plastic work σ:Δε_p as E_ZONE_PLASTIC and, for the zones whose material
    has the mixed discretisation (``ZM_MIXED``; ``mixed``: whether any has), the work
    A ½(σ_xx + σ_yy)(ē − e) the mixed volumetric strain ē adds over the zone's own e as
    E_ZONE_MIXED (the nodes' forces come from the zones' stresses, so this work is done by no
    force: it is the discretisation's, and the ledger states it, docs/dem.md §16.5).

    Strain increment Δε = ½(∇v + ∇vᵀ)Δt and spin θ = ½(∂v_y/∂x − ∂v_x/∂y)Δt of the constant-strain
    triangle on the new geometry; in a mixed zone the volumetric part is replaced by the
    area-weighted mean over the mixed zones around each of its nodes, averaged over the zone's three
    nodes (nodal mixed discretisation, Detournay & Dzik 2006: no volumetric locking under plastic
    flow; ``node_ev``/``node_a`` are scratch of the node count). The stress is rotated by θ
    (Jaumann), takes the elastic increment Δσ = λ tr(Δε) I + 2G Δε (plane strain, σ_zz included),
    and is returned to the yield surface of the zone's model (:func:`_mc_return`,
    :func:`_hb_return`). ``strain`` accumulates the total strain (xx, yy, xy tensor), ``eps_p``
    the plastic strain magnitude, ``state`` the plastic bits. Zones not ``live`` (excavated) are
    left alone.
    """
    nz = len(tri)
    if mixed:
        node_ev[:] = 0.0
        node_a[:] = 0.0
        for z in range(nz):
            if not live[z] or mtab[zmat[z], ZM_MIXED] == 0.0:
                continue
            a, gxi, gyi, gxj, gyj, gxk, gyk = _zone_gradients(xy, tri, z)
            i = tri[z, 0]
            j = tri[z, 1]
            k = tri[z, 2]
            ev = (vel[i, 0] * gxi + vel[j, 0] * gxj + vel[k, 0] * gxk
                  + vel[i, 1] * gyi + vel[j, 1] * gyj + vel[k, 1] * gyk) * dt
            for n in (i, j, k):
                node_ev[n] += a * ev
                node_a[n] += a
    trial = np.empty(4)
    old = np.empty(4)
    scratch = np.empty(4)
    work_p = 0.0
    for z in range(nz):
        if not live[z]:
            continue
        a, gxi, gyi, gxj, gyj, gxk, gyk = _zone_gradients(xy, tri, z)
        i = tri[z, 0]
        j = tri[z, 1]
        k = tri[z, 2]
        lxx = (vel[i, 0] * gxi + vel[j, 0] * gxj + vel[k, 0] * gxk) * dt
        lxy = (vel[i, 0] * gyi + vel[j, 0] * gyj + vel[k, 0] * gyk) * dt
        lyx = (vel[i, 1] * gxi + vel[j, 1] * gxj + vel[k, 1] * gxk) * dt
        lyy = (vel[i, 1] * gyi + vel[j, 1] * gyj + vel[k, 1] * gyk) * dt
        shift = 0.0
        if mixed and mtab[zmat[z], ZM_MIXED] != 0.0:
            ev = (node_ev[i] / node_a[i] + node_ev[j] / node_a[j] + node_ev[k] / node_a[k]) / 3.0
            shift = 0.5 * (ev - lxx - lyy)
            lxx += shift
            lyy += shift
        exy = 0.5 * (lxy + lyx)
        theta = 0.5 * (lyx - lxy)
        strain[z, 0] += lxx
        strain[z, 1] += lyy
        strain[z, 2] += exy
        m = mtab[zmat[z]]
        s = sig[z]
        # rotation (Jaumann), then the elastic trial
        sxx = s[ZS_XX]
        syy = s[ZS_YY]
        sxy = s[ZS_XY]
        s[ZS_XX] = sxx - 2.0 * theta * sxy
        s[ZS_YY] = syy + 2.0 * theta * sxy
        s[ZS_XY] = sxy + theta * (sxx - syy)
        for q in range(4):
            old[q] = s[q]
        kk = m[ZM_K]
        gg = m[ZM_G]
        lam = kk - 2.0 * gg / 3.0
        ev = lxx + lyy
        s[ZS_XX] += lam * ev + 2.0 * gg * lxx
        s[ZS_YY] += lam * ev + 2.0 * gg * lyy
        s[ZS_ZZ] += lam * ev
        s[ZS_XY] += 2.0 * gg * exy
        model = int(m[ZM_MODEL])
        bits = 0
        if model != ZMODEL_ELASTIC:
            for q in range(4):
                trial[q] = s[q]
            if model == ZMODEL_MC:
                bits = _mc_return(s, m, m[ZM_NPHI], m[ZM_COH], m[ZM_NPSI], m[ZM_TEN])
            else:
                bits = _hb_return(s, m, m[ZM_NPSI], scratch)
            if bits != 0:
                # plastic strain D⁻¹(σ_trial − σ) and its work σ:Δε_p (docs/dem.md §16.5)
                dxx = trial[ZS_XX] - s[ZS_XX]
                dyy = trial[ZS_YY] - s[ZS_YY]
                dzz = trial[ZS_ZZ] - s[ZS_ZZ]
                dxy = trial[ZS_XY] - s[ZS_XY]
                p = (dxx + dyy + dzz) / 3.0
                exx = p / (3.0 * kk) + (dxx - p) / (2.0 * gg)
                eyy = p / (3.0 * kk) + (dyy - p) / (2.0 * gg)
                ezz = p / (3.0 * kk) + (dzz - p) / (2.0 * gg)
                gxy = dxy / gg  # engineering shear strain
                work_p += a * (s[ZS_XX] * exx + s[ZS_YY] * eyy + s[ZS_ZZ] * ezz
                               + s[ZS_XY] * gxy)
                eps_p[z] += math.sqrt(exx * exx + eyy * eyy + ezz * ezz + 0.5 * gxy * gxy)
                bits |= bits << 2  # "now" bits also set the "past" bits
        state[z] = (state[z] & (ZST_SHEAR_PAST | ZST_TENSION_PAST)) | bits
        if shift != 0.0:  # mid-step in-plane mean stress × the added volumetric strain 2·shift
            E[E_ZONE_MIXED] += a * 0.5 * (old[ZS_XX] + old[ZS_YY] + s[ZS_XX] + s[ZS_YY]) * shift
    E[E_ZONE_PLASTIC] += work_p


@njit(cache=True)
def zone_forces(xy, tri, sig, live, f, fabs):
    """Nodal forces of the ``live`` zones' stresses, f_i −= A σ·∇N_i (docs/dem.md §16.2, eq.
    (16.2)), added to ``f``; ``fabs`` receives the magnitude of each contribution (the applied
    force of the equilibrium ratio)."""
    for z in range(len(tri)):
        if not live[z]:
            continue
        a, gxi, gyi, gxj, gyj, gxk, gyk = _zone_gradients(xy, tri, z)
        sxx = sig[z, ZS_XX]
        syy = sig[z, ZS_YY]
        sxy = sig[z, ZS_XY]
        for n, gx, gy in ((tri[z, 0], gxi, gyi), (tri[z, 1], gxj, gyj), (tri[z, 2], gxk, gyk)):
            fx = -a * (sxx * gx + sxy * gy)
            fy = -a * (sxy * gx + syy * gy)
            f[n, 0] += fx
            f[n, 1] += fy
            fabs[n] += math.sqrt(fx * fx + fy * fy)


@njit(cache=True)
def zone_nodes_step(xy, vel, fint, fcon, fext, fabs, mass, inv_mass, mode, presc, gravity,
                    alpha_local, alpha_mass, vref_x, vref_y, dt, E):
    """Central-difference step of the zone nodes (docs/dem.md §16.6): per degree of freedom the
    zones' forces ``fint``, the contacts' ``fcon``, the external forces ``fext`` and the weight
    m g (true mass), local damping −α|F|sign(v) and mass damping −α_M m (v − v_ref); fixed dofs
    (``mode`` 1) keep zero velocity, prescribed ones (2) move at ``presc``. ``inv_mass`` may be
    scaled (static relaxation); ``mass`` is the true lumped mass (weight, kinetic energy).
    Returns (Σ|unbalanced force|, Σ applied force, kinetic energy, max speed). Work booked with
    the mid-step velocity (eq. (11.2)): ``fint`` as E_ZONE_INTERNAL, ``fcon`` as
    E_CONTACT_FREE, ``fext`` as E_EXTERNAL, the weight as E_GRAVITY, and the damping."""
    unb = 0.0
    app = 0.0
    ke = 0.0
    vmax = 0.0
    for n in range(len(xy)):
        fn2 = 0.0
        for d in range(2):
            v_old = vel[n, d]
            if mode[n, d] == 1:
                vel[n, d] = 0.0
                continue
            if mode[n, d] == 2:  # the boundary's motion: it works on the model through the
                # node's zones and contacts (E_CONTACT_PRESC, as a prescribed block's contacts)
                E[E_CONTACT_PRESC] += (fint[n, d] + fcon[n, d]) * 0.5 * (v_old + presc[n, d]) * dt
                vel[n, d] = presc[n, d]
                xy[n, d] += presc[n, d] * dt
                continue
            weight = mass[n] * gravity[d]
            v_ref = vref_x if d == 0 else vref_y
            fv = -alpha_mass * mass[n] * (v_old - v_ref)
            ff = fint[n, d] + fcon[n, d] + fext[n, d] + weight + fv
            fd = 0.0
            if alpha_local > 0.0 and v_old != 0.0:
                fd = -alpha_local * abs(ff) * (1.0 if v_old > 0.0 else -1.0)
            v_new = v_old + (ff + fd) * inv_mass[n] * dt
            w = 0.5 * (v_old + v_new) * dt
            E[E_ZONE_INTERNAL] += fint[n, d] * w
            E[E_CONTACT_FREE] += fcon[n, d] * w
            E[E_EXTERNAL] += fext[n, d] * w
            E[E_GRAVITY] += weight * w
            E[E_LOCAL_DAMP] += fd * w
            E[E_VISCOUS] += fv * w
            vel[n, d] = v_new
            xy[n, d] += v_new * dt
            fn2 += ff * ff
            ke += 0.5 * v_new * v_new / inv_mass[n]  # the mass it steps with
            if abs(v_new) > vmax:
                vmax = abs(v_new)
        unb += math.sqrt(fn2)
        app += (fabs[n] + math.sqrt(fext[n, 0] ** 2 + fext[n, 1] ** 2)
                + mass[n] * math.sqrt(gravity[0] ** 2 + gravity[1] ** 2))
    return unb, app, ke, vmax


@njit(cache=True)
def advance_zones(n_steps, xy, vel, tri, zmat, mtab, sig, strain, state, eps_p, mixed, fext,
                  mass, inv_mass, mode, presc, gravity, alpha_local, alpha_mass, dt, tol_ratio,
                  check_every, E, out):
    """Steps of a model of zones only (no contacts): :func:`zone_forces`, :func:`zone_nodes_step`,
    :func:`zone_stress_update` (the stress always belongs to the present positions), until the unbalanced-force ratio Σ|F_unb|/Σ|F_applied| is below
    ``tol_ratio`` at a check (every ``check_every`` steps, with the kinetic energy falling) or
    ``n_steps``. ``out`` receives [steps, ratio, kinetic energy, max speed]; returns
    ``RC_CONVERGED``, ``RC_DONE`` or ``RC_NONFINITE``. The plastic work goes to E_ZONE_PLASTIC."""
    nn = len(xy)
    f = np.zeros((nn, 2))
    none = np.zeros((nn, 2))
    fabs = np.zeros(nn)
    node_ev = np.zeros(nn)
    node_a = np.zeros(nn)
    live = np.ones(len(tri), np.bool_)
    ke_prev = np.inf
    for step in range(n_steps):
        f[:] = 0.0
        fabs[:] = 0.0
        zone_forces(xy, tri, sig, live, f, fabs)
        unb, app, ke, vmax = zone_nodes_step(xy, vel, f, none, fext, fabs, mass, inv_mass, mode,
                                             presc, gravity, alpha_local, alpha_mass, 0.0, 0.0,
                                             dt, E)
        zone_stress_update(xy, vel, tri, zmat, mtab, sig, strain, state, eps_p, live, dt, mixed,
                           node_ev, node_a, E)
        ratio = unb / app if app > 0.0 else 0.0
        out[0] = step + 1
        out[1] = ratio
        out[2] = ke
        out[3] = vmax
        if not math.isfinite(ratio) or not math.isfinite(vmax):
            return RC_NONFINITE
        if tol_ratio > 0.0 and (step + 1) % check_every == 0:
            falling = ke <= ke_prev
            ke_prev = ke
            if ratio < tol_ratio and falling:
                return RC_CONVERGED
    return RC_DONE


# ------------------------------------------------------------------------------------------------
# Deformable blocks in the contact model (docs/dem.md §16.8): each zone is a block of the contact
# search whose vertices, motion and strain rate come from its nodes, and whose contact forces go
# to its nodes.
# ------------------------------------------------------------------------------------------------


@njit(cache=True)
def zone_world_vertices(zoning, off, lgeo, wv):
    """World vertex rows of the zones' blocks from their nodes (columns ``W_*``): the vertex, the
    outward normal of the edge starting there, and the rounded corner of radius r (``lgeo[k, 5]``,
    fixed at set-up) recomputed for the present shape, C = v − r(n₁ + n₂)/(1 + n₁·n₂), tangent
    length r |n₁ × n₂|/(1 + n₁·n₂) (:func:`rockmass.solver.engine.rounded_corners`)."""
    xy, tri, live, zb = zoning.xy, zoning.tri, zoning.live, zoning.zone_block
    for z in range(len(tri)):
        if not live[z]:
            continue
        k0 = off[zb[z]]
        for q in range(3):
            n0 = tri[z, q]
            n1 = tri[z, (q + 1) % 3]
            ex = xy[n1, 0] - xy[n0, 0]
            ey = xy[n1, 1] - xy[n0, 1]
            le = math.sqrt(ex * ex + ey * ey)
            wv[k0 + q, W_X] = xy[n0, 0]
            wv[k0 + q, W_Y] = xy[n0, 1]
            wv[k0 + q, W_NX] = ey / le
            wv[k0 + q, W_NY] = -ex / le
        for q in range(3):
            k = k0 + q
            kp = k0 + (q + 2) % 3
            n1x = wv[kp, W_NX]
            n1y = wv[kp, W_NY]
            n2x = wv[k, W_NX]
            n2y = wv[k, W_NY]
            c = 1.0 + n1x * n2x + n1y * n2y
            r = lgeo[k, 5]
            wv[k, W_TAN] = r * (n1x * n2y - n1y * n2x) / c
            wv[k, W_CX] = wv[k, W_X] - r * (n1x + n2x) / c
            wv[k, W_CY] = wv[k, W_Y] - r * (n1y + n2y) / c
            wv[k, W_RAD] = r


@njit(cache=True, inline="always")
def _barycentric_add(xy, tri, z, px, py, fx, fy, f, fabs):
    """Add the force (fx, fy) at (px, py) to the nodes of zone z with the barycentric weights of
    the point (its resultant and moment are kept exactly, also for a point just outside)."""
    i = tri[z, 0]
    j = tri[z, 1]
    k = tri[z, 2]
    a2 = ((xy[j, 0] - xy[i, 0]) * (xy[k, 1] - xy[i, 1])
          - (xy[k, 0] - xy[i, 0]) * (xy[j, 1] - xy[i, 1]))
    wi = ((xy[j, 0] - px) * (xy[k, 1] - py) - (xy[k, 0] - px) * (xy[j, 1] - py)) / a2
    wj = ((xy[k, 0] - px) * (xy[i, 1] - py) - (xy[i, 0] - px) * (xy[k, 1] - py)) / a2
    wk = 1.0 - wi - wj
    mag = math.sqrt(fx * fx + fy * fy)
    for n, w in ((i, wi), (j, wj), (k, wk)):
        f[n, 0] += w * fx
        f[n, 1] += w * fy
        fabs[n] += abs(w) * mag


@njit(cache=True)
def zone_contact_forces(zoning, zone_of, pa, pb, S):
    """The contact forces on the zones' blocks, slot by slot (``FNA``, ``FSA``: dashpots
    included; eq. (4.5)), given to the zones' nodes at the slot's point (docs/dem.md §16.8)."""
    xy, tri, fcon, fabs = zoning.xy, zoning.tri, zoning.fcon, zoning.fabs
    for p in range(len(pa)):
        za = zone_of[pa[p]]
        zb = zone_of[pb[p]]
        if za < 0 and zb < 0:
            continue
        for k in range(2):
            if S[p, k, ACT] == 0.0:
                continue
            fn = S[p, k, FNA]
            fs = S[p, k, FSA]
            nx = S[p, k, NX]
            ny = S[p, k, NY]
            fx = -fn * nx - fs * ny  # on a (eq. (4.5))
            fy = -fn * ny + fs * nx
            if za >= 0:
                _barycentric_add(xy, tri, za, S[p, k, PX], S[p, k, PY], fx, fy, fcon, fabs)
            if zb >= 0:
                _barycentric_add(xy, tri, zb, S[p, k, PX], S[p, k, PY], -fx, -fy, fcon, fabs)


@njit(cache=True)
def zone_block_motion(zoning, pos, vel, omg, rot, srate, ref_pos, ref_rot, radius, dt, limit):
    """Centroid, velocity, spin and strain rate of each live zone's block from its nodes, and
    whether one moved more than ``limit`` since the pair list was made (docs/dem.md §16.8)."""
    xy, v, tri, live, zb = zoning.xy, zoning.vel, zoning.tri, zoning.live, zoning.zone_block
    moved = False
    for z in range(len(tri)):
        if not live[z]:
            continue
        b = zb[z]
        a, gxi, gyi, gxj, gyj, gxk, gyk = _zone_gradients(xy, tri, z)
        i = tri[z, 0]
        j = tri[z, 1]
        k = tri[z, 2]
        pos[b, 0] = (xy[i, 0] + xy[j, 0] + xy[k, 0]) / 3.0
        pos[b, 1] = (xy[i, 1] + xy[j, 1] + xy[k, 1]) / 3.0
        vel[b, 0] = (v[i, 0] + v[j, 0] + v[k, 0]) / 3.0
        vel[b, 1] = (v[i, 1] + v[j, 1] + v[k, 1]) / 3.0
        lxx = v[i, 0] * gxi + v[j, 0] * gxj + v[k, 0] * gxk
        lxy = v[i, 0] * gyi + v[j, 0] * gyj + v[k, 0] * gyk
        lyx = v[i, 1] * gxi + v[j, 1] * gxj + v[k, 1] * gxk
        lyy = v[i, 1] * gyi + v[j, 1] * gyj + v[k, 1] * gyk
        omg[b] = 0.5 * (lyx - lxy)
        rot[b] += omg[b] * dt
        srate[b, 0] = lxx
        srate[b, 1] = lyy
        srate[b, 2] = 0.5 * (lxy + lyx)
        dx = pos[b, 0] - ref_pos[b, 0]
        dy = pos[b, 1] - ref_pos[b, 1]
        if math.sqrt(dx * dx + dy * dy) + radius[b] * abs(rot[b] - ref_rot[b]) > limit:
            moved = True
    return moved


@njit(cache=True)
def _zone_block_loads(zoning, pos, bf):
    """A force and moment (fx, fy, m) on each zone's block, ``bf`` rows, added to its nodes'
    contact forces keeping the resultant and the moment about the centroid ``pos``."""
    xy, tri, zb, fcon, fabs = zoning.xy, zoning.tri, zoning.zone_block, zoning.fcon, zoning.fabs
    for z in range(len(tri)):
        b = zb[z]
        if bf[b, 0] == 0.0 and bf[b, 1] == 0.0 and bf[b, 2] == 0.0:
            continue
        r2 = 0.0
        for q in range(3):
            n = tri[z, q]
            r2 += (xy[n, 0] - pos[b, 0]) ** 2 + (xy[n, 1] - pos[b, 1]) ** 2
        for q in range(3):
            n = tri[z, q]
            rx = xy[n, 0] - pos[b, 0]
            ry = xy[n, 1] - pos[b, 1]
            fx = bf[b, 0] / 3.0 - bf[b, 2] * ry / r2
            fy = bf[b, 1] / 3.0 + bf[b, 2] * rx / r2
            fcon[n, 0] += fx
            fcon[n, 1] += fy
            fabs[n] += math.sqrt(fx * fx + fy * fy)


@njit(cache=True)
def zone_step(zoning, blocks, pairs, presc_val, step, gravity, alpha_local, alpha_mass, ref_col,
              dt, limit, bf, E):
    """One step of the deformable blocks inside :func:`advance`, after the contact forces: the
    contacts' and the zones' forces on the nodes, the nodes' motion, the stress update and the
    zones' blocks placed on their nodes (docs/dem.md §16.8). ``bf``: the bolts' forces and
    moments on the blocks (:func:`bolt_step`), given to a zone's nodes as F/3 + M ẑ×r_i/Σ|r_j|²
    (r_i from the zone's centroid: the resultant and moment are kept). Returns (Σ|unbalanced|,
    Σ applied, kinetic energy, max speed, moved)."""
    zoning.fint[:] = 0.0
    zoning.fcon[:] = 0.0
    zoning.fabs[:] = 0.0
    zone_contact_forces(zoning, blocks.zone_of, pairs.pa, pairs.pb, pairs.S)
    if len(bf):
        _zone_block_loads(zoning, blocks.pos, bf)
    zone_forces(zoning.xy, zoning.tri, zoning.sig, zoning.live, zoning.fint, zoning.fabs)
    presc = zoning.presc
    node_input = zoning.node_input
    for n in range(len(presc)):
        for d in range(2):
            if zoning.mode[n, d] == 2:
                presc[n, d] = presc_val[step, node_input[n, d]]
    vref_x = presc_val[step, ref_col[0]] if ref_col[0] >= 0 else 0.0
    vref_y = presc_val[step, ref_col[1]] if ref_col[1] >= 0 else 0.0
    unb, app, ke, vmax = zone_nodes_step(
        zoning.xy, zoning.vel, zoning.fint, zoning.fcon, zoning.fext, zoning.fabs, zoning.mass,
        zoning.inv_mass, zoning.mode, presc, gravity, alpha_local, alpha_mass, vref_x, vref_y, dt,
        E)
    zone_stress_update(zoning.xy, zoning.vel, zoning.tri, zoning.zmat, zoning.mtab, zoning.sig,
                       zoning.strain, zoning.state, zoning.eps_p, zoning.live, dt,
                       zoning.mixed[0] != 0, zoning.node_ev, zoning.node_a, E)
    moved = zone_block_motion(zoning, blocks.pos, blocks.vel, blocks.omg, blocks.rot,
                              blocks.srate, pairs.ref_pos, pairs.ref_rot, blocks.radius, dt, limit)
    return unb, app, ke, vmax, moved
