"""Config hash: a function of the resolved configuration, not of how the file spells it."""

from __future__ import annotations

import hashlib
import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockmass.config import FractalConfig, RockmassConfig, canonical_json, config_hash, load_config

# Written by hand from the documented defaults: the independent answer.
DEFAULT_FRACTAL_CANONICAL = (
    '{"blocks":null,"dfn":null,"fractal":{"grid":360,"invert":false,"line_rule":"supercover","method":"raster",'
    '"n_offsets":8,"range_px":null,"skeletonize":"auto","threshold":null},"imaging":null,"solve":null}'
)


def _load(tmp_path, text, name="c.toml"):
    path = tmp_path / name
    path.write_text(text)
    return load_config(path)


def test_default_section_hash_matches_hand_written_canonical_json(tmp_path):
    cfg = _load(tmp_path, "[fractal]\n")
    assert canonical_json(cfg) == DEFAULT_FRACTAL_CANONICAL
    assert config_hash(cfg) == hashlib.sha256(DEFAULT_FRACTAL_CANONICAL.encode()).hexdigest()


def test_key_order_and_explicit_defaults_do_not_change_hash(tmp_path):
    omitted = _load(tmp_path, '[fractal]\nmethod = "vector"\n', "a.toml")
    reordered = _load(tmp_path, '[fractal]\ninvert = false\nmethod = "vector"\ngrid = 360\n', "b.toml")
    spelled_out = _load(
        tmp_path,
        '[fractal]\nskeletonize = "auto"\nn_offsets = 8\nline_rule = "supercover"\n'
        'method = "vector"\ngrid = 360\ninvert = false\n',
        "c.toml",
    )
    assert config_hash(omitted) == config_hash(reordered) == config_hash(spelled_out)


def test_integer_and_float_spelling_of_a_float_give_same_hash(tmp_path):
    a = _load(tmp_path, "[fractal]\nrange_px = [2, 32]\nthreshold = 100\n", "a.toml")
    b = _load(tmp_path, "[fractal]\nrange_px = [2.0, 32.0]\nthreshold = 100.0\n", "b.toml")
    assert config_hash(a) == config_hash(b)


@pytest.mark.parametrize(
    "change",
    [
        {"grid": 361},
        {"method": "vector"},
        {"range_px": (1.0, 90.0)},
        {"n_offsets": 9},
        {"line_rule": "bresenham"},
        {"skeletonize": "never"},
        {"threshold": 0.5},
        {"invert": True},
    ],
)
def test_any_value_change_changes_hash(change):
    base = RockmassConfig(fractal=FractalConfig())
    changed = RockmassConfig(fractal=FractalConfig(**change))
    assert config_hash(changed) != config_hash(base)


def test_absent_section_differs_from_section_with_defaults():
    assert config_hash(RockmassConfig()) != config_hash(RockmassConfig(fractal=FractalConfig()))


def test_canonical_json_is_sorted_and_compact():
    assert canonical_json({"b": [1, 2.5], "a": {"d": None, "c": "σ"}}) == '{"a":{"c":"σ","d":null},"b":[1,2.5]}'


@settings(max_examples=40, deadline=None)
@given(st.dictionaries(st.text(max_size=6), st.integers() | st.text(max_size=4), min_size=1, max_size=6), st.randoms())
def test_hash_of_mapping_ignores_insertion_order(mapping, rnd):
    items = list(mapping.items())
    rnd.shuffle(items)
    assert config_hash(dict(items)) == config_hash(mapping)
    assert json.loads(canonical_json(mapping)) == mapping
