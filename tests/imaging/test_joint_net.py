"""The convolutional joint detector (docs/imaging.md §3.6): the shipped network on faces whose
joints are known, its input, its file handling, "auto"'s third candidate, the random textures and
the training labels. Answers come from the synthetic truth, closed forms and the chain run alone."""

from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from rockmass.dfn import TraceMap
from rockmass.imaging import joint_net, joints_on_photo, synthetic_face
from rockmass.imaging.extract import (AUTO_NETWORK_RATIO, ExtractParams, extract,
                                      network_length_ratio)
from rockmass.imaging.joint_net import (CNN_MODEL_FILE, HALO_PX, MAX_PASS_PIXELS, SIZE_MULTIPLE,
                                        ConvModel, net_input, read_conv_model)
from rockmass.imaging.learned import load_model, model_input, model_record
from rockmass.imaging.metrics import trace_accuracy
from rockmass.imaging.rock_textures import (crack_clutter, photo_rock, power_law_noise,
                                            procedural_rock, random_rock)
from rockmass.imaging.train_joint_net import FIRST_SEED, UNSCORED, tile_labels

CNN = ExtractParams(pixel_model="cnn")
WITHOUT_NETWORK = ExtractParams(auto_network_ratio=float("inf"))  # the two-detector "auto" (§3.3)


def test_the_shipped_network_loads_by_name_and_is_recorded_as_shipped():
    model = load_model("cnn")
    assert isinstance(model, ConvModel) and model.path == CNN_MODEL_FILE
    assert model.input_stretch is not None  # its training recorded the input stretch
    record = model_record("cnn")
    assert record["shipped"] and record["file"] == str(CNN_MODEL_FILE)
    assert "no real photograph" in record["trained_on"]
    # the training command's default seed is the shipped file's, so that the documented command
    # (python -m rockmass.imaging.train_joint_net) writes it again (docs/imaging.md §3.6)
    assert model.info["seed"] == FIRST_SEED


BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


def _benchmark(name: str):
    """A script of benchmarks/ imported as a module (they import each other by name)."""
    import importlib
    import sys

    sys.path.insert(0, str(BENCHMARKS))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(BENCHMARKS))


def test_default_network_ratio_is_the_rules_choice_on_the_saved_training_scores():
    # the per-photo scores bench_network_ratio.py saved (rock-face-fractures train/, real labels):
    # its rule, the smallest ratio at which the network costs the labels nothing, picks the default
    import json

    ratio_bench = _benchmark("bench_network_ratio")
    saved = json.loads((BENCHMARKS / "results" / "bench_network_ratio.json").read_text())
    assert len(saved["photos"]["train"]) == 99
    assert (ratio_bench.chosen_ratio(ratio_bench.rows_of("train", saved["photos"]["train"]))
            == AUTO_NETWORK_RATIO)


def test_network_finds_joints_drawn_on_a_texture_it_never_saw():
    rock = procedural_rock(np.random.default_rng(5), (320, 480))  # a seed outside training's
    face = joints_on_photo(rock, "moderate", seed=7, m_per_px=0.012)
    result = extract(face.image, m_per_px=face.m_per_px, params=CNN)
    accuracy = trace_accuracy(result.traces, face.truth, buffer_px=3.0, m_per_px=face.m_per_px)
    assert accuracy.precision > 0.8 and accuracy.recall > 0.5


def test_network_draws_little_on_rock_without_joints():
    rock = procedural_rock(np.random.default_rng(11), (320, 480))
    result = extract(rock, m_per_px=0.012, params=CNN)
    face_area_m2 = 320 * 480 * 0.012 ** 2
    drawn_p21 = result.traces.lengths_m().sum() / face_area_m2 if result.traces.n_traces else 0.0
    joints = joints_on_photo(rock, "moderate", seed=7, m_per_px=0.012).truth
    assert drawn_p21 < 0.1 * joints.lengths_m().sum() / face_area_m2


def test_probability_map_keeps_the_image_shape_for_any_size_and_is_bounded():
    face = synthetic_face("moderate", seed=4, shape_px=(101, 157), m_per_px=0.01)
    p = load_model("cnn").probability_of(model_input(face.image.astype(np.float32) / 255.0))
    assert p.shape == (101, 157) and p.dtype == np.float32
    assert np.isfinite(p).all() and p.min() >= 0.0 and p.max() <= 1.0
    assert p.max() > 0.9  # it sees the joints


def test_strips_of_rows_give_the_map_of_one_pass(monkeypatch):
    # each strip carries HALO_PX rows of context: the network's reach, so nothing changes; a halo
    # shorter than the reach would change the map near the strips' edges
    rng = np.random.default_rng(3)
    flat = (1.0 + 0.2 * rng.standard_normal((403, 157))).astype(np.float32)
    flat[:, 60:63] = 0.5  # a joint across every strip
    model = load_model("cnn")
    whole = model.probability_of(flat)
    for budget in (1.0, 160 * 230, 160 * 300):  # the smallest strips, and ones ending anywhere
        np.testing.assert_array_equal(model.probability_of(flat, max_pass_pixels=budget), whole)
    assert HALO_PX % SIZE_MULTIPLE == 0 and MAX_PASS_PIXELS < 4e6  # a 4 MP grid goes in strips
    monkeypatch.setattr(joint_net, "HALO_PX", 40)  # less than the reach: the strips' edges show
    assert np.abs(model.probability_of(flat, max_pass_pixels=1.0) - whole).max() > 0.01


def test_two_threads_get_what_one_thread_gets():
    # an OpenCV net keeps the buffers of its last input: each thread must have its own
    images = [model_input(synthetic_face("moderate", seed=s, shape_px=shape, m_per_px=0.01)
                          .image.astype(np.float32) / 255.0)
              for s, shape in ((1, (96, 200)), (2, (160, 120)))]
    model = load_model("cnn")
    alone = [model.probability_of(image) for image in images]
    together = [None, None]

    def run(k):
        for _ in range(3):
            together[k] = model.probability_of(images[k])

    threads = [threading.Thread(target=run, args=(k,)) for k in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(alone, together):
        np.testing.assert_array_equal(a, b)


def test_net_input_is_a_clipped_log():
    flat = np.array([[1.0, np.e ** -0.5, 1e-6, 1e9]], np.float32)
    np.testing.assert_allclose(net_input(flat), [[0.0, -2.0, -8.0, 8.0]], atol=1e-6)


def test_bad_and_missing_network_files_are_named(tmp_path):
    bad = tmp_path / "broken.onnx"
    bad.write_bytes(b"not a network")
    with pytest.raises(ValueError, match="broken.onnx: not an ONNX network"):
        read_conv_model(bad)
    with pytest.raises(ValueError, match="broken.onnx"):
        load_model(str(bad))
    with pytest.raises(FileNotFoundError, match="absent.onnx: no such network file"):
        load_model(str(tmp_path / "absent.onnx"))


def test_auto_keeps_the_network_exactly_when_it_finds_enough_more_length():
    rock = procedural_rock(np.random.default_rng(5), (320, 480))
    face = joints_on_photo(rock, "moderate", seed=7, m_per_px=0.012)
    auto = extract(face.image, m_per_px=face.m_per_px)  # the default: "auto" with the network
    choice = auto.detector_choice
    network = extract(face.image, m_per_px=face.m_per_px, params=CNN)
    learned = extract(face.image, m_per_px=face.m_per_px, params=ExtractParams(detector="learned"))
    ratio = network_length_ratio(network.traces, learned.traces)
    assert choice["agreement"] <= 0.55  # textured rock: the pixel model's over the ridge filter's
    assert choice["network_length_ratio"] == pytest.approx(ratio, rel=1e-12)
    assert choice["auto_network_ratio"] == AUTO_NETWORK_RATIO and np.isfinite(AUTO_NETWORK_RATIO)
    expected = "cnn" if ratio >= choice["auto_network_ratio"] else "learned"
    assert choice["kept"] == expected
    kept = {"cnn": network, "learned": learned}.get(expected)
    if kept is not None:  # the traces are those of the chain run alone
        assert auto.traces.n_traces == kept.traces.n_traces
        for i in range(kept.traces.n_traces):
            np.testing.assert_array_equal(auto.traces.polyline(i), kept.traces.polyline(i))
    if expected == "cnn":
        assert auto.detector_model["file"] == str(CNN_MODEL_FILE)
    # inf does not run the network
    never = extract(face.image, m_per_px=face.m_per_px, params=WITHOUT_NETWORK)
    assert "network_length_ratio" not in never.detector_choice
    assert set(never.detector_choice["traces"]) == {"learned", "ridge"}
    assert "network_probability" not in extract(face.image, m_per_px=face.m_per_px,
                                                params=WITHOUT_NETWORK, debug=True).debug
    with_debug = extract(face.image, m_per_px=face.m_per_px, debug=True)
    assert with_debug.debug["network_probability"].shape == face.image.shape


def test_auto_runs_the_network_only_where_it_keeps_the_pixel_models_traces():
    # a clean face: "auto" keeps the ridge filter's traces, which the network cannot replace
    face = synthetic_face("easy", seed=2, shape_px=(300, 450), m_per_px=0.01)
    auto = extract(face.image, m_per_px=face.m_per_px, debug=True)
    choice = auto.detector_choice
    assert choice["kept"] == "ridge" and choice["agreement"] > 0.55
    assert "network_length_ratio" not in choice and set(choice["traces"]) == {"learned", "ridge"}
    assert choice["auto_network_ratio"] == AUTO_NETWORK_RATIO
    assert "network_probability" not in auto.debug
    alone = extract(face.image, m_per_px=face.m_per_px, params=ExtractParams(detector="ridge"))
    assert auto.traces.n_traces == alone.traces.n_traces


def test_network_length_ratio_edges():
    line = TraceMap.from_polylines([np.array([[0.0, 0.0], [2.0, 0.0]])])
    empty = TraceMap.from_polylines([])
    assert network_length_ratio(line, empty) == float("inf")
    assert network_length_ratio(empty, line) == 0.0
    assert network_length_ratio(empty, empty) == 0.0


@pytest.mark.parametrize("ratio", [0.0, -1.0, float("nan"), "1.2"])
def test_bad_network_ratio_is_refused(ratio):
    with pytest.raises(ValueError, match="auto_network_ratio"):
        ExtractParams(auto_network_ratio=ratio)


def test_power_law_noise_has_the_spectral_slope_asked_for():
    beta = 2.4
    noise = power_law_noise(np.random.default_rng(0), (256, 256), beta)
    power = np.abs(np.fft.fft2(noise)) ** 2
    f = np.hypot(*np.meshgrid(np.fft.fftfreq(256), np.fft.fftfreq(256), indexing="ij"))
    bins = np.geomspace(0.01, 0.4, 12)
    centres, means = [], []
    for lo, hi in zip(bins[:-1], bins[1:]):
        ring = (f >= lo) & (f < hi)
        centres.append(np.sqrt(lo * hi))
        means.append(power[ring].mean())
    slope = np.polyfit(np.log(centres), np.log(means), 1)[0]
    assert slope == pytest.approx(-beta, abs=0.2)


def test_textures_are_reproducible_and_clutter_is_empty_without_cracks():
    a, b = (random_rock(np.random.default_rng(3), (64, 80)) for _ in range(2))
    np.testing.assert_array_equal(a, b)
    assert not crack_clutter(np.random.default_rng(0), (40, 40), 0).any()
    crop = photo_rock(np.random.default_rng(2), (50, 70))
    assert crop.shape == (50, 70) and crop.dtype == np.uint8 and crop.std() > 0


def test_tile_labels_score_the_centre_and_leave_the_band_out():
    lines = np.zeros((20, 30), bool)
    lines[10, :] = True
    ignore = np.zeros_like(lines)
    ignore[:, :5] = True
    labels = tile_labels(lines, ignore)
    assert (labels[9:12, 5:] == 1).all()  # within 1 px
    assert (labels[[7, 8, 12, 13], 5:] == UNSCORED).all()  # 2-3 px: left out
    assert (labels[:7, 5:] == 0).all() and (labels[14:, 5:] == 0).all()
    assert (labels[:7, :5] == UNSCORED).all()  # an ignored negative is not scored


def test_training_tiles_pair_inputs_with_labels_of_their_shape():
    from rockmass.imaging.train_joint_net import training_tiles

    tiles = list(training_tiles(70_000, n_field=1, n_tunnel=0, n_plain=1, n_texture=4))
    assert len(tiles) == 6
    for x, y in tiles:
        assert x.shape == y.shape and x.dtype == np.float16 and np.isfinite(x).all()
        assert set(np.unique(y)) <= {0, 1, UNSCORED}
    assert all((y == 1).any() for _, y in tiles[:2])  # field and plain faces have joints
    assert not tiles[-1][1].any()  # every fourth texture face is rock alone, nothing to find


def test_a_trained_network_reads_back_through_opencv(tmp_path):
    pytest.importorskip("torch")
    pytest.importorskip("onnx")
    from rockmass.imaging.train_joint_net import main

    out = tmp_path / "tiny.onnx"
    assert main(["--out", str(out), "--iterations", "2", "--faces-for-test"]) == 0
    model = load_model(str(out))
    p = model.probability_of(np.ones((40, 52), np.float32))
    assert p.shape == (40, 52) and np.isfinite(p).all()
    assert model.info["iterations"] == 2


def test_a_back_end_config_names_a_shipped_model_by_name_and_a_file_by_its_path(tmp_path):
    # rockmass score --choose-back-end --pixel-model cnn writes a config that must load anywhere
    from types import SimpleNamespace

    from rockmass.imaging.site_back_end import BackEndChoice

    choice = SimpleNamespace(base={"detector": "learned"}, settings={"prob_low": 0.7})
    assert 'pixel_model = "cnn"' in BackEndChoice.config_snippet(choice, "cnn")
    own = tmp_path / "site.npz"
    assert f'pixel_model = "{own.resolve()}"' in BackEndChoice.config_snippet(choice, own)
    assert "pixel_model" not in BackEndChoice.config_snippet(choice, None)


def test_every_back_end_setting_of_the_benchmark_can_be_named_on_its_command_line():
    # bench_network_back_end.py --settings takes the names comma-separated: none may hold a comma
    names = _benchmark("bench_network_back_end").VARIANTS
    assert set(",".join(names).split(",")) == set(names)
