"""``samples/extract_fine_joints.toml``, the recipe for a map of every joint (docs/imaging.md §8.4):
it validates, gives the settings it says, and on a synthetic face, whose truth counts every line
drawn (hairlines too), finds clearly more of the truth than the network with the default trace
filters, its precision still above 0.9."""

from pathlib import Path

import pytest

from rockmass.config import load_config
from rockmass.imaging.extract import ExtractParams, extract
from rockmass.imaging.metrics import trace_accuracy
from rockmass.imaging.synthetic import synthetic_face

SAMPLE = Path(__file__).resolve().parents[2] / "samples" / "extract_fine_joints.toml"


def test_the_recipe_turns_the_trace_filters_off_on_the_network():
    params = ExtractParams(**load_config(SAMPLE).imaging.params)
    assert (params.detector, params.pixel_model) == ("learned", "cnn")
    assert params.min_trace_contrast == float("-inf") and params.min_trace_width == 0.0
    assert params.min_trace_length_px == 20.0


@pytest.mark.parametrize("seed", [2, 3])
def test_the_recipe_finds_the_fine_joints_the_default_filters_drop(seed):
    face = synthetic_face("moderate", seed=seed, shape_px=(400, 600), m_per_px=0.008)
    fine = ExtractParams(**load_config(SAMPLE).imaging.params)
    filtered = ExtractParams(detector="learned", pixel_model="cnn")
    a_fine, a_filtered = (trace_accuracy(extract(face.image, m_per_px=0.008, params=p).traces,
                                         face.truth, m_per_px=0.008) for p in (fine, filtered))
    assert a_fine.recall >= a_filtered.recall + 0.1
    assert abs(a_fine.p21_rel_error) < abs(a_filtered.p21_rel_error)
    assert a_fine.precision >= 0.9 and a_fine.f1 >= 0.9
