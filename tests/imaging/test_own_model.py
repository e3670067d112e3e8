"""A pixel model trained on the user's own labelled photographs (train_pixel_model --photos), its
label reading, and its use by extract / the CLI (params.pixel_model, --pixel-model)."""

import hashlib
import io
import json

import cv2
import numpy as np
import pytest

from rockmass.cli import main as cli
from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.labels import label_centre_lines, label_mask, labelled_pairs
from rockmass.imaging.learned import MAX_STRETCH, MIN_SPREAD, MODEL_FILE, load_model
from rockmass.imaging.metrics import raster_counts, render_traces
from rockmass.imaging.train_pixel_model import labelled_photo, main as train

from ._photos import as_photo, draw_joint, rock_texture


def _vein_photo(seed, shape=(240, 320), n=5):
    """A grey rock texture crossed by ``n`` straight *bright* veins 3 px wide, and their label
    (white on black). The shipped model is trained on dark joints only."""
    rng = np.random.default_rng(seed)
    image = rock_texture(rng, shape, 0.45, 0.06)
    label = np.zeros(shape, np.uint8)
    for _ in range(n):
        centre, angle = rng.uniform([0, 0], shape[::-1]), rng.uniform(0, np.pi)
        reach = np.array([np.cos(angle), np.sin(angle)]) * 400
        a, b = (tuple(int(v) for v in centre - reach), tuple(int(v) for v in centre + reach))
        draw_joint(image, label, a, b, 0.8)
    return as_photo(image), label


@pytest.fixture(scope="module")
def vein_model(tmp_path_factory):
    root = tmp_path_factory.mktemp("veins")
    (root / "photos").mkdir()
    (root / "labels").mkdir()
    for seed in range(12):
        image, label = _vein_photo(seed)
        cv2.imwrite(str(root / "photos" / f"v{seed:02d}.png"), image)
        cv2.imwrite(str(root / "labels" / f"v{seed:02d}.png"), label)
    out = root / "veins.npz"
    assert train(["--faces", "0", "--epochs", "4", "--photos", str(root / "photos"),
                  "--labels", str(root / "labels"), "--out", str(out)]) == 0
    return root, out


def _precision_recall(image, label, **params):
    truth = label_centre_lines(label)
    result = extract(image, m_per_px=1.0,
                     params=ExtractParams(min_trace_contrast=float("-inf"), **params))
    c = raster_counts(render_traces(result.traces, truth.shape, 1.0), truth, tolerance_px=3.0)
    return c[0] / max(c[1], 1), c[2] / max(c[3], 1)


def test_a_model_trained_on_labelled_vein_photos_finds_the_veins_the_shipped_one_misses(vein_model):
    _, model = vein_model
    info = load_model(model).info
    assert "12 labelled photographs" in info["data"] and "(1 held out)" in info["data"]
    assert "synthetic" not in info["data"]  # --faces 0: the photos only
    for seed in (100, 101):  # photos it never saw
        image, label = _vein_photo(seed)
        shipped = _precision_recall(image, label, detector="learned")
        own = _precision_recall(image, label, pixel_model=str(model))
        assert own[0] > 0.95 and own[1] > 0.95
        assert shipped[0] < 0.5 and shipped[1] < 0.5


def test_labels_painted_red_or_white_on_black_give_the_same_centre_lines(tmp_path):
    _, white = _vein_photo(7)
    painted = np.zeros(white.shape + (3,), np.uint8)
    painted[0, :] = 255  # a white frame, as the rock-face-fractures labels have: not a label
    painted[white > 0] = (0, 0, 255)  # BGR red
    cv2.imwrite(str(tmp_path / "red.png"), painted)
    cv2.imwrite(str(tmp_path / "white.png"), white)
    assert not label_mask(tmp_path / "red.png")[0].all()
    np.testing.assert_array_equal(label_centre_lines(tmp_path / "red.png"),
                                  label_centre_lines(tmp_path / "white.png"))


def test_labels_of_16_bits_with_an_alpha_channel_or_of_0_and_1_read_as_8_bit_ones(tmp_path):
    from PIL import Image

    _, white = _vein_photo(7)
    cv2.imwrite(str(tmp_path / "white.png"), white)
    cv2.imwrite(str(tmp_path / "deep.png"), white.astype(np.uint16) * 257)
    Image.fromarray(np.dstack([white, np.full_like(white, 255)]), "LA").save(tmp_path / "la.png")
    cv2.imwrite(str(tmp_path / "ones.png"), (white > 0).astype(np.uint8))  # a 0/1 mask
    expected = label_mask(tmp_path / "white.png")
    assert expected.any()
    for name in ("deep.png", "la.png", "ones.png"):
        np.testing.assert_array_equal(label_mask(tmp_path / name), expected)
    np.testing.assert_array_equal(label_mask(np.dstack([white, np.full_like(white, 255)])),
                                  expected)  # grey and alpha as an array
    cv2.imwrite(str(tmp_path / "float.tif"), white.astype(np.float32))
    with pytest.raises(ValueError, match="float.tif: a label image must be"):
        label_mask(tmp_path / "float.tif")


def test_photos_without_labels_and_missing_folders_are_named(tmp_path):
    (tmp_path / "photos").mkdir()
    (tmp_path / "labels").mkdir()
    with pytest.raises(FileNotFoundError, match="photos: no photo in the folder"):
        labelled_pairs(tmp_path / "photos", tmp_path / "labels")
    cv2.imwrite(str(tmp_path / "photos" / "a.jpg"), np.zeros((8, 8), np.uint8))
    with pytest.raises(FileNotFoundError, match="labels: no label in the folder"):
        labelled_pairs(tmp_path / "photos", tmp_path / "labels")
    cv2.imwrite(str(tmp_path / "labels" / "b.png"), np.zeros((8, 8), np.uint8))
    with pytest.raises(FileNotFoundError, match="no photo has a label of the same name"):
        labelled_pairs(tmp_path / "photos", tmp_path / "labels")
    (tmp_path / "labels" / "b.png").unlink()
    with pytest.raises(FileNotFoundError, match="no such folder of labels"):
        labelled_pairs(tmp_path / "photos", tmp_path / "nowhere")
    cv2.imwrite(str(tmp_path / "labels" / "a.png"), np.zeros((8, 9), np.uint8))
    with pytest.raises(ValueError, match="a.png: label is 9 x 8 px, its photo a.jpg 8 x 8 px"):
        train(["--faces", "0", "--photos", str(tmp_path / "photos"), "--labels",
               str(tmp_path / "labels"), "--out", str(tmp_path / "m.npz")])


@pytest.mark.parametrize("args, message", [
    (["--photos", "p"], "--photos and --labels go together"),
    (["--photos", "p", "--labels", "l"], "give --out for a model trained on your photos"),
    (["--photos", "p", "--labels", "l", "--out", "m.npz", "--stages", "2"], "use --stages 1"),
    (["--faces", "0", "--plain-faces", "0"], "nothing to train on"),
    (["--crevice-width", "10", "20"], "--crevice-width goes with --wide-crevices"),
    (["--wide-crevices", "1.5"], "the share must be in (0, 1]"),
    (["--wide-crevices", "--crevice-width", "20", "10"], "give 0 < LO <= HI")])
def test_training_options_that_cannot_work_are_refused(args, message, capsys):
    with pytest.raises(SystemExit) as stop:
        train(args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err


def test_large_photos_are_trained_on_the_grid_extraction_runs_the_model_on(tmp_path):
    image, label = _vein_photo(3, shape=(600, 800))
    cv2.imwrite(str(tmp_path / "big.png"), image)
    cv2.imwrite(str(tmp_path / "big_label.png"), label)
    grey, lines = labelled_photo(tmp_path / "big.png", tmp_path / "big_label.png", 0.12)
    work = extract(image, m_per_px=1.0, params=ExtractParams(max_megapixels=0.12)).scale
    assert grey.shape == lines.shape == tuple(work.work_shape_px)
    assert work.work_factor == pytest.approx(0.5, rel=0.01)
    # the centre lines at half the size: on the half-size label, and about half as many pixels
    half = cv2.resize(label, grey.shape[::-1], interpolation=cv2.INTER_AREA) > 0
    assert half[lines].all()
    full = label_centre_lines(label).sum()
    assert 0.4 * full < lines.sum() < 0.6 * full


def test_pixel_model_is_for_the_learned_detector_and_must_exist(tmp_path):
    with pytest.raises(ValueError, match="pixel_model .* is the learned detector's model"):
        ExtractParams(detector="ridge", pixel_model="m.npz")
    with pytest.raises(FileNotFoundError, match="nowhere.npz: no such model file"):
        extract(_vein_photo(0)[0], m_per_px=1.0,
                params=ExtractParams(pixel_model=str(tmp_path / "nowhere.npz")))


def _npy_bytes():
    buffer = io.BytesIO()
    np.save(buffer, np.zeros(3))
    return buffer.getvalue()


@pytest.mark.parametrize("content", [b"hello", b"PK\x03\x04 not a zip", _npy_bytes()])
def test_a_file_that_is_not_a_model_is_refused_by_name(content, tmp_path):
    path = tmp_path / "bad.npz"
    path.write_bytes(content)
    with pytest.raises(ValueError, match="bad.npz: not a pixel model written by"):
        load_model(path)


def test_results_name_the_model_they_came_from(vein_model):
    _, model = vein_model
    image = _vein_photo(100)[0]
    shipped = extract(image, m_per_px=1.0).summary()["detector_model"]
    assert shipped["shipped"] and shipped["file"] == str(MODEL_FILE.resolve())
    assert shipped["sha256"] == hashlib.sha256(MODEL_FILE.read_bytes()).hexdigest()
    assert shipped["trained_on"].startswith("synthetic faces")
    own = extract(image, m_per_px=1.0, params=ExtractParams(pixel_model=str(model))).summary()
    assert not own["detector_model"]["shipped"]
    assert own["detector_model"]["sha256"] == hashlib.sha256(model.read_bytes()).hexdigest()
    assert "12 labelled photographs" in own["detector_model"]["trained_on"]
    # the stretch its training photos went through (learned.model_input), for extract to compare
    assert own["detector_model"]["input_stretch"] == {"min_face_spread": MIN_SPREAD,
                                                      "max_stretch": MAX_STRETCH}
    ridge = extract(image, m_per_px=1.0, params=ExtractParams(detector="ridge")).summary()
    assert ridge["detector_model"] is None


def test_cli_uses_the_model_given_and_records_it(vein_model, tmp_path, capsys):
    root, model = vein_model
    photo = root / "photos" / "v03.png"
    out = tmp_path / "out"
    assert cli(["extract", str(photo), "--m-per-px", "0.01", "--pixel-model", str(model),
                "--out", str(out), "--json"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["extraction"]["params"]["pixel_model"] == str(model)
    assert summary["extraction"]["detector_model"]["file"] == str(model.resolve())
    capsys.readouterr()
    missing = tmp_path / "missing"
    assert cli(["extract", str(photo), "--pixel-model", str(tmp_path / "none.npz"),
                "--out", str(missing)]) == 2
    assert "none.npz: no such model file" in capsys.readouterr().err
    assert not missing.exists()
