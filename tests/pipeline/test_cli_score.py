"""``rockmass score``: traces scored against hand-traced labels; the answers come from labels whose
match is known (the face's own truth, the truth moved off the joints, nothing), and bad input."""

import csv
import json

import cv2
import numpy as np
import pytest

from rockmass.cli import main
from rockmass.imaging import synthetic_face
from rockmass.imaging.metrics import render_traces

SCALE = 0.005  # sparse joints: unrelated lines match by chance at F1 0.1-0.2
RIDGE = ["--detector", "ridge"]


def _label(truth_lines: np.ndarray, shift_px: int = 0) -> np.ndarray:
    """A label image as a geologist would paint it: the lines 3 px wide, white on black, moved
    ``shift_px`` pixels down."""
    mask = cv2.dilate(truth_lines.astype(np.uint8), np.ones((3, 3), np.uint8))
    return np.roll(mask * 255, shift_px, axis=0).astype(np.uint8)


@pytest.fixture(scope="module")
def faces(tmp_path_factory):
    """Three plain moderate faces (photos), the centre lines of their joints, and those of three
    other faces (labels of joints that are not in the photos)."""
    folder = tmp_path_factory.mktemp("faces")
    photos = folder / "photos"
    photos.mkdir()
    lines, others = {}, {}
    for seed in (1, 2, 3):
        face = synthetic_face("moderate", seed=seed, shape_px=(300, 400), m_per_px=SCALE)
        cv2.imwrite(str(photos / f"face{seed}.png"), face.image)
        lines[f"face{seed}"] = render_traces(face.truth, face.image.shape, face.m_per_px)
        other = synthetic_face("moderate", seed=seed + 10, shape_px=(300, 400), m_per_px=SCALE)
        others[f"face{seed}"] = render_traces(other.truth, other.image.shape, other.m_per_px)
    return photos, lines, others


def _labels(folder, lines, shift_px=0, **overrides):
    folder.mkdir()
    for stem, truth in lines.items():
        cv2.imwrite(str(folder / f"{stem}.png"), overrides.get(stem, _label(truth, shift_px)))
    return folder


def _rows(out):
    with open(out / "scores.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_the_faces_own_truth_scores_high_and_other_joints_low(faces, tmp_path, capsys):
    photos, lines, others = faces
    right = _labels(tmp_path / "right", lines)
    wrong = _labels(tmp_path / "wrong", others)
    assert main(["score", "--photos", str(photos), "--labels", str(right), "--out",
                 str(tmp_path / "a"), *RIDGE]) == 0
    printed = capsys.readouterr().out
    assert "over 3 photos at 5 px" in printed
    good = json.loads((tmp_path / "a" / "summary.json").read_text())["overall"]
    assert good["photos"] == 3 and good["F1"] > 0.95 and abs(good["dP21_pct"]) < 10
    assert main(["score", "--photos", str(photos), "--labels", str(wrong), "--out",
                 str(tmp_path / "b"), *RIDGE]) == 0
    bad = json.loads((tmp_path / "b" / "summary.json").read_text())["overall"]
    assert bad["F1"] < 0.3


def test_every_joint_finds_more_of_a_truth_that_counts_hairlines(faces, tmp_path):
    # the labels hold every line drawn: --joints all (the network, filters off) finds more of
    # them than the network with the default trace filters, and says so in its settings
    photos, lines, _ = faces
    labels = _labels(tmp_path / "labels", lines)
    recall = {}
    for name, flags in (("all", ["--joints", "all"]), ("filtered", ["--pixel-model", "cnn"])):
        out = tmp_path / name
        assert main(["score", "--photos", str(photos), "--labels", str(labels), "--out", str(out),
                     *flags]) == 0
        summary = json.loads((out / "summary.json").read_text())
        recall[name] = summary["overall"]["recall"]
        if name == "all":
            params = summary["settings"]["params"]
            assert params["min_trace_contrast"] == "-inf" and params["pixel_model"] == "cnn"
    assert recall["all"] >= recall["filtered"] + 0.1


def test_the_tolerance_is_in_pixels_of_the_photograph(faces, tmp_path, capsys):
    # labels moved 12 px down: out of reach at 5 px where a joint runs across the shift, within
    # reach of every joint at 13 px
    photos, lines, _ = faces
    moved = _labels(tmp_path / "moved", lines, shift_px=12)
    f1 = {}
    for tolerance in ("5", "13"):
        assert main(["score", "--photos", str(photos), "--labels", str(moved), "--tolerance",
                     tolerance, "--json", *RIDGE]) == 0
        f1[tolerance] = json.loads(capsys.readouterr().out)["overall"]["F1"]
    assert f1["13"] > 0.9 > f1["5"] + 0.2


def test_scores_csv_holds_each_photo_and_the_summary_their_mean(faces, tmp_path):
    photos, lines, _ = faces
    labels = _labels(tmp_path / "labels", lines)
    out = tmp_path / "out"
    assert main(["score", "--photos", str(photos), "--labels", str(labels), "--out", str(out),
                 *RIDGE]) == 0
    rows = _rows(out)
    assert [r["photo"].rsplit("/", 1)[-1] for r in rows] == ["face1.png", "face2.png", "face3.png"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overall"]["F1"] == pytest.approx(np.mean([float(r["F1"]) for r in rows]))
    drawn = sum(int(r["drawn_px"]) for r in rows)
    labelled = sum(int(r["labelled_px"]) for r in rows)
    assert summary["overall"]["dP21_pct"] == pytest.approx(100 * (drawn / labelled - 1))
    assert all(r["detector"] == "ridge" for r in rows)
    assert summary["settings"]["params"]["detector"] == "ridge"
    manifest = json.loads((out / "manifest.json").read_text())
    assert len(manifest["inputs"]) == 6  # every photo and label, with their digests


def test_review_images_colour_matched_false_and_missed_lines(faces, tmp_path):
    photos, lines, others = faces
    # face1 labelled right; face2 labelled with another face's joints: mostly red and blue
    labels = _labels(tmp_path / "labels", lines, face2=_label(others["face2"]))
    out = tmp_path / "out"
    assert main(["score", "--photos", str(photos), "--labels", str(labels), "--out", str(out),
                 "--review", *RIDGE]) == 0
    colours = {}
    for stem in ("face1", "face2"):
        rgb = cv2.imread(str(out / "review" / f"{stem}.png"))[..., ::-1]
        colours[stem] = {name: int(np.all(rgb == colour, axis=2).sum()) for name, colour in
                         (("matched", (40, 200, 60)), ("false", (230, 40, 40)),
                          ("missed", (40, 110, 255)))}
    assert colours["face1"]["matched"] > 5 * (colours["face1"]["false"] + colours["face1"]["missed"])
    assert colours["face2"]["false"] > colours["face2"]["matched"]
    assert colours["face2"]["missed"] > colours["face2"]["matched"]


def test_a_photo_whose_label_marks_nothing_is_reported_not_averaged(faces, tmp_path, capsys):
    photos, lines, _ = faces
    labels = _labels(tmp_path / "labels", lines, face3=np.zeros((300, 400), np.uint8))
    assert main(["score", "--photos", str(photos), "--labels", str(labels), "--json", *RIDGE]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["overall"]["photos"] == 2
    assert [p.rsplit("/", 1)[-1] for p in document["skipped"]] == ["face3.png"]


@pytest.mark.parametrize("case", ["label size", "label unreadable", "no pairs", "all empty",
                                  "review without out", "tolerance", "config value",
                                  "photo unreadable", "labels with the photos", "two labels"])
def test_bad_input_stops_with_exit_2_naming_the_file_and_keeps_the_previous_outputs(
        faces, tmp_path, capsys, case):
    photos, lines, _ = faces
    good = _labels(tmp_path / "good", lines)
    out = tmp_path / "out"
    assert main(["score", "--photos", str(photos), "--labels", str(good), "--out", str(out),
                 *RIDGE]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    args = ["score", "--photos", str(photos), "--labels", str(good), "--out", str(out), *RIDGE]
    named = None
    if case == "label size":
        labels = _labels(tmp_path / "labels", lines, face3=np.zeros((200, 400), np.uint8))
        args[4], named = str(labels), "face3.png"
    elif case == "label unreadable":
        labels = _labels(tmp_path / "labels", lines)
        (labels / "face2.png").write_bytes(b"not a png")
        args[4], named = str(labels), "face2.png"
    elif case == "no pairs":
        (tmp_path / "elsewhere").mkdir()
        cv2.imwrite(str(tmp_path / "elsewhere" / "other.png"), np.zeros((8, 8), np.uint8))
        args[4], named = str(tmp_path / "elsewhere"), "no photo has a label"
    elif case == "all empty":
        blank = {stem: np.zeros((300, 400), np.uint8) for stem in lines}
        args[4], named = str(_labels(tmp_path / "blank", lines, **blank)), "no label marks any"
    elif case == "review without out":
        args, named = args[:5] + ["--review"], "--out"
    elif case == "tolerance":
        args, named = args + ["--tolerance", "nan"], "--tolerance"
    elif case == "config value":
        config = tmp_path / "bad.toml"
        config.write_text("[imaging.params]\nprob_low = 2.0\n")
        args, named = args + ["--config", str(config)], "prob_low"
    elif case == "photo unreadable":
        broken = tmp_path / "broken"
        broken.mkdir()
        for stem in lines:
            (broken / f"{stem}.png").symlink_to(photos / f"{stem}.png")
        (broken / "face0.png").write_bytes(b"\x89PNG broken")
        labels = _labels(tmp_path / "labels0", {"face0": lines["face1"], **lines})
        args[2], args[4], named = str(broken), str(labels), "face0.png"
    elif case == "labels with the photos":
        args[4], named = str(photos), "the labels are in the photos' folder"
    elif case == "two labels":
        labels = _labels(tmp_path / "labels", lines)
        (labels / "face2.tif").write_bytes((labels / "face2.png").read_bytes())
        args[4], named = str(labels), "face2.png and face2.tif"
    capsys.readouterr()
    assert main(args) == 2
    assert named in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_it_scores_real_photos_as_the_benchmarks_do(tmp_path, capsys):
    # four drone tiles of benchmarks/data/marques2022 (MIT): the command and the benchmarks'
    # own scoring (bench_imaging_real.score_real, another reading path and extraction call) agree
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    sys.path.insert(0, str(root / "benchmarks"))
    from bench_imaging_real import score_real

    from rockmass.imaging.extract import ExtractParams

    data = root / "benchmarks" / "data" / "marques2022"
    photos, labels = tmp_path / "photos", tmp_path / "labels"
    photos.mkdir()
    labels.mkdir()
    tiles = sorted((data / "images").glob("*.png"))[:4]
    for tile in tiles:
        (photos / tile.name).symlink_to(tile)
        (labels / tile.name).symlink_to(data / "labels" / "consolidated" / tile.name)
    assert main(["score", "--photos", str(photos), "--labels", str(labels), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)["overall"]
    expected = score_real([(photos / t.name, labels / t.name) for t in tiles], ExtractParams(), None)
    for ours, theirs in (("F1", "F1"), ("precision", "P"), ("recall", "R"), ("dP21_pct", "dP21_pct"),
                         ("dP20_pct", "dP20_pct")):
        assert got[ours] == pytest.approx(expected[theirs], abs=1e-12), ours


def test_a_new_run_drops_the_review_images_of_an_earlier_one(faces, tmp_path):
    photos, lines, _ = faces
    labels = _labels(tmp_path / "labels", lines)
    out = tmp_path / "out"
    common = ["score", "--photos", str(photos), "--labels", str(labels), "--out", str(out), *RIDGE]
    assert main([*common, "--review"]) == 0
    assert len(list((out / "review").iterdir())) == 3
    (out / "notes.txt").write_text("mine")  # the user's own file stays
    assert main(common) == 0
    assert not (out / "review").exists() and (out / "notes.txt").read_text() == "mine"
