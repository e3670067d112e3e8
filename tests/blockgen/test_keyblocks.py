"""Keyblocks in the wall and roof of a rectangular tunnel against limit-equilibrium closed forms:
a block sliding on one plane (FS = (W cos ψ tan φ + c A)/(W sin ψ)), a symmetric wedge sliding on two
(FS = tan φ / (sin(ξ/2) tan ψ_i), Hoek & Bray), and a roof pyramid falling free."""

import math

import numpy as np
import pytest

from rockmass.blockgen.blocks3d import Planes, cut_box
from rockmass.blockgen.keyblocks import keyblocks
from rockmass.blockgen.openings3d import Tunnel

BOX = np.array([[0.0, 0.0, 0.0], [4.0, 4.0, 4.0]])
# rectangular tunnel along +y: walls x = 0.5 and x = 2.5, invert z = 1, roof z = 3
TUNNEL = Tunnel(np.array([[-1.0, 0.0], [1.0, 0.0], [1.0, 2.0], [-1.0, 2.0]]), centre_m=(1.5, 0.0, 1.0))
RHO, G = 2500.0, 9.81


def _planes(normals, points, labels):
    n = np.asarray(normals, float)
    n /= np.linalg.norm(n, axis=1)[:, None]
    p = np.asarray(points, float)
    k = len(n)
    return Planes(n, np.einsum("ij,ij->i", n, p), np.asarray(labels), np.zeros((k, 3)), np.full(k, np.inf))


def _block_at(blocks, point):
    for p, piece in enumerate(blocks.pieces):
        inside = True
        for face in piece.faces:
            m = np.cross(face[1] - face[0], face[2] - face[0])
            if (np.asarray(point) - face[0]) @ m > 0:
                inside = False
                break
        if inside:
            return int(blocks.block_id[p])
    raise AssertionError("no piece holds the point")


def _result(results, block):
    return next(r for r in results if r.block == block)


@pytest.mark.parametrize("phi, cohesion", [(20.0, 0.0), (30.0, 0.0), (25.0, 2e4)])
def test_block_sliding_on_one_plane_out_of_the_wall(phi, cohesion):
    psi = 35.0                                   # base dips ψ towards the tunnel (−x)
    s, c = math.sin(math.radians(psi)), math.cos(math.radians(psi))
    planes = _planes([[-s, 0, c], [0, 1, 0], [0, 1, 0], [0, 0, 1]],
                     [[2.5, 2.0, 1.5], [0, 1.7, 0], [0, 2.3, 0], [0, 0, 2.0]], [0, 1, 1, 2])
    blocks = cut_box(BOX, planes, tunnels=(TUNNEL,))
    block = _block_at(blocks, [2.55, 2.0, 1.9])
    strength = {0: (phi, cohesion), 1: (0.0, 0.0), 2: (0.0, 0.0)}
    r = _result(keyblocks(blocks, strength, RHO, G), block)
    # the prism: triangle (wall height 0.5, top length 0.5/tan ψ) x 0.6 m along the tunnel
    volume = 0.5 * 0.5 * (0.5 / math.tan(math.radians(psi))) * 0.6
    base_area = (0.5 / s) * 0.6
    weight = RHO * G * volume
    assert r.volume_m3 == pytest.approx(volume, rel=1e-9)
    assert r.mode == "slide" and r.planes == (0,)
    expected = (weight * c * math.tan(math.radians(phi)) + cohesion * base_area) / (weight * s)
    assert r.factor_of_safety == pytest.approx(expected, rel=1e-9)
    assert r.apex_height_m == pytest.approx(0.5 / math.tan(math.radians(psi)), rel=1e-9)
    np.testing.assert_allclose(r.direction, [-c, 0.0, -s], atol=1e-9)


@pytest.mark.parametrize("plunge, half_angle", [(35.0, 40.0), (45.0, 30.0)])
def test_symmetric_wedge_sliding_on_two_planes(plunge, half_angle):
    pi, hx = math.radians(plunge), math.radians(half_angle)
    w = np.array([-math.sin(pi), 0.0, math.cos(pi)])        # up, perpendicular to the line
    y = np.array([0.0, 1.0, 0.0])
    m_plus = math.cos(hx) * y - math.sin(hx) * w             # outward (from the wedge) normals
    m_minus = -math.cos(hx) * y - math.sin(hx) * w
    apex = [2.5, 2.0, 1.4]
    planes = _planes([m_plus, m_minus, [0, 0, 1]], [apex, apex, [0, 0, 1.9]], [0, 1, 2])
    blocks = cut_box(BOX, planes, tunnels=(TUNNEL,))
    block = _block_at(blocks, [2.52, 2.0, 1.85])
    phi = 30.0
    r = _result(keyblocks(blocks, {0: (phi, 0.0), 1: (phi, 0.0), 2: (0.0, 0.0)}, RHO, G), block)
    assert r.mode == "slide2" and set(r.planes) == {0, 1}
    expected = math.tan(math.radians(phi)) / (math.sin(hx) * math.tan(pi))
    assert r.factor_of_safety == pytest.approx(expected, rel=1e-9)
    np.testing.assert_allclose(r.direction, [-math.cos(pi), 0.0, -math.sin(pi)], atol=1e-9)


def test_roof_pyramid_falls_free_and_a_flat_topped_slab_is_stable():
    # three planes leaning over the roof (z = 3) meet above it: a tetrahedron with its apex up
    centre = np.array([1.5, 2.0, 3.0])
    normals, points = [], []
    for k in range(3):
        a = 2 * math.pi * k / 3
        outward = np.array([math.cos(a), math.sin(a), 0.8])     # from the pyramid into the rock
        normals.append(outward)
        points.append(centre + 0.5 * np.array([math.cos(a), math.sin(a), 0.0]))
    blocks = cut_box(BOX, _planes(normals, points, [0, 1, 2]), tunnels=(TUNNEL,))
    block = _block_at(blocks, centre + [0.0, 0.0, 0.05])
    r = _result(keyblocks(blocks, {}, RHO, G), block)
    assert r.mode == "fall" and r.factor_of_safety == 0.0
    assert r.free_area_m2 > 0


def test_a_block_wider_inside_the_rock_than_at_the_wall_is_locked():
    # two planes converging towards the tunnel, closed at x = 3.5: the block tapers out of the wall
    planes = _planes([[-1, 1, 0], [-1, -1, 0], [0, 0, 1], [0, 0, -1], [1, 0, 0]],
                     [[2.5, 2.2, 0], [2.5, 1.8, 0], [0, 0, 2.0], [0, 0, 1.5], [3.5, 0, 0]],
                     [0, 1, 2, 3, 4])
    blocks = cut_box(BOX, planes, tunnels=(TUNNEL,))
    block = _block_at(blocks, [2.55, 2.0, 1.75])
    r = _result(keyblocks(blocks, {}, RHO, G), block)
    assert r.mode == "locked"
