"""Strict TOML configs (docs/design.md §4): every problem reported at once, naming file, field and value."""

from __future__ import annotations

import textwrap

import pytest
from pydantic import Field, ValidationError

from rockmass.config import FractalConfig, RockmassConfig, StrictModel, load_config
from rockmass.errors import ConfigError, InputError

ALLOWED_FRACTAL_KEYS = ["grid", "method", "range_px", "n_offsets", "line_rule", "skeletonize", "threshold", "invert"]


@pytest.fixture
def write(tmp_path):
    def _write(text: str, name: str = "site.toml"):
        path = tmp_path / name
        path.write_text(textwrap.dedent(text), encoding="utf-8")
        return path

    return _write


def _problems(path, model=RockmassConfig) -> dict[str, str]:
    with pytest.raises(ConfigError) as info:
        load_config(path, model)
    assert info.value.path == str(path)
    return dict(info.value.problems)


# ------------------------------------------------------------------------------------ valid files


def test_valid_file_loads_values_and_fills_defaults(write):
    cfg = load_config(
        write(
            """
            [fractal]
            grid = 512
            method = "vector"
            range_px = [2, 64.5]
            threshold = 128
            invert = true
            """
        )
    )
    assert isinstance(cfg, RockmassConfig)
    f = cfg.fractal
    assert (f.grid, f.method, f.range_px, f.threshold, f.invert) == (512, "vector", (2.0, 64.5), 128.0, True)
    assert (f.n_offsets, f.line_rule, f.skeletonize) == (8, "supercover", "auto")
    assert type(f.threshold) is float and type(f.range_px[0]) is float  # a float field stores ints as floats


def test_empty_file_gives_every_section_absent(write):
    assert load_config(write("")).fractal is None


def test_empty_section_gives_documented_defaults(write):
    assert load_config(write("[fractal]\n")).fractal == FractalConfig(
        grid=360, method="raster", range_px=None, n_offsets=8, line_rule="supercover",
        skeletonize="auto", threshold=None, invert=False,
    )


def test_loaded_config_is_frozen(write):
    cfg = load_config(write("[fractal]\n"))
    with pytest.raises(ValidationError):
        cfg.fractal.grid = 100


def test_byte_order_mark_is_tolerated(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf[fractal]\ngrid = 64\n")
    assert load_config(path).fractal.grid == 64


# ------------------------------------------------------------------------------------ bad files


def test_unknown_key_names_file_field_and_allowed_keys(write):
    path = write("[fractal]\ngridd = 360\n", name="face_A.toml")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    text = str(info.value)
    assert "face_A.toml" in text and "fractal.gridd" in text
    assert "unknown key (allowed: " + ", ".join(ALLOWED_FRACTAL_KEYS) + ")" in text
    assert 'did you mean "grid"' in text


def test_unknown_section_lists_known_sections(write):
    assert _problems(write("[fractl]\ngrid = 3\n")) == {
        "fractl": 'unknown key (allowed: imaging, fractal, dfn, blocks, blocks3d, solve, run); did you mean "fractal"?'
    }


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("grid = 4", "must be >= 8, got 4 (allowed: 8 <= grid <= 16384)"),
        ("grid = 20000", "must be <= 16384, got 20000 (allowed: 8 <= grid <= 16384)"),
    ],
)
def test_out_of_range_grid_names_field_bound_and_value(write, line, message):
    path = write(f"[fractal]\n{line}\n")
    assert _problems(path) == {"fractal.grid": message}
    with pytest.raises(ConfigError, match=f"site.toml: fractal.grid: {message[:16]}"):
        load_config(path)


def test_out_of_range_offsets_reported_as_documented(write):
    assert _problems(write("[fractal]\nn_offsets = 0\n"))["fractal.n_offsets"].startswith("must be >= 1, got 0")


@pytest.mark.parametrize(
    ("line", "field", "message"),
    [
        ('grid = "360"', "fractal.grid", 'must be an integer, got "360" (a string)'),
        ("grid = 3.5", "fractal.grid", "must be an integer, got 3.5 (a float)"),
        ("grid = 360.0", "fractal.grid", "must be an integer, got 360.0 (a float)"),
        ("grid = true", "fractal.grid", "must be an integer, got true (a boolean)"),
        ("invert = 1", "fractal.invert", "must be true or false, got 1 (an integer)"),
        ('threshold = "0.5"', "fractal.threshold", 'must be a number, got "0.5" (a string)'),
        ("threshold = nan", "fractal.threshold", "must be a finite number, got nan"),
        ("threshold = -inf", "fractal.threshold", "must be a finite number, got -inf"),
        ('method = "rastr"', "fractal.method", 'must be one of "raster", "vector"; got "rastr" (a string)'),
        ('range_px = ["1", 4]', "fractal.range_px[0]", 'must be a number, got "1" (a string)'),
        ("range_px = 4", "fractal.range_px", "must be an array, got 4 (an integer)"),
    ],
)
def test_wrong_type_or_value_is_rejected_with_field_and_value(write, line, field, message):
    assert _problems(write(f"[fractal]\n{line}\n")) == {field: message}


def test_section_that_is_not_a_table_is_rejected(write):
    assert _problems(write("fractal = 5\n")) == {
        "fractal": "must be a table ([section] or {key = value}), got 5 (an integer)"
    }


def test_several_problems_are_reported_together(write):
    problems = _problems(
        write(
            """
            [fractal]
            grid = 2
            gridd = 360
            method = "rastr"
            n_offsets = 3.5
            """
        )
    )
    assert set(problems) == {"fractal.grid", "fractal.gridd", "fractal.method", "fractal.n_offsets"}


def test_toml_syntax_error_reports_line_and_column(write):
    path = write('[fractal]\nmethod = "raster"\ngrid = = 360\n')
    problems = _problems(path)
    assert list(problems) == ["<file>"]
    assert "at line 3, column" in problems["<file>"]
    assert "grid = = 360" in problems["<file>"]


def test_range_px_beyond_grid_names_range_px(write):
    problems = _problems(write("[fractal]\ngrid = 64\nrange_px = [1, 100]\n"))
    assert problems == {"fractal.range_px": "max box size must be <= grid (64), got [1.0, 100.0]"}


def test_range_px_within_grid_is_accepted_at_the_bound(write):
    assert load_config(write("[fractal]\ngrid = 64\nrange_px = [1, 64]\n")).fractal.range_px == (1.0, 64.0)


@pytest.mark.parametrize(
    ("value", "field", "message"),
    [
        ("[8, 4]", "fractal.range_px", "must be [min, max] with min < max, got [8.0, 4.0]"),
        ("[4, 4]", "fractal.range_px", "must be [min, max] with min < max, got [4.0, 4.0]"),
        ("[0.5, 4]", "fractal.range_px[0]", "must be >= 1, got 0.5"),
        ("[1, 2, 3]", "fractal.range_px", "must be an array of exactly 2 items, got 3: [1, 2, 3]"),
        ("[1]", "fractal.range_px", "must be an array of exactly 2 items, got 1: [1]"),
    ],
)
def test_bad_range_px_is_rejected(write, value, field, message):
    assert _problems(write(f"[fractal]\nrange_px = {value}\n")) == {field: message}


def test_missing_file_raises_config_error_naming_it(tmp_path):
    path = tmp_path / "absent.toml"
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert isinstance(info.value, InputError)
    assert info.value.problems == [("<file>", "cannot read: No such file or directory")]
    assert "absent.toml" in str(info.value)


def test_folder_instead_of_file_raises_config_error(tmp_path):
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(tmp_path)


def test_non_utf8_file_raises_config_error(tmp_path):
    path = tmp_path / "latin1.toml"
    path.write_bytes("# contrainte σ\n".encode("utf-16"))
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_config(path)


# ---------------------------------------------------------------- nested sections and list indices


class _SetConfig(StrictModel):
    kappa: float = Field(ge=0)
    dip_deg: float = Field(45.0, ge=0, le=90)


class _DfnConfig(StrictModel):
    sets: list[_SetConfig]


class _Doc(StrictModel):
    dfn: _DfnConfig | None = None


def test_problems_in_arrays_of_tables_name_the_index(write):
    path = write(
        """
        [[dfn.sets]]
        kappa = 10
        [[dfn.sets]]
        kappa = -3
        kapa = 2
        """
    )
    assert _problems(path, _Doc) == {
        "dfn.sets[1].kappa": "must be >= 0, got -3",
        "dfn.sets[1].kapa": 'unknown key (allowed: kappa, dip_deg); did you mean "kappa"?',
    }


def test_missing_required_key_is_reported(write):
    assert _problems(write("[[dfn.sets]]\ndip_deg = 10\n"), _Doc) == {"dfn.sets[0].kappa": "required key is missing"}
