"""Trace checks on sections (rockmass.dfn.validation.section_check) and ``[[dfn.sections]]`` in the CLI.

Oracles: a single disk whose trace is worked out by hand; the seed-001 samples at P32 = 1 and 2
(their P21 on the section against Σ P32 / C23 within the Poisson spread of the mean over realizations).
"""

import json
from pathlib import Path

import numpy as np
import pytest
from rockmass.cli import main
from rockmass.dfn import DiskNetwork
from rockmass.dfn.generation import FractureSetSpec, IntensityP32, UniformOrientation
from rockmass.dfn.sizes import ConstantSize
from rockmass.dfn.validation import section_check

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def test_one_disk_across_a_horizontal_section_gives_its_diameter_over_the_area():
    net = DiskNetwork([[0.0, 0.0, 0.0]], [[1.0, 0.0, 0.0]], [1.0], [0], [-5, -5, -5, 5, 5, 5])
    spec = FractureSetSpec(UniformOrientation(), ConstantSize(1.0), IntensityP32(0.1))
    out = section_check(net, [spec], [0, 0, 0], [0, 0, 1], [(-5, -5), (5, -5), (5, 5), (-5, 5)])
    assert out["traces"] == 1 and out["area_m2"] == pytest.approx(100.0)
    assert out["p21"] == pytest.approx(2.0 / 100.0)                         # the diameter, 2 m
    assert out["p21_expected"] == pytest.approx((np.pi / 1000) / (4 / np.pi))   # P32 / C23, isotropic
    assert out["p21_sd"] is None and out["z"] is None                      # one trace: no spread
    json.dumps(out, allow_nan=False)


@pytest.mark.parametrize("sample, p32", [("dfn_seed001.toml", 1.0), ("dfn_seed001_p32_2.toml", 2.0)])
def test_seed001_samples_report_section_p21_near_p32_over_c23(sample, p32, tmp_path):
    out = tmp_path / "out"
    assert main(["dfn", str(SAMPLES / sample), "--out", str(out), "--realizations", "6"]) == 0
    summaries = [json.loads((out / f"realization_{i:04d}" / "summary.json").read_text()) for i in range(6)]
    for s in summaries:
        assert s["total"]["achieved_p32"] == pytest.approx(p32, rel=0.03)
    sections = [s["sections"][0] for s in summaries]
    measured = np.array([s["p21"] for s in sections])
    expected = np.array([s["p21_expected"] for s in sections])
    # realizations are independent: the mean of 6 is within 3 standard errors of the expectation
    standard_error = measured.std(ddof=1) / np.sqrt(measured.size)
    assert abs(measured.mean() - expected.mean()) <= 3 * standard_error
    inv_c23 = sum(_mean_sin_psi(dip, dd, 20.0, [0.0, 1.0, 0.0]) for dip, dd in ((50, 270), (80, 10), (70, 150)))
    assert expected.mean() == pytest.approx(p32 / 3 * inv_c23, rel=0.03)  # achieved P32 is within 3 % of target


def _mean_sin_psi(dip_deg, dip_direction_deg, kappa, m):
    """1/C23 = E[sqrt(1 - (n·m)²)] over a Fisher set, by direct quadrature of the Fisher density."""
    from scipy.integrate import dblquad

    d, a = np.radians(dip_deg), np.radians(dip_direction_deg)
    mean = np.array([np.sin(d) * np.sin(a), np.sin(d) * np.cos(a), np.cos(d)])
    cos_b = float(abs(mean @ np.asarray(m)))
    sin_b = np.sqrt(1 - cos_b ** 2)

    def f(phi, theta):
        c = np.cos(theta) * cos_b + np.sin(theta) * sin_b * np.cos(phi)
        return np.sqrt(max(0.0, 1 - c * c)) * np.exp(kappa * (np.cos(theta) - 1)) * np.sin(theta)

    norm = 2 * np.pi * (1 - np.exp(-2 * kappa)) / kappa
    return dblquad(f, 0, np.pi, 0, 2 * np.pi)[0] / norm


def test_bad_section_window_exits_2_naming_the_section(tmp_path, capsys):
    text = (SAMPLES / "dfn_seed001.toml").read_text().replace(
        "window_uv_m = [[-25.0, 0.0], [25.0, 0.0], [25.0, 6.0], [-25.0, 6.0]]",
        "window_uv_m = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    assert main(["dfn", str(bad), "--out", str(tmp_path / "o"), "--realizations", "1"]) == 2
    assert "dfn.sections[0]" in capsys.readouterr().err
