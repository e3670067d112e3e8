"""Block models and reference solutions for the advanced verification and stress tests.

The models are built by hand (:func:`tests.solver._models.hand_model`) so that every block index is
known; the reference solutions (the continuously-yielding joint as an ODE, the reflection and
transmission of a discrete chain) are computed here from their equations, never from solver output.
"""

from __future__ import annotations

import math

import numpy as np

from ._models import hand_model, rect

__all__ = ["roof_wedge", "chain_column", "cy_branch", "chain_reflection", "chain_transmission",
           "finite_arrays"]


# --------------------------------------------------------------------------------- models --
def roof_wedge(alpha_deg: float, h: float = 1.0, top: float = 0.2, side: float = 2.0):
    """A symmetric roof wedge (docs/dem.md §13, problem 7) between two side blocks.

    Block 1 is the wedge: a trapezoid whose faces lean at the half-apex angle α from the vertical
    and meet above the model (apex up, the free base y = 0 is the roof of the opening). Its top, of
    half-width ``top``, lies on the domain outline, so the side blocks 0 (left) and 2 (right) touch
    nothing but the wedge: the whole horizontal push on a side block's outer face (``"left"`` /
    ``"right"``) reaches the wedge face, H = σ_xx h per face.
    """
    ta = math.tan(math.radians(alpha_deg))
    xb = top + h * ta  # half-width of the wedge at y = 0
    wedge = np.array([[-xb, 0.0], [xb, 0.0], [top, h], [-top, h]])
    left = np.array([[-xb - side, 0.0], [-xb, 0.0], [-top, h], [-xb - side, h]])
    right = np.array([[xb, 0.0], [xb + side, 0.0], [xb + side, h], [top, h]])
    return hand_model([left, wedge, right], [(0, 1), (1, 2)])


def chain_column(n: int, s: float = 1.0, width: float = 1.0, soft_joint: int | None = None):
    """A vertical column of ``n`` blocks of height ``s`` (block 0 at the bottom, block n − 1 on top)
    on n − 1 horizontal joints (set 0, ``"j"``); with ``soft_joint = k`` the joint between blocks
    k − 1 and k is set 1 (``"soft"``). Every block touches the domain outline (its sides), block 0
    the ``"bottom"``, block n − 1 the ``"top"``.

    Rigid blocks on joints are a mass-spring chain: masses m = ρ s w, springs k = k_n w (the two
    sub-contacts of a joint, w/2 each). Its long waves travel at c = s √(k_n/(ρ s)) = √(k_n s/ρ)
    and its impedance per unit area is Z = ρ c = √(ρ k_n s).
    """
    polys = [rect(0.0, k * s, width, (k + 1) * s) for k in range(n)]
    pairs = [(k - 1, k) for k in range(1, n)]
    sets = [1 if (soft_joint is not None and k == soft_joint) else 0 for k in range(1, n)]
    return hand_model(polys, pairs, sets, set_names=("j", "soft"))


# ------------------------------------------------------------ continuously yielding joint --
def cy_branch(tau0: float, phi0: float, d: int, r: float, s_eval: np.ndarray, sigma_n: float,
              ks: float, phi_b: float, rough: float):
    """τ, φ_m and the dilation along one monotonic branch of the CY joint (docs/dem.md §6; Kiran & Juneja 2022, eqs. 6–13) at
    constant σ_n.

    ``s_eval``: path lengths |Δu| from the start of the branch (increasing), ``d`` = ±1 the
    direction, ``r`` the reversal factor (0 on the first loading, τ/τ_m · d at a reversal).
    Below the bounding strength: dτ/ds = d F k_s, F = (1 − dτ/τ_m)/(1 − r), τ_m = σ_n tan φ_m,
    dφ_m/ds = −(φ_m − φ_b)(1 − F)/R, integrated with scipy's DOP853 at rtol 1e-11 up to the event
    dτ = τ_m. On the bound F = 0, so φ_m = φ_b + (φ_m* − φ_b) exp(−(s − s*)/R) in closed form and
    τ = d σ_n tan φ_m. The dilation grows by tan i du_p with i = atan(|τ|/σ_n) − φ_b (eq. 13, no
    contraction when i < 0) and du_p = (1 − F) ds (eq. 11), integrated alongside (on the bound
    tan i = tan(φ_m − φ_b)). Returns (τ(s), φ_m(s), dilation(s) from the branch start, s*, τ(s*));
    s* = inf (τ(s*) = τ at the end) if the bound is not reached.
    """
    from scipy.integrate import solve_ivp

    s_eval = np.asarray(s_eval, float)
    s_end = float(s_eval.max(initial=0.0))

    def rhs(_s, y):
        tau, phi, _dil = y
        tm = sigma_n * math.tan(phi)
        f = (1.0 - d * tau / tm) / (1.0 - r)
        ang = math.atan(abs(tau) / sigma_n) - phi_b
        return [d * f * ks, -(phi - phi_b) * (1.0 - f) / rough,
                math.tan(ang) * (1.0 - f) if ang > 0 else 0.0]

    def rhs_bound(_s, y):
        phi, _dil = y
        return [-(phi - phi_b) / rough, math.tan(phi - phi_b)]

    def bound(_s, y):
        return sigma_n * math.tan(y[1]) - d * y[0]

    bound.terminal = True
    bound.direction = -1
    tau = np.empty_like(s_eval)
    phi = np.empty_like(s_eval)
    dil = np.empty_like(s_eval)
    if s_end <= 0.0:
        tau[:], phi[:], dil[:] = tau0, phi0, 0.0
        return tau, phi, dil, math.inf, tau0
    sol = solve_ivp(rhs, (0.0, s_end), [tau0, phi0, 0.0], method="DOP853", rtol=1e-11,
                    atol=[1e-6 * sigma_n, 1e-14, 1e-15], events=bound, dense_output=True)
    hit = sol.t_events[0]
    s_hit = float(hit[0]) if len(hit) else math.inf
    below = s_eval <= s_hit
    tau[below], phi[below], dil[below] = sol.sol(s_eval[below])
    tau_hit = sol.y[0, -1]
    if len(hit):
        tau_hit, phi_hit, dil_hit = sol.y_events[0][0]
        phi[~below] = phi_b + (phi_hit - phi_b) * np.exp(-(s_eval[~below] - s_hit) / rough)
        tau[~below] = d * sigma_n * np.tan(phi[~below])
        if s_end > s_hit:
            on = solve_ivp(rhs_bound, (s_hit, s_end), [phi_hit, dil_hit], method="DOP853",
                           rtol=1e-11, atol=[1e-14, 1e-15], dense_output=True)
            dil[~below] = on.sol(s_eval[~below])[1]
    return tau, phi, dil, s_hit, tau_hit


# ----------------------------------------------------------------- discrete chain waves --
def _theta(omega, k: float, m: float, dt: float):
    """Wavenumber θ (rad per block) of the leap-frog mass-spring chain at angular frequency ω:
    (2/Δt) sin(ωΔt/2) = 2 √(k/m) sin(θ/2) (central differences in time and space; Δt = 0 for the
    time-continuous chain)."""
    omega = np.atleast_1d(np.asarray(omega, float))
    big = omega if dt <= 0 else 2.0 / dt * np.sin(0.5 * omega * dt)
    return 2.0 * np.arcsin(np.clip(big / (2.0 * math.sqrt(k / m)), 0.0, 1.0))


def chain_reflection(omega, k: float, m: float, c: float, dt: float = 0.0):
    """Complex displacement reflection coefficient of a semi-infinite chain (masses m, springs k,
    sites n = 0, 1, …) whose end mass 0 has a dashpot c to the ground.

    Waves e^{−iωt}; incident e^{−iθn} (towards the end) plus R e^{iθn}. Extending the interior
    equation to a ghost site n = −1, the end-mass equation becomes D c u₀ = k(u₋₁ − u₀), with D the
    dashpot's velocity operator: iω in continuous time; with central differences the solver's
    dashpot uses the velocity of the previous half step, D = (e^{iωΔt} − 1)/Δt. With c = √(km)
    the end absorbs only long waves: |R| ≈ θ/4.
    """
    omega = np.atleast_1d(np.asarray(omega, float))
    theta = _theta(omega, k, m, dt)
    dop = 1j * omega if dt <= 0 else (np.exp(1j * omega * dt) - 1.0) / dt
    e = np.exp(1j * theta)
    # k(e + R/e − 1 − R) = D c (1 + R)
    return (dop * c - k * (e - 1.0)) / (k * (1.0 / e - 1.0) - dop * c)


def chain_transmission(omega, k: float, m: float, kappa: float, dt: float = 0.0):
    """Complex displacement transmission coefficient of an infinite chain (masses m, springs k)
    in which the spring between sites 0 and 1 is κ (the displacement-discontinuity joint of
    Pyrak-Nolte, discrete).

    Incident e^{iθn} plus R e^{−iθn} for n ≤ 0, T e^{iθn} for n ≥ 1. With the chain extended one
    ghost site on each side the equations of masses 0 and 1 read k(u₁ᵍ − u₀) = κ(u₁ − u₀) and
    k(u₀ᵍ − u₁) = κ(u₀ − u₁). As θ → 0 (k = k_n w, m = ρ s w, κ → κ w) this tends to
    T = 1/(1 − iωZ/(2κ)) per unit area, |T| = 2κ/√(4κ² + ω²Z²), Z = √(ρ k_n s).
    """
    omega = np.atleast_1d(np.asarray(omega, float))
    theta = _theta(omega, k, m, dt)
    out = np.empty(len(omega), complex)
    for i, th in enumerate(theta):
        e = np.exp(1j * th)
        a = np.array([[k * (1.0 / e - 1.0) + kappa, -kappa * e],
                      [-kappa, k * (1.0 - e) + kappa * e]], complex)
        rhs = np.array([-k * (e - 1.0) - kappa, kappa], complex)
        out[i] = np.linalg.solve(a, rhs)[1]
    return out


# ------------------------------------------------------------------------------- checks --
def finite_arrays(result) -> list[str]:
    """Names of the arrays / JSON numbers of a Result that are not finite (empty list: all good)."""
    bad = []

    def walk(name, value):
        if isinstance(value, dict):
            for k, v in value.items():
                walk(f"{name}.{k}", v)
        elif isinstance(value, (list, tuple)):
            for i, v in enumerate(value):
                walk(f"{name}[{i}]", v)
        elif isinstance(value, np.ndarray):
            if value.dtype.kind in "fc" and not np.isfinite(value).all():
                bad.append(name)
        elif isinstance(value, float) and not math.isfinite(value):
            bad.append(name)

    for attr in ("displacement_m", "rotation_rad", "velocity_m_s", "history", "contacts",
                 "block_energy", "info"):
        walk(attr, getattr(result, attr))
    for i, f in enumerate(result.frames):
        for attr in ("position_m", "rotation_rad", "velocity_m_s"):
            walk(f"frames[{i}].{attr}", getattr(f, attr))
    walk("json", result.to_json_dict())
    return bad
