"""``rockmass extract``: outputs on a synthetic face and on a real photograph, units, bad input."""

import json

import numpy as np
import pytest

from rockmass.cli import main
from rockmass.dfn import read_traces
from rockmass.imaging import save_synthetic_face, synthetic_face

OUTPUTS = ("traces.geojson", "summary.json", "overlay.png", "rose.png", "manifest.json")


@pytest.fixture(scope="module")
def face_png(tmp_path_factory):
    folder = tmp_path_factory.mktemp("face")
    face = synthetic_face("easy", seed=11, shape_px=(300, 450), m_per_px=0.02)
    return save_synthetic_face(face, folder)["image"], face


def test_synthetic_face_gives_every_output_in_metres(face_png, tmp_path):
    path, face = face_png
    out = tmp_path / "out"
    assert main(["extract", str(path), "--m-per-px", "0.02", "--out", str(out), "--debug",
                 "--detector", "ridge"]) == 0
    for name in OUTPUTS:
        assert (out / name).stat().st_size > 0
    assert list(out.glob("debug_*.png"))
    summary = json.loads((out / "summary.json").read_text())
    traces = read_traces(out / "traces.geojson")
    assert traces.n_traces == summary["extraction"]["n_traces"] > 0
    assert {"id", "set", "length_m", "angle_deg"} <= set(traces.attributes)
    assert summary["extraction"]["units"] == "m"
    assert summary["statistics"]["Fracture Intensity P21"]["unit"] == "m/m²"
    # the truth P21 over the same window: the extraction is within 25 % on an easy face
    truth_p21 = face.truth.total_length_m() / (0.02 * 450 * 0.02 * 300)
    got = summary["statistics"]["Fracture Intensity P21"]["value"]
    assert abs(got - truth_p21) / truth_p21 < 0.25


def test_summary_gives_the_statistics_without_low_score_traces(face_png, tmp_path, capsys):
    # a hand-made threshold on the geojson's joint_score must select what the summary counts
    from rockmass.dfn import trace_map_statistics

    path, _ = face_png
    out = tmp_path / "out"
    assert main(["extract", str(path), "--m-per-px", "0.02", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    traces = read_traces(out / "traces.geojson")
    confident = summary["statistics_confident"]
    score = np.asarray(traces.attributes["joint_score"], dtype=float)
    kept = score >= confident["min_joint_score"]
    assert confident["traces_kept"] == kept.sum() > 0
    assert confident["traces_left_out"] == (~kept).sum()
    stats = confident["statistics"]
    assert stats["Number of Traces"]["value"] == kept.sum()
    expected = trace_map_statistics(traces.subset(kept)).to_dict()["Fracture Intensity P21"]["value"]
    assert stats["Fracture Intensity P21"]["value"] == pytest.approx(expected)
    assert stats["Fracture Intensity P21"]["value"] <= summary["statistics"]["Fracture Intensity P21"]["value"]


def test_bright_lines_with_the_learned_detector_exit_2(face_png, tmp_path, capsys):
    # the learned detector finds dark joints only: asked for bright ones it must refuse, not ignore
    path, _ = face_png
    code = main(["extract", str(path), "--m-per-px", "0.02", "--out", str(tmp_path / "o"),
                 "--bright-lines", "--detector", "learned"])
    assert code == 2
    assert "needs params.detector = 'ridge'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_control_points_give_the_same_scale_as_m_per_px(face_png, tmp_path, capsys):
    path, _ = face_png
    assert main(["extract", str(path), "--control-points", "0", "0", "30", "40", "1.0",
                 "--out", str(tmp_path / "a"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["extraction"]["scale"]["m_per_px"] == pytest.approx(0.02)


def test_missing_scale_runs_in_pixels_with_a_warning(face_png, tmp_path, capsys):
    path, _ = face_png
    assert main(["extract", str(path), "--out", str(tmp_path / "px"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["extraction"]["units"] == "px"
    assert any("pixels" in w for w in summary["extraction"]["warnings"])
    assert summary["statistics"]["Fracture Intensity P21"]["unit"] == "px/px²"


def test_brick_photo_with_bright_lines_finds_the_two_joint_sets(tmp_path, capsys):
    import cv2
    import skimage.data

    photo = tmp_path / "brick.png"
    cv2.imwrite(str(photo), skimage.data.brick())
    assert main(["extract", str(photo), "--bright-lines", "--joint-width", "12",
                 "--out", str(tmp_path / "b"), "--json"]) == 0
    sets = json.loads(capsys.readouterr().out)["statistics"]["sets"]
    angles = sorted(s["Mean Angle"]["value"] % 180 for s in sets)
    assert len(angles) == 2
    assert min(angles[0], 180 - angles[0]) < 10 and abs(angles[1] - 90) < 10


@pytest.mark.parametrize("args, fragment", [
    (["--control-points", "0", "0", "30", "40", "0"], "distance"),
    (["--m-per-px", "-1"], "m_per_px"),
])
def test_bad_scale_exits_2(face_png, tmp_path, capsys, args, fragment):
    path, _ = face_png
    out = tmp_path / "o"
    assert main(["extract", str(path), "--out", str(out), *args]) == 2
    assert fragment in capsys.readouterr().err
    assert not out.exists()


def test_tiny_and_unreadable_images_exit_2(tmp_path, capsys):
    import cv2

    tiny = tmp_path / "tiny.png"
    cv2.imwrite(str(tiny), np.zeros((1, 1), np.uint8))
    assert main(["extract", str(tiny), "--out", str(tmp_path / "t")]) == 2
    assert "tiny.png" in capsys.readouterr().err
    junk = tmp_path / "junk.jpg"
    junk.write_bytes(b"\xff\xd8\xff not a jpeg")
    assert main(["extract", str(junk), "--out", str(tmp_path / "j")]) == 2
    assert "junk.jpg" in capsys.readouterr().err


def test_unknown_imaging_param_in_config_names_the_key(face_png, tmp_path, capsys):
    path, _ = face_png
    config = tmp_path / "c.toml"
    config.write_text("[imaging]\nm_per_px = 0.02\n[imaging.params]\nlow_kk = 2.0\n")
    assert main(["extract", str(path), "--config", str(config), "--out", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "c.toml" in err and "imaging.params" in err and "low_kk" in err


def test_extract_debug_images_do_not_switch_on_tracebacks(tmp_path, capsys):
    """``extract --debug`` writes the intermediate images; it is not the global ``--debug``: a bad
    photo still exits 2 with a message, not 1 with a traceback (issue 18)."""
    bad = tmp_path / "face.png"
    bad.write_bytes(b"not a png at all")
    assert main(["extract", str(bad), "--m-per-px", "0.02", "--out", str(tmp_path / "out"), "--debug"]) == 2
    err = capsys.readouterr().err
    assert "face.png" in err and "Traceback" not in err


@pytest.mark.parametrize("flags, used, mode", [([], True, "border"), (["--face-mask", "full"], True, "full"),
                                               (["--no-face-mask"], False, "off")])
def test_face_mask_is_on_by_default_and_recorded_in_the_summary(face_png, tmp_path, flags, used, mode):
    path, _ = face_png
    out = tmp_path / "out"
    assert main(["extract", str(path), "--m-per-px", "0.02", "--out", str(out), *flags]) == 0
    summary = json.loads((out / "summary.json").read_text())
    info = summary["extraction"]["face_mask"]
    assert info["used"] is used and info["mode"] == mode
    assert summary["extraction"]["params"]["face_mask"] == mode
    # the border band alone: 1 % of the 300 px short side (3 px) on each side of a 300 x 450 photo
    expected = 1 - (300 - 6) * (450 - 6) / (300 * 450) if used else 0.0
    assert info["masked_fraction"] == pytest.approx(expected, abs=0.005)


def test_face_mask_flags_are_exclusive(face_png, tmp_path, capsys):
    path, _ = face_png
    with pytest.raises(SystemExit) as exc:
        main(["extract", str(path), "--out", str(tmp_path / "o"), "--no-face-mask", "--face-mask", "full"])
    assert exc.value.code == 2


@pytest.mark.parametrize("argv, hint", [
    (["--m-per-pix", "0.02"], "--m-per-pix: did you mean --m-per-px?"),
    (["--detecter=ridge"], "--detecter: did you mean --detector?"),
    (["--zzz"], None),
])
def test_an_unknown_option_exits_2_with_the_subcommands_usage_and_the_closest_option(
        face_png, tmp_path, capsys, argv, hint):
    path, _ = face_png
    with pytest.raises(SystemExit) as exc:
        main(["extract", str(path), "--out", str(tmp_path / "o"), *argv])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and not (tmp_path / "o").exists()
    assert "usage: rockmass extract" in err and f"unrecognized arguments: {' '.join(argv)}" in err
    assert (hint in err) if hint else "did you mean" not in err


def test_confident_statistics_fall_back_to_bic_when_too_few_traces_are_kept():
    # three traces at two angles, the two of one angle scored low: --sets 2 fits all traces, not
    # the one kept; its statistics are still given, with sets by BIC and a note saying why
    from rockmass.dfn import TraceMap
    from rockmass.extract_stage import _confident_statistics

    traces = TraceMap.from_polylines(
        [[(0.1, 0.1), (0.9, 0.1)], [(0.1, 0.3), (0.8, 0.9)], [(0.2, 0.2), (0.9, 0.8)]],
        window=[(0, 0), (1, 0), (1, 1), (0, 1)], attributes={"joint_score": [0.9, 0.2, 0.3]})
    entry = _confident_statistics(traces, 2, "m", {})
    assert (entry["traces_kept"], entry["traces_left_out"]) == (1, 2)
    assert entry["statistics"]["Number of Traces"]["value"] == 1
    assert "chosen by BIC" in entry["note"]
    assert _confident_statistics(traces, None, "m", {}).get("note") is None
    # none left out: the statistics of all traces are reused, not fitted again
    every = {"Number of Traces": {"value": 3}}
    all_kept = TraceMap.from_polylines([traces.polyline(i) for i in range(3)],
                                       window=[(0, 0), (1, 0), (1, 1), (0, 1)],
                                       attributes={"joint_score": [0.9, 0.6, 0.5]})
    assert _confident_statistics(all_kept, 2, "m", every)["statistics"] is every


def test_imaging_defaults_without_a_config_are_those_of_the_config_model():
    # rockmass extract without --config writes the [imaging] defaults out instead of importing
    # pydantic for them: they must stay ImagingConfig's
    from rockmass.config import ImagingConfig
    from rockmass.extract_stage import _imaging_defaults

    assert _imaging_defaults() == ImagingConfig().model_dump()


def test_extract_without_a_config_does_not_import_pydantic(face_png, tmp_path):
    import subprocess
    import sys

    path, _ = face_png
    out = tmp_path / "out"
    code = ("import sys\nfrom rockmass.cli import main\n"
            f"assert main(['extract', {str(path)!r}, '--m-per-px', '0.02', '--out', {str(out)!r}, "
            "'--detector', 'ridge']) == 0\n"
            "print('pydantic' in sys.modules, 'rockmass.config' in sys.modules)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split()[-2:] == ["False", "False"]
    manifest = json.loads((out / "manifest.json").read_text())
    from rockmass.config import config_hash

    assert manifest["config_hash"] == config_hash(manifest["config"])


def test_the_process_runs_one_blas_thread_and_keeps_a_users_choice(face_png, tmp_path):
    """`rockmass` as a process sets OPENBLAS_NUM_THREADS to 1 before numpy loads (its own threads
    and OpenBLAS's spin-waiting ones would share the cores), keeps a value the user set, and, once
    main returns, has frozen the garbage collector's objects (gc.freeze)."""
    import os
    import subprocess
    import sys

    path, _ = face_png
    code = ("import gc, os, sys\nfrom rockmass.cli import main\n"
            f"sys.argv = ['rockmass', 'extract', {str(path)!r}, '--m-per-px', '0.02', '--out', "
            f"{str(tmp_path / 'out')!r}, '--detector', 'ridge']\n"
            "assert main() == 0\n"
            "print(os.environ.get('OPENBLAS_NUM_THREADS'), gc.get_freeze_count() > 0)\n")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env=env)
    assert done.stdout.split()[-2:] == ["1", "True"]
    env["OPENBLAS_NUM_THREADS"] = "2"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env=env)
    assert done.stdout.split()[-2:] == ["2", "True"]
