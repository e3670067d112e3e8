"""The learned detector's back end chosen for a site model by cross-validation
(rockmass.imaging.site_back_end, train_pixel_model --choose-back-end), and what extract says when a
model's chosen settings are not used."""

import json
import os
import subprocess
import sys
import tomllib

import cv2
import numpy as np
import pytest

from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.labels import label_centre_lines
from rockmass.imaging.learned import MODEL_FILE, load_model, model_record
from rockmass.imaging.site_back_end import (BACK_END_GRID, BackEndScore, choose_back_end,
                                            choose_setting, fold_of)
from rockmass.imaging.train_pixel_model import main as train

from ._photos import as_photo, draw_joint, rock_texture

JOINT_PX = 40  # every joint of the photos below is this long: a length floor above it drops all
CELL_PX = 70


def _short_joint_photo(seed, cells=(3, 4)):
    """A textured grey face with one dark straight joint 3 px wide and JOINT_PX long in each
    CELL_PX cell, at a random angle (none touches another), and its label (white on black)."""
    rng = np.random.default_rng(seed)
    shape = (cells[0] * CELL_PX, cells[1] * CELL_PX)
    image = rock_texture(rng, shape, 0.55, 0.05)
    label = np.zeros(shape, np.uint8)
    for row in range(cells[0]):
        for col in range(cells[1]):
            centre = np.array([(col + 0.5) * CELL_PX, (row + 0.5) * CELL_PX])
            angle = rng.uniform(0, np.pi)
            half = 0.5 * JOINT_PX * np.array([np.cos(angle), np.sin(angle)])
            a, b = (tuple(int(round(v)) for v in centre - half),
                    tuple(int(round(v)) for v in centre + half))
            draw_joint(image, label, a, b, 0.2)
    return as_photo(image), label


@pytest.fixture(scope="module")
def short_joints(tmp_path_factory):
    root = tmp_path_factory.mktemp("short_joints")
    (root / "photos").mkdir()
    (root / "labels").mkdir()
    pairs = []
    for seed in range(10):
        image, label = _short_joint_photo(seed)
        photo, mask = root / "photos" / f"s{seed}.png", root / "labels" / f"s{seed}.png"
        cv2.imwrite(str(photo), image)
        cv2.imwrite(str(mask), label)
        pairs.append((photo, mask))
    return root, pairs


FLOORS = [{"prob_low": 0.8, "prob_high": 0.97, "min_trace_length_px": floor}
          for floor in (70.0, 50.0, 30.0)]


def test_a_length_floor_longer_than_every_joint_is_replaced_by_one_that_keeps_them(short_joints):
    _, pairs = short_joints
    calls = []

    def shipped(train_pairs, fold):  # any model will do: the floor decides
        calls.append((fold, [p for p, _ in train_pairs]))
        return MODEL_FILE

    choice = choose_back_end(pairs, shipped, folds=3, grid=FLOORS)
    # the defaults (70 px) draw next to nothing on joints 40 px long (a few traces are joined
    # across cells); only the 30 px floor keeps them
    assert choice.at_given.f1 < 0.1 and choice.at_given.dp21_pct < -90
    assert choice.scores[1].f1 < 0.5 * choice.chosen.f1
    assert choice.settings["min_trace_length_px"] == 30.0 and not choice.kept_given
    assert choice.chosen.f1 > 0.8 and abs(choice.chosen.dp21_pct) < 25
    # each photo is scored once, by the fold that left it out of training
    assert len(choice.chosen.photo_f1) == len(pairs) == choice.photos
    photos = [p for p, _ in pairs]
    for fold, trained_on in calls:
        held = {photos[k] for k in range(len(photos)) if fold_of(k, len(photos), 3) == fold}
        assert held.isdisjoint(trained_on) and held | set(trained_on) == set(photos)
    # the shipped model at the given settings is the same model here: the same scores
    assert choice.shipped.photo_f1 == choice.at_given.photo_f1
    assert choice.base == {}  # the defaults: nothing else to record


def test_each_photo_is_scored_by_the_model_of_its_own_fold(short_joints, monkeypatch):
    from rockmass.imaging import site_back_end

    _, pairs = short_joints
    scored = []

    def counts(image, lines, params, *_):  # which model scored which photo (by its label's pixels)
        scored.append((int(lines.sum()), params.pixel_model))
        return (1, 1, 1, 1)

    monkeypatch.setattr(site_back_end, "_photo_counts", counts)
    choose_back_end(pairs, lambda train_pairs, fold: f"fold{fold}.npz", folds=4, grid=FLOORS[:1])
    lines = [int(label_centre_lines(label).sum()) for _, label in pairs]
    assert len(set(lines)) == len(lines)  # the label pixel counts name the photos
    for k, n_lines in enumerate(lines):
        models = {model for n, model in scored if n == n_lines and model is not None}
        assert models == {f"fold{fold_of(k, len(pairs), 4)}.npz"}


def test_folds_are_consecutive_photos_of_near_equal_size():
    for n, folds in ((10, 3), (7, 7), (23, 5)):
        assignment = [fold_of(k, n, folds) for k in range(n)]
        assert assignment == sorted(assignment) and set(assignment) == set(range(folds))
        sizes = np.bincount(assignment)
        assert sizes.max() - sizes.min() <= 1


def test_given_settings_outside_the_grid_are_scored_and_recorded(short_joints):
    _, pairs = short_joints
    base = ExtractParams(prob_low=0.7, min_trace_length_px=25.0, min_trace_contrast=0.1)
    choice = choose_back_end(pairs[:4], lambda p, f: MODEL_FILE, folds=2, base=base,
                             grid=FLOORS[:1])
    assert dict(choice.at_given.settings) == {"prob_low": 0.7, "prob_high": 0.97,
                                              "min_trace_length_px": 25.0}
    assert choice.at_given.f1 > 0.8  # the 25 px floor keeps the 40 px joints; 70 px does not
    assert choice.kept_given and choice.chosen is choice.at_given
    assert dict(choice.base) == {"min_trace_contrast": 0.1}


def test_a_photo_whose_label_marks_nothing_is_not_scored(short_joints, tmp_path):
    _, pairs = short_joints
    empty = tmp_path / "empty.png"
    cv2.imwrite(str(empty), np.zeros((3 * CELL_PX, 4 * CELL_PX), np.uint8))
    with_empty = [*pairs[:3], (pairs[3][0], empty)]
    choice = choose_back_end(with_empty, lambda p, f: MODEL_FILE, folds=2, grid=FLOORS)
    assert choice.photos == 3 and choice.skipped == (str(pairs[3][0]),)
    assert len(choice.chosen.photo_f1) == 3
    with pytest.raises(ValueError, match="no label marks any trace"):
        choose_back_end([(pairs[0][0], empty)] * 2, lambda p, f: MODEL_FILE, folds=2, grid=FLOORS)


def test_the_given_settings_stay_unless_a_setting_beats_them_by_more_than_one_standard_error():
    given = BackEndScore({"s": "given"}, 0.60, 0.6, 0.6, -5.0, (0.5, 0.6, 0.7, 0.6))
    tiny = BackEndScore({"s": "tiny"}, 0.61, 0.6, 0.6, -5.0, (0.7, 0.4, 0.72, 0.62))
    clear = BackEndScore({"s": "clear"}, 0.65, 0.6, 0.6, -5.0, (0.56, 0.64, 0.76, 0.64))
    # tiny: gains (0.2, -0.2, 0.02, 0.02), mean 0.01 < standard error 0.08; clear: 0.04 each
    assert choose_setting([tiny], given) is given
    assert choose_setting([tiny, clear], given) is clear
    # a setting within the length tolerance is the candidate even at a lower F1 ...
    level = BackEndScore({"s": "level"}, 0.55, 0.6, 0.6, +10.0, (0.45, 0.55, 0.65, 0.55))
    long = BackEndScore({"s": "long"}, 0.70, 0.6, 0.6, +40.0, (0.6, 0.7, 0.8, 0.7))
    assert choose_setting([long, level], given) is given  # ... and must still beat the given F1
    assert choose_setting([long], given) is long  # none within: the best F1
    with pytest.raises(ValueError, match="no settings"):
        choose_setting([], given)


def test_a_score_with_nothing_drawn_is_recorded_as_json_without_nan():
    nothing = BackEndScore({"s": 1}, 0.0, float("nan"), 0.0, -100.0, (0.0, 0.0))
    record = nothing.record()
    assert record["P"] is None and record["F1"] == 0.0
    json.dumps(record, allow_nan=False)


def test_folds_must_be_between_two_and_the_number_of_photos(short_joints):
    _, pairs = short_joints
    for folds in (1, 11, 2.5, True):
        with pytest.raises(ValueError, match="folds must be an integer from 2 to the number"):
            choose_back_end(pairs, lambda p, f: MODEL_FILE, folds=folds)


def test_the_default_grid_holds_the_defaults_and_keeps_the_levels_ordered():
    defaults = ExtractParams(detector="learned")
    given = {name: defaults.resolved(name) for name in BACK_END_GRID[0]}
    assert given in [dict(s) for s in BACK_END_GRID]
    assert all(s["prob_low"] <= s["prob_high"] for s in BACK_END_GRID)
    assert len({tuple(s.values()) for s in BACK_END_GRID}) == len(BACK_END_GRID)


@pytest.fixture(scope="module")
def chosen_model(short_joints):
    """A photos-only site model whose back end the command chose, and its printed report."""
    root, _ = short_joints
    out = root / "site.npz"
    config = root / "base.toml"
    config.write_text('[imaging.params]\nmin_trace_contrast = -inf\npixel_model = "ignored.npz"\n')
    done = subprocess.run(
        [sys.executable, "-m", "rockmass.imaging.train_pixel_model", "--faces", "0", "--epochs", "3",
         "--photos", str(root / "photos"), "--labels", str(root / "labels"), "--out", str(out),
         "--choose-back-end", "2", "--config", str(config)],
        capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"}, check=True)
    return out, done.stdout, done.stderr


def test_the_command_records_the_choice_and_prints_a_config_that_reproduces_it(chosen_model):
    out, stdout, stderr = chosen_model
    back_end = load_model(out).info["back_end"]
    assert back_end["folds"] == 2 and back_end["photos"] == 10
    assert back_end["settings"]["min_trace_length_px"] == 30.0  # the joints are 40 px long
    assert back_end["at_given_settings"]["F1"] < 0.1
    assert back_end["cross_validated"]["F1"] > 0.5
    assert back_end["with"] == {"min_trace_contrast": float("-inf")}  # the config's, pixel_model left out
    assert "fold 2/2" in stderr
    assert model_record(out)["back_end"] == back_end["settings"]
    # the snippet is TOML whose settings ExtractParams takes: the model's absolute path, the
    # config's other settings and the chosen ones
    snippet = stdout[stdout.index("[imaging.params]"):stdout.index("\nwrote ")]
    params = tomllib.loads(snippet)["imaging"]["params"]
    assert params.pop("pixel_model") == str(out.resolve())
    assert params == {**back_end["with"], **back_end["settings"]}
    ExtractParams(**params)


def test_extract_warns_when_the_settings_chosen_for_its_model_are_not_used(chosen_model):
    out, _, _ = chosen_model
    image, _ = _short_joint_photo(50)
    default = extract(image, m_per_px=0.01, params=ExtractParams(pixel_model=str(out)))
    [note] = [w for w in default.warnings if "chosen for it by cross-validation" in w]
    assert "min_trace_length_px = 70" in note and "set them in [imaging.params]" in note
    assert "min_trace_contrast = 0.25" in note  # the config's setting the choice was made with
    back_end = load_model(out).info["back_end"]
    settings = {**back_end["with"], **back_end["settings"]}
    used = extract(image, m_per_px=0.01, params=ExtractParams(pixel_model=str(out), **settings))
    assert not [w for w in used.warnings if "cross-validation" in w]
    assert used.traces.n_traces > default.traces.n_traces
    shipped = extract(image, m_per_px=0.01, params=ExtractParams(detector="learned"))
    assert not [w for w in shipped.warnings if "cross-validation" in w]


@pytest.mark.parametrize("config, message", [
    ('[imaging.params]\nmin_trace_contrst = 0.1\n',
     "imaging.params: unknown key(s) min_trace_contrst (allowed: max_megapixels,"),
    ('[imaging.params]\nprob_low = 2\n',
     "imaging.params: params.prob_low must be a probability in 0-1, got 2"),
    ('[imaging.params\n', "<file>: invalid TOML: Expected ']' at the end of a table declaration"),
    ('imaging = 3\n', "imaging: must be a table ([section] or {key = value}), got 3"),
    ('[imaging.params]\nline_polarity = "bright"\n', "needs params.detector = 'ridge'"),
    ('[imaging.params]\nmax_megapixels = 8.0\n',
     "max_megapixels = 8.0 differs from the training's --max-megapixels 4"),
])
def test_a_config_the_choice_cannot_start_from_is_refused_by_file_and_field(config, message,
                                                                          short_joints, tmp_path,
                                                                          capsys):
    root, _ = short_joints
    path = tmp_path / "bad.toml"
    path.write_text(config)
    with pytest.raises(SystemExit) as stop:
        train(["--faces", "0", "--photos", str(root / "photos"), "--labels", str(root / "labels"),
               "--out", str(tmp_path / "m.npz"), "--choose-back-end", "2", "--config", str(path)])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert f"--config {path}" in err and message in err
    assert not (tmp_path / "m.npz").exists()


def test_a_config_with_a_byte_order_mark_is_read_as_rockmass_reads_configs(short_joints, tmp_path):
    from rockmass.imaging.train_pixel_model import _config_params

    path = tmp_path / "bom.toml"
    path.write_bytes("\ufeff[imaging.params]\nmin_trace_contrast = -inf\n".encode("utf-8"))
    params = _config_params(path, None, 4.0)
    assert params.min_trace_contrast == float("-inf") and params.detector == "learned"


@pytest.mark.parametrize("args, message", [
    (["--choose-back-end"], "chooses settings on your labelled --photos"),
    (["--config", "c.toml"], "--config goes with --choose-back-end"),
    (["--choose-back-end", "11"],
     "FOLDS must be an integer from 2 to the number of labelled photos (10)"),
])
def test_back_end_options_that_cannot_work_are_refused(args, message, short_joints, tmp_path, capsys):
    root, _ = short_joints
    photos = ["--photos", str(root / "photos"), "--labels", str(root / "labels"),
              "--out", str(tmp_path / "m.npz")]
    with pytest.raises(SystemExit) as stop:
        train(["--faces", "0", *(photos if "11" in args else []), *args])
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


FIT_SCRIPT = """
import numpy as np
from rockmass.imaging.train_pixel_model import fit_mlp
rng = np.random.default_rng(0)
x = rng.normal(size=(6000, 27)).astype(np.float32)
y = (x[:, 0] + 0.5 * x[:, 1] > 0).astype(np.float32)
mean, std, weights, biases = fit_mlp(x, y, epochs=2, seed=1)
print(np.concatenate([w.ravel() for w in weights + biases]).astype(np.float32).tobytes().hex())
"""


def test_a_fit_gives_the_same_weights_whatever_the_number_of_blas_threads():
    fits = []
    for threads in ("1", "2"):
        env = {**os.environ, "OPENBLAS_NUM_THREADS": threads, "OMP_NUM_THREADS": threads}
        done = subprocess.run([sys.executable, "-c", FIT_SCRIPT], capture_output=True, text=True,
                              env=env, check=True)
        fits.append(done.stdout.strip())
    assert fits[0] == fits[1]


def test_model_records_are_json(chosen_model):
    out, _, _ = chosen_model
    json.dumps(model_record(out), allow_nan=False)


def test_the_printed_config_runs_rockmass_extract_with_the_chosen_settings(chosen_model, tmp_path):
    from rockmass.cli import main as cli

    out, stdout, _ = chosen_model
    snippet = stdout[stdout.index("[imaging.params]"):stdout.index("\nwrote ")]
    config = tmp_path / "site.toml"
    config.write_text(snippet + "\n")
    image, _ = _short_joint_photo(51)
    photo = tmp_path / "face.png"
    cv2.imwrite(str(photo), image)
    assert cli(["extract", str(photo), "--m-per-px", "0.01", "--config", str(config),
                "--out", str(tmp_path / "out"), "--json"]) == 0
    extraction = json.loads((tmp_path / "out" / "summary.json").read_text())["extraction"]
    assert extraction["detector_model"]["file"] == str(out.resolve())
    assert extraction["params"]["min_trace_length_px"] == 30.0
    # the config's -inf (no contrast floor) went through, and JSON holds it as text
    assert extraction["params"]["min_trace_contrast"] == "-inf"
    assert extraction["face_contrast"]["contrast_floor"] == "-inf"
    assert not [w for w in extraction["warnings"] if "cross-validation" in w]


def test_a_model_is_trained_on_fewer_than_ten_photos_without_a_held_out_loss(short_joints, tmp_path,
                                                                               capsys):
    root, pairs = short_joints
    (tmp_path / "photos").mkdir()
    (tmp_path / "labels").mkdir()
    for photo, label in pairs[:3]:
        (tmp_path / "photos" / photo.name).symlink_to(photo)
        (tmp_path / "labels" / label.name).symlink_to(label)
    out = tmp_path / "three.npz"
    assert train(["--faces", "0", "--epochs", "1", "--photos", str(tmp_path / "photos"),
                  "--labels", str(tmp_path / "labels"), "--out", str(out)]) == 0
    info = load_model(out).info
    assert info["held_out_log_loss"] is None and info["held_out_samples"] == 0
    assert "3 labelled photographs" in info["data"] and "(0 held out)" in info["data"]
    assert "no held-out loss" in capsys.readouterr().err


def test_the_held_out_score_catches_a_choice_that_only_fits_the_photos_it_was_made_on():
    # two settings, each right on one fold's photos and wrong on the other's; the given one is
    # middling everywhere. The best of the grid on all photos looks better than the given
    # setting, but a choice made on one fold is the wrong one for the other: held out, it loses.
    from rockmass.imaging.site_back_end import held_out_score

    good, bad, middling = (9, 10, 9, 10), (1, 10, 1, 10), (6, 10, 6, 10)  # F1 0.9, 0.1, 0.6
    first = [good, good, good, bad, bad, bad]     # photos 0-2 are fold 0, 3-5 fold 1
    second = [bad, bad, bad, good, good, good]
    given = [middling] * 6
    grid = [{"x": 1}, {"x": 2}]
    score, chosen = held_out_score([first, second], given, [0, 0, 0, 1, 1, 1], grid, {"x": 0})
    assert [dict(c) for c in chosen] == [{"x": 2}, {"x": 1}]  # each fold: the other's best
    assert score.f1 == pytest.approx(0.1)                    # which is wrong on it
    # a setting right on every photo (first in the grid: it wins the tie on fold 0's photos) is
    # chosen in every fold and keeps its score held out
    score, chosen = held_out_score([[good] * 6, first], given, [0, 0, 0, 1, 1, 1], grid, {"x": 0})
    assert [dict(c) for c in chosen] == [{"x": 1}, {"x": 1}] and score.f1 == pytest.approx(0.9)


def test_a_fixed_models_choice_reports_the_held_out_score_and_the_settings_per_fold(short_joints):
    _, pairs = short_joints
    choice = choose_back_end(pairs, lambda p, f: MODEL_FILE, folds=3, grid=FLOORS)
    assert len(choice.fold_settings) == 3 and choice.held_out is not None
    assert len(choice.held_out.photo_f1) == choice.photos == len(pairs)
    # the joints are 40 px long: every fold's choice is the 30 px floor, as on all photos
    assert all(s["min_trace_length_px"] == 30.0 for s in choice.fold_settings)
    assert choice.held_out.f1 == pytest.approx(choice.chosen.f1)
    record = choice.record()["chosen_without_the_photos_scored"]
    assert record["F1"] == pytest.approx(choice.held_out.f1, abs=1e-4) and len(record["settings"]) == 3
    # the shipped model at the given settings is the model's own score there: not extracted twice
    assert choice.shipped.photo_f1 == choice.at_given.photo_f1


def test_rockmass_score_chooses_the_back_end_of_the_shipped_model_and_its_config_scores_so(
        short_joints, tmp_path, capsys):
    from rockmass.cli import main

    root, _ = short_joints
    out = tmp_path / "out"
    assert main(["score", "--photos", str(root / "photos"), "--labels", str(root / "labels"),
                 "--out", str(out), "--choose-back-end", "3", "--joint-width", "3"]) == 0
    printed = capsys.readouterr().out
    assert "what choosing does on photos the choice did not see" in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overall"]["F1"] < 0.1  # the defaults: the 70 px floor drops the 40 px joints
    back_end = summary["back_end"]
    assert back_end["model"] == "shipped" and back_end["settings"]["min_trace_length_px"] <= 50
    assert back_end["chosen_without_the_photos_scored"]["F1"] > 0.8
    imaging = tomllib.loads((out / "back_end.toml").read_text())["imaging"]
    assert "pixel_model" not in imaging["params"]  # the shipped model: no file in the package
    assert imaging["joint_width_px"] == 3.0  # the width it was chosen at goes with it
    # the printed settings do what the choice said, on the command that extracts
    assert main(["score", "--photos", str(root / "photos"), "--labels", str(root / "labels"),
                 "--config", str(out / "back_end.toml"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["overall"]["F1"] > 0.8


def test_rockmass_score_records_an_infinite_setting_of_the_choice_as_text(short_joints, tmp_path,
                                                                           capsys):
    from rockmass.cli import main

    root, pairs = short_joints
    photos, labels = tmp_path / "photos", tmp_path / "labels"
    photos.mkdir()
    labels.mkdir()
    for photo, label in pairs[:2]:
        (photos / photo.name).symlink_to(photo)
        (labels / label.name).symlink_to(label)
    config = tmp_path / "off.toml"
    config.write_text("[imaging.params]\nmin_trace_contrast = -inf\n")
    assert main(["score", "--photos", str(photos), "--labels", str(labels), "--config", str(config),
                 "--choose-back-end", "--json"]) == 0
    back_end = json.loads(capsys.readouterr().out)["back_end"]
    assert back_end["folds"] == 2  # the default, 5, cut to the two photos
    assert back_end["with"]["min_trace_contrast"] == "-inf"
    assert "min_trace_contrast = -inf" in back_end["config"]


@pytest.mark.parametrize("flags, message", [(["--detector", "ridge"], "ridge detector"),
                                            (["--choose-back-end", "1"], "FOLDS must be an integer "
                                             "from 2 to the number of labelled photos (10), got 1"),
                                            (["--choose-back-end", "11"], "FOLDS must be an integer "
                                             "from 2 to the number of labelled photos (10), got 11")])
def test_rockmass_score_refuses_a_back_end_choice_it_cannot_make(short_joints, capsys, flags,
                                                                  message):
    from rockmass.cli import main

    root, _ = short_joints
    args = ["score", "--photos", str(root / "photos"), "--labels", str(root / "labels"),
            "--choose-back-end", "2", *flags]
    assert main(args) == 2
    assert message in capsys.readouterr().err
