"""``rockmass dfn`` with ``[dfn.fit]``: fit from field files, fitted.json, realizations, validation.json.

The field data of ``samples/dfn_fit_seed001.toml`` are virtual: two scanlines and two mapped faces of
one realization of ``samples/dfn_seed001.toml`` (the three sets of Kiran & Juneja 2022, P32 = 1 m²/m³), made by
:func:`make_field_sample` below (``python -m tests.dfn.test_cli_fit`` rewrites them). Oracles: the
known sets they were sampled from (recovered within the fit's own standard deviations) and the
bundled files equal what the generator writes.
"""

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from rockmass.cli import main
from rockmass.config import load_config
from rockmass.dfn.generation import generate
from rockmass.dfn.traceio import write_traces
from rockmass.dfn.validation import virtual_face, virtual_scanline
from rockmass.dfn_config import DFNDocument

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
SOURCE = SAMPLES / "dfn_seed001.toml"
FIT_SAMPLE = SAMPLES / "dfn_fit_seed001.toml"
#: The two fit samples: (field-data source config, file-name stem, fit config).
VARIANTS = [(SOURCE, "scanline_seed001", FIT_SAMPLE),
            (SAMPLES / "dfn_seed001_p32_2.toml", "scanline_seed001_p32_2", SAMPLES / "dfn_fit_seed001_p32_2.toml")]
#: Field geometry of the sample: (file, start, end) of each scanline ...
SCANLINES = [("_x.csv", (1.0, 20.0, 3.0), (49.0, 20.0, 3.0)),
             ("_y.csv", (25.0, 1.0, 2.0), (25.0, 79.0, 2.0))]
#: ... and (file, point, normal, window) of each face: a pavement at z = 3 m (map view: u East,
#: v North) and a vertical face at y = 40 m looking North (u West, v up).
FACES = [("_pavement.geojson", (0.0, 0.0, 3.0), (0.0, 0.0, 1.0),
          [(1.0, 1.0), (49.0, 1.0), (49.0, 79.0), (1.0, 79.0)]),
         ("_face.geojson", (25.0, 40.0, 0.0), (0.0, 1.0, 0.0),
          [(-24.0, 0.2), (24.0, 0.2), (24.0, 5.8), (-24.0, 5.8)])]


def _scanline_csv(survey, start, source) -> str:
    lines = [f"# Virtual scanline: one realization of samples/{source.name} (seed 1, realization 0),",
             "# written by tests/dfn/test_cli_fit.py::make_field_sample.",
             f"# trend: {survey.trend_deg:.6f}", f"# plunge: {survey.plunge_deg + 0.0:.6f}",
             f"# length: {survey.length_m:.6f}", "# start: " + ", ".join(f"{v:g}" for v in start),
             "distance_m,dip_deg,dip_direction_deg"]
    lines += [f"{d:.4f},{a:.2f},{b:.2f}" for d, a, b in zip(survey.distance_m, survey.dip_deg, survey.dip_direction_deg)]
    return "\n".join(lines) + "\n"


def make_field_sample(folder: Path) -> None:
    """Write the virtual field files of both fit samples into ``folder``."""
    for source, stem, _ in VARIANTS:
        cfg = load_config(source, model=DFNDocument).dfn
        specs = [s.to_spec() for s in cfg.sets]
        net = generate(specs, cfg.domain_m(), seed=cfg.seed, realization=0)
        for suffix, a, b in SCANLINES:
            (folder / (stem + suffix)).write_text(_scanline_csv(virtual_scanline(net, a, b), a, source))
        for suffix, point, normal, window in FACES:
            tm = virtual_face(net, point, normal, window).trace_map
            write_traces(dataclasses.replace(tm, frame="face", attributes={"id": tm.attributes["id"]}),
                         folder / (stem + suffix))


def _same_numbers(written, bundled, tolerance: float, where: str) -> None:
    """The same JSON structure, numbers within ``tolerance``: the generator's floating-point
    results differ in the last bit between machines (numpy picks its SIMD code by CPU), so the
    bundled files are compared by value, not byte for byte."""
    if isinstance(bundled, dict):
        assert isinstance(written, dict) and written.keys() == bundled.keys(), where
        for key in bundled:
            _same_numbers(written[key], bundled[key], tolerance, f"{where}.{key}")
    elif isinstance(bundled, list):
        assert isinstance(written, list) and len(written) == len(bundled), where
        for i, (a, b) in enumerate(zip(written, bundled)):
            _same_numbers(a, b, tolerance, f"{where}[{i}]")
    elif isinstance(bundled, float):
        assert written == pytest.approx(bundled, rel=0, abs=tolerance), where
    else:
        assert written == bundled, where


def test_bundled_field_samples_are_what_the_generator_writes(tmp_path):
    make_field_sample(tmp_path)
    for _, stem, fit_config in VARIANTS:
        for suffix in [s[0] for s in SCANLINES]:  # rounded to 0.1 mm and 0.01°: by value, to that
            name = stem + suffix
            written, bundled = ((folder / name).read_text().splitlines() for folder in (tmp_path, SAMPLES))
            head = [[ln for ln in lines if not ln[:1].isdigit()] for lines in (written, bundled)]
            assert head[0] == head[1], name  # comments and the column names
            rows = [np.array([[float(v) for v in ln.split(",")] for ln in lines if ln[:1].isdigit()])
                    for lines in (written, bundled)]
            assert rows[0].shape == rows[1].shape, name
            np.testing.assert_allclose(rows[0], rows[1], rtol=0, atol=0.01 + 1e-9, err_msg=name)
            assert f'"{name}"' in fit_config.read_text()
        for suffix in [f[0] for f in FACES]:  # coordinates in metres, to 1 nm
            name = stem + suffix
            _same_numbers(json.loads((tmp_path / name).read_text()),
                          json.loads((SAMPLES / name).read_text()), 1e-9, name)
            assert f'"{name}"' in fit_config.read_text()


def test_the_two_fit_samples_differ_only_in_their_field_files_and_comments():
    def body(path, stem):
        lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
        return "\n".join(lines).replace(stem, "STEM")
    assert body(VARIANTS[0][2], VARIANTS[0][1]) == body(VARIANTS[1][2], VARIANTS[1][1])


@pytest.fixture(scope="module", params=[0, 1], ids=["p32_1", "p32_2"])
def fitted_run(request, tmp_path_factory):
    source, _, fit_config = VARIANTS[request.param]
    out = tmp_path_factory.mktemp("fit") / "out"
    assert main(["dfn", str(fit_config), "--out", str(out), "--realizations", "2"]) == 0
    return out, source


def test_fit_run_writes_fitted_json_and_validation_per_realization(fitted_run):
    fitted_run, _ = fitted_run
    names = sorted(p.name for p in fitted_run.iterdir())
    assert names == ["fitted.json", "manifest.json", "realization_0000", "realization_0001"]
    assert sorted(p.name for p in (fitted_run / "realization_0001").iterdir()) == \
        ["fractures.csv", "fractures.vtu", "summary.json", "validation.json"]
    manifest = json.loads((fitted_run / "manifest.json").read_text())
    assert len(manifest["inputs"]) == 1 + len(SCANLINES) + len(FACES)      # the config and every field file
    assert manifest["config"]["dfn"]["fit"]["validate"] is True             # the key as written in TOML
    fitted = json.loads((fitted_run / "fitted.json").read_text())   # strict JSON: no NaN
    assert fitted["n_sets"] == 3
    for s in fitted["sets"]:
        assert s["intensity"]["sd"] > 0 and s["orientation"]["kappa_sd"] > 0
        assert s["size"]["ok"] and s["size"]["sd"]["alpha"] is not None


def test_fitted_sets_match_the_sets_the_field_data_came_from(fitted_run):
    fitted_run, source = fitted_run
    from rockmass.dfn.orientation import angle_between, pole_from_dip

    fitted = json.loads((fitted_run / "fitted.json").read_text())["sets"]
    truth = load_config(source, model=DFNDocument).dfn.sets
    for t in truth:
        pole = pole_from_dip(t.orientation.dip_deg, t.orientation.dip_direction_deg)
        angles = [float(angle_between(pole, pole_from_dip(f["orientation"]["dip_deg"],
                                                           f["orientation"]["dip_direction_deg"]))) for f in fitted]
        f = fitted[int(np.argmin(angles))]
        assert min(angles) <= 1.52 * f["orientation"]["alpha95_deg"]
        assert abs(f["intensity"]["value"] - t.intensity.value) <= 3 * f["intensity"]["sd"]


def test_validation_rows_pass_within_their_poisson_tolerances(fitted_run):
    fitted_run, _ = fitted_run
    doc = json.loads((fitted_run / "realization_0000" / "validation.json").read_text())
    quantities = {r["quantity"] for r in doc["rows"]}
    assert {"p10", "p21", "mean_trace_length_m", "mean_pole_deg"} <= quantities
    # 3σ rows: at most one miss in ~13 by chance
    assert doc["n_failed"] <= 1, [r for r in doc["rows"] if not r["ok"]]


def test_fit_config_without_sizes_or_with_a_missing_file_exits_2_naming_the_field(tmp_path, capsys):
    text = FIT_SAMPLE.read_text().replace('"scanline_seed001_x.csv"', f'"{SAMPLES / "missing.csv"}"')
    bad = tmp_path / "missing.toml"
    bad.write_text(text)
    assert main(["dfn", str(bad), "--out", str(tmp_path / "o")]) == 2
    assert "dfn.fit.scanlines[0]" in capsys.readouterr().err
    no_faces = tmp_path / "no_faces.toml"
    body = FIT_SAMPLE.read_text().split("[[dfn.fit.faces]]")[0]
    no_faces.write_text(body.replace('scanlines = ["', f'scanlines = ["{SAMPLES}/'
                                     ).replace('", "scanline', f'", "{SAMPLES}/scanline'))
    assert main(["dfn", str(no_faces), "--out", str(tmp_path / "o2")]) == 2
    assert "dfn.fit.faces" in capsys.readouterr().err
    assert not (tmp_path / "o").exists() and not (tmp_path / "o2").exists()


def test_sets_and_fit_together_are_refused(tmp_path, capsys):
    both = tmp_path / "both.toml"
    both.write_text(SOURCE.read_text().replace("[dfn.domain]", '[dfn.fit]\nscanlines = ["a.csv"]\n'
                                               'size = { distribution = "constant", radius_m = 1.0 }\n\n[dfn.domain]'))
    assert main(["dfn", str(both), "--out", str(tmp_path / "o")]) == 2
    assert "dfn.sets" in capsys.readouterr().err


def test_bootstrap_orientation_generates_only_measured_poles(tmp_path):
    from rockmass.dfn.network_io import read_fractures_csv
    from rockmass.dfn.scanline import read_scanline

    text = FIT_SAMPLE.read_text().replace('"scanline_seed001', f'"{SAMPLES}/scanline_seed001')
    config = tmp_path / "boot.toml"
    config.write_text(text.replace('size_family = "power_law"', 'size_family = "power_law"\norientation = "bootstrap"'))
    out = tmp_path / "out"
    assert main(["dfn", str(config), "--out", str(out), "--realizations", "1"]) == 0
    summary = json.loads((out / "realization_0000" / "summary.json").read_text())
    net = read_fractures_csv(out / "realization_0000" / "fractures.csv", summary["domain_m"])
    poles = np.concatenate([read_scanline(SAMPLES / (VARIANTS[0][1] + s[0])).poles() for s in SCANLINES])
    # the CSV keeps 9+ significant digits; the scanline files 2 decimals of a degree
    assert np.allclose(np.abs(net.normal @ poles.T).max(axis=1), 1.0, atol=1e-8)


if __name__ == "__main__":
    make_field_sample(SAMPLES if len(sys.argv) < 2 else Path(sys.argv[1]))
