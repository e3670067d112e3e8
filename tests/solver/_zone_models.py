"""Zoned bodies and closed forms for the deformable-block verification problems (docs/dem.md
§16.7): a quarter annulus around a circular opening, graded towards the wall, and Kirsch's,
Salençon's and Carranza-Torres & Fairhurst's solutions."""

from __future__ import annotations

import math

import numpy as np


def quarter_annulus(a: float, outer: float, n_theta: int, first: float, growth: float):
    """Nodes and zones of the quarter annulus a ≤ r ≤ outer, 0 ≤ θ ≤ π/2: rings at radii growing
    by ``growth`` from a first ring width ``first`` (the last stretched to reach ``outer``), each
    quad split along alternating diagonals. Returns (nodes, triangles, radii, n_theta)."""
    radii = [a]
    width = first
    while radii[-1] + width < outer:
        radii.append(radii[-1] + width)
        width *= growth
    radii[-1] = outer
    radii = np.array(radii)
    theta = np.linspace(0.0, math.pi / 2, n_theta + 1)
    rr, tt = np.meshgrid(radii, theta, indexing="ij")
    nodes = np.column_stack([(rr * np.cos(tt)).ravel(), (rr * np.sin(tt)).ravel()])
    idx = np.arange(len(nodes)).reshape(rr.shape)
    tris = []
    for i in range(len(radii) - 1):
        for j in range(n_theta):
            p, q, r, s = idx[i, j], idx[i + 1, j], idx[i + 1, j + 1], idx[i, j + 1]
            if (i + j) % 2 == 0:
                tris += [(p, q, r), (p, r, s)]
            else:
                tris += [(p, q, s), (q, r, s)]
    return nodes, np.array(tris, np.int64), radii, n_theta


def quarter_boundaries(nodes: np.ndarray, radii: np.ndarray, n_theta: int):
    """Node indices of the wall (r = a), the outer arc, the x axis and the y axis, and the outer
    arc's edges (counter-clockwise along the body's boundary)."""
    nt = n_theta + 1
    idx = np.arange(len(nodes)).reshape(len(radii), nt)
    outer = idx[-1]
    edges = np.column_stack([outer[:-1], outer[1:]])
    return idx[0], outer, idx[:, 0], idx[:, -1], edges


def far_field_tractions(zones, edges: np.ndarray, sxx: float, syy: float) -> None:
    """Forces of the far-field stress (compression positive) on the outer edges: t = σ·n l, half
    to each end."""
    x = zones.x0
    d = x[edges[:, 1]] - x[edges[:, 0]]
    n_len = np.column_stack([d[:, 1], -d[:, 0]])  # outward for a CCW outer arc, length-weighted
    t = np.column_stack([-sxx * n_len[:, 0], -syy * n_len[:, 1]])
    np.add.at(zones.fext, edges[:, 0], t / 2)
    np.add.at(zones.fext, edges[:, 1], t / 2)


def kirsch_stresses(r, theta, a, px, py):
    """Kirsch: (σ_r, σ_θ, τ_rθ) around a circular hole of radius a in an infinite plate under the
    far-field σ_xx = px, σ_yy = py (compression positive), θ from the x axis (Kirsch 1898; Brady &
    Brown 2004, §7.2)."""
    p, q = (px + py) / 2, (px - py) / 2
    ar2 = (a / r) ** 2
    c2, s2 = np.cos(2 * theta), np.sin(2 * theta)
    sr = p * (1 - ar2) + q * (1 - 4 * ar2 + 3 * ar2 ** 2) * c2
    st = p * (1 + ar2) - q * (1 + 3 * ar2 ** 2) * c2
    trt = -q * (1 + 2 * ar2 - 3 * ar2 ** 2) * s2
    return sr, st, trt


def kirsch_radial_displacement(r, theta, a, px, py, shear, poisson):
    """Radial displacement induced by excavating the hole (outward positive; plane strain):
    u_r = −(a²/(4G r)) [2P + 2Q (4(1 − ν) − a²/r²) cos 2θ], P = (px + py)/2, Q = (px − py)/2
    (Brady & Brown 2004, §7.2)."""
    p, q = (px + py) / 2, (px - py) / 2
    return -(a * a / (4 * shear * r)) * (2 * p + 2 * q * (4 * (1 - poisson) - (a / r) ** 2)
                                          * np.cos(2 * theta))


def salencon_plastic_radius(a, p0, pi, cohesion, friction_deg):
    """Mohr–Coulomb plastic radius around a circular opening under hydrostatic p0 with internal
    pressure pi (compression positive): R_p = a [2(p0(N − 1) + σ_c) / ((1 + N)((N − 1)pi + σ_c))]^
    (1/(N − 1)), N = (1 + sin φ)/(1 − sin φ), σ_c = 2c√N (Salençon 1969)."""
    s = math.sin(math.radians(friction_deg))
    n = (1 + s) / (1 - s)
    sc = 2 * cohesion * math.sqrt(n)
    return a * (2 * (p0 * (n - 1) + sc) / ((1 + n) * ((n - 1) * pi + sc))) ** (1 / (n - 1))


def hoek_brown_plastic_radius(a, p0, pi, sigma_ci, mb, s):
    """Plastic radius of the original Hoek–Brown criterion (a = 1/2) around a circular opening,
    Carranza-Torres & Fairhurst (1999): scaled stresses P = p/(m_b σ_ci) + s/m_b²; the critical
    scaled pressure P_cr = (1 − √(1 + 16 P0))²/16; R_p = a exp(2(√P_cr − √P_i)) when P_i < P_cr."""
    scale = lambda p: p / (mb * sigma_ci) + s / mb ** 2  # noqa: E731
    p0s, pis = scale(p0), scale(pi)
    pcr = (1 - math.sqrt(1 + 16 * p0s)) ** 2 / 16
    if pis >= pcr:
        return a
    return a * math.exp(2 * (math.sqrt(pcr) - math.sqrt(pis)))


def opening(model, n_theta: int, growth: float, sxx: float, syy: float, nu: float,
            mixed=None, tolerance: float = 1e-7):
    """The quarter annulus a = 1 m to 20 m of :func:`quarter_annulus` under the far field
    (compression positive; σ_zz = p0 when hydrostatic, else the plane-strain ν(σ_xx + σ_yy)), the
    opening excavated at the start, relaxed to ``tolerance``. Returns (zones, wall nodes, ring
    radii, sectors, relax info, seconds)."""
    import time

    from rockmass.solver.zones import Zones

    nodes, tri, radii, nt = quarter_annulus(1.0, 20.0, n_theta, math.pi / 2 / n_theta, growth)
    zones = Zones(nodes, tri, model, mixed=mixed)
    wall, _outer, xaxis, yaxis, edges = quarter_boundaries(nodes, radii, nt)
    zones.fix(xaxis, x=False, y=True)
    zones.fix(yaxis, x=True, y=False)
    zones.set_stress(sxx, syy, sxx if sxx == syy else nu * (sxx + syy))
    far_field_tractions(zones, edges, sxx, syy)
    t0 = time.perf_counter()
    info = zones.relax(tolerance=tolerance, max_steps=400_000)
    return zones, wall, radii, nt, info, time.perf_counter() - t0


def ring_hoop(zones, ring: int, nt: int):
    """Radius, angle and hoop stress of each sector of a ring of :func:`quarter_annulus` (the
    sector's two triangles averaged)."""
    sl = slice(2 * nt * ring, 2 * nt * (ring + 1))
    s = zones.stress[sl].reshape(nt, 2, 4).mean(axis=1)
    c = zones.centroids[sl].reshape(nt, 2, 2).mean(axis=1)
    t = np.arctan2(c[:, 1], c[:, 0])
    hoop = s[:, 0] * np.sin(t) ** 2 + s[:, 1] * np.cos(t) ** 2 - 2 * s[:, 3] * np.sin(t) * np.cos(t)
    return np.hypot(*c.T), t, hoop


def kirsch_errors(zones, wall, nt, px: float, py: float, shear: float, nu: float):
    """Relative errors against Kirsch, as fractions of their peaks: the wall's radial
    displacement, the hoop stress extrapolated to the wall from the first two rings, and the
    first ring's hoop stress against the field at its centroids."""
    x = zones.x0[wall]
    theta = np.arctan2(x[:, 1], x[:, 0])
    ur = (zones.displacement[wall] * x).sum(axis=1)
    exact_u = kirsch_radial_displacement(1.0, theta, 1.0, px, py, shear, nu)
    r0, t0, h0 = ring_hoop(zones, 0, nt)
    r1, _t1, h1 = ring_hoop(zones, 1, nt)
    at_wall = h0 + (h0 - h1) * (r0 - 1.0) / (r1 - r0)
    exact_h = kirsch_stresses(1.0, t0, 1.0, px, py)[1]
    peak = np.max(np.abs(exact_h))
    return (np.max(np.abs(ur - exact_u)) / np.max(np.abs(exact_u)),
            np.max(np.abs(at_wall - exact_h)) / peak,
            np.max(np.abs(h0 - kirsch_stresses(r0, t0, 1.0, px, py)[1])) / peak)
