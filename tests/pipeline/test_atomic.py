"""Atomic outputs (docs/design.md §3.7): complete new file or untouched old file, never a partial one."""

from __future__ import annotations

import dataclasses
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rockmass import atomic
from rockmass.atomic import (
    atomic_path,
    atomic_write_bytes,
    atomic_write_json,
    atomic_write_text,
    to_jsonable,
)


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# ------------------------------------------------------------------------------------- round trips


def test_bytes_round_trip_and_parent_folder_created(tmp_path):
    target = tmp_path / "new" / "deeper" / "a.bin"
    data = bytes(range(256)) * 3
    assert atomic_write_bytes(target, data) == target
    assert target.read_bytes() == data
    assert _names(target.parent) == ["a.bin"]


def test_text_round_trip_keeps_newlines_and_encoding(tmp_path):
    target = tmp_path / "t.txt"
    text = "σ_n = 2 MPa\r\nline 2\n"
    atomic_write_text(target, text)
    assert target.read_bytes() == text.encode("utf-8")
    atomic_write_text(target, text, encoding="utf-16")
    assert target.read_bytes().decode("utf-16") == text


def test_json_round_trip_keeps_key_order_as_given(tmp_path):
    obj = {"zeta": 1, "alpha": [1.5, None, True, "x"], "mid": {"b": 2, "a": 1}}
    target = atomic_write_json(tmp_path / "r.json", obj)
    text = target.read_text(encoding="utf-8")
    assert json.loads(text) == obj
    assert text.index('"zeta"') < text.index('"alpha"') < text.index('"mid"')
    assert text.index('"b"') < text.index('"a"')
    assert text.endswith("}\n")


def test_replacing_existing_file_gives_new_content(tmp_path):
    target = tmp_path / "r.json"
    atomic_write_json(target, {"v": 1})
    atomic_write_json(target, {"v": 2})
    assert json.loads(target.read_text()) == {"v": 2}
    assert _names(tmp_path) == ["r.json"]


@pytest.mark.skipif(os.name != "posix", reason="umask permissions are POSIX")
def test_written_file_has_same_permissions_as_plain_open(tmp_path):
    plain = tmp_path / "plain"
    plain.write_bytes(b"x")
    target = atomic_write_bytes(tmp_path / "atomic", b"x")
    assert target.stat().st_mode == plain.stat().st_mode


@pytest.mark.skipif(os.name != "posix", reason="permission bits are POSIX")
def test_replaced_file_keeps_its_permissions_as_plain_open_would(tmp_path):
    target = tmp_path / "private.json"
    target.write_text("{}")
    os.chmod(target, 0o600)
    atomic_write_json(target, {"v": 2})
    with atomic_path(target) as tmp:
        tmp.write_text('{"v": 3}')
    assert json.loads(target.read_text()) == {"v": 3}
    assert target.stat().st_mode & 0o777 == 0o600


# ---------------------------------------------------------------------------------- failure paths


def _fail(*args, **kwargs):
    raise OSError("simulated failure")


def test_old_file_survives_failed_rename_and_no_temp_file_is_left(tmp_path, monkeypatch):
    target = tmp_path / "summary.json"
    target.write_text("old complete content")
    monkeypatch.setattr(atomic.os, "replace", _fail)
    with pytest.raises(OSError, match="simulated"):
        atomic_write_json(target, {"new": 1})
    assert target.read_text() == "old complete content"
    assert _names(tmp_path) == ["summary.json"]


def test_old_file_survives_interrupt_mid_write_and_no_temp_file_is_left(tmp_path, monkeypatch):
    target = tmp_path / "data.bin"
    target.write_bytes(b"old")

    def interrupt(fd):
        raise KeyboardInterrupt  # a user pressing Ctrl-C after the bytes went out, before fsync

    monkeypatch.setattr(atomic.os, "fsync", interrupt)
    with pytest.raises(KeyboardInterrupt):
        atomic_write_bytes(target, b"new content that never becomes visible")
    assert target.read_bytes() == b"old"
    assert _names(tmp_path) == ["data.bin"]


def test_json_encoding_error_leaves_old_file_and_folder_untouched(tmp_path):
    target = tmp_path / "r.json"
    target.write_text('{"old": true}')
    with pytest.raises(ValueError):
        atomic_write_json(target, {"x": float("nan")})
    with pytest.raises(TypeError):
        atomic_write_json(target, {"x": object()})
    assert target.read_text() == '{"old": true}'
    assert _names(tmp_path) == ["r.json"]


# -------------------------------------------------------------------------------- strict JSON


def test_nan_is_refused_with_its_key_path(tmp_path):
    obj = {"result": {"D": 1.3, "local_slopes": [1.1, 1.2, 1.25, float("nan")]}}
    with pytest.raises(ValueError, match=r"result\.local_slopes\[3\] is NaN; JSON has no NaN"):
        atomic_write_json(tmp_path / "r.json", obj)
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize(
    ("value", "word"), [(math.inf, "is Infinity"), (-math.inf, "is -Infinity"), (np.float32("nan"), "is NaN")]
)
def test_infinities_and_numpy_nan_are_refused_with_key_path(value, word):
    with pytest.raises(ValueError, match=rf"runs\[0\]\.energy {word};"):
        to_jsonable({"runs": [{"energy": value}]})


def test_nan_inside_numpy_array_is_refused_with_its_index():
    a = np.zeros((2, 3))
    a[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"^counts\[1\]\[2\] is NaN"):
        to_jsonable({"counts": a})


def test_nan_as_null_writes_null(tmp_path):
    obj = {"slope": float("nan"), "arr": np.array([1.0, np.inf, -np.inf]), "nested": [{"x": float("nan")}]}
    target = atomic_write_json(tmp_path / "r.json", obj, nan_as_null=True)
    assert json.loads(target.read_text()) == {"slope": None, "arr": [1.0, None, None], "nested": [{"x": None}]}
    assert "NaN" not in target.read_text() and "Infinity" not in target.read_text()


def test_numpy_scalars_and_arrays_serialise_as_plain_numbers(tmp_path):
    obj = {
        "f32": np.float32(0.5),
        "f64": np.float64(2.25),
        "i64": np.int64(7),
        "u8": np.uint8(255),
        "flag": np.bool_(True),
        "grid": np.arange(6, dtype=np.int32).reshape(2, 3),
        "mask": np.array([True, False]),
        "xy": np.array([[0.5, 1.5]]),
        np.int64(3): "numpy integer key",
    }
    loaded = json.loads(atomic_write_json(tmp_path / "n.json", obj).read_text())
    assert loaded == {
        "f32": 0.5,
        "f64": 2.25,
        "i64": 7,
        "u8": 255,
        "flag": True,
        "grid": [[0, 1, 2], [3, 4, 5]],
        "mask": [True, False],
        "xy": [[0.5, 1.5]],
        "3": "numpy integer key",
    }
    assert type(loaded["flag"]) is bool and type(loaded["i64"]) is int


def test_dataclasses_and_paths_serialise():
    @dataclasses.dataclass(frozen=True)
    class Fit:
        slope: float
        source: Path
        sizes_px: tuple[int, ...]

    assert to_jsonable({"fit": Fit(1.5, Path("maps") / "a.csv", (1, 2))}) == {
        "fit": {"slope": 1.5, "source": str(Path("maps") / "a.csv"), "sizes_px": [1, 2]}
    }


def test_unserialisable_value_is_refused_with_key_path_and_type():
    with pytest.raises(TypeError, match=r"blob\[1\] is of type bytes"):
        to_jsonable({"blob": [1, b"\x00"]})


def test_circular_reference_is_refused():
    loop: dict = {"a": []}
    loop["a"].append(loop)
    with pytest.raises(ValueError, match="circular"):
        to_jsonable(loop)


def test_input_not_modified():
    obj = {"a": [1.0, float("nan")], "b": (1, 2)}
    to_jsonable(obj, nan_as_null=True)
    assert obj["b"] == (1, 2) and math.isnan(obj["a"][1])


_json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False) | st.text(),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=5), children, max_size=4),
    max_leaves=20,
)


@settings(max_examples=60, deadline=None)
@given(_json_values)
def test_finite_json_values_survive_conversion_and_dumping_unchanged(value):
    assert json.loads(json.dumps(to_jsonable(value), allow_nan=False)) == value


# -------------------------------------------------------------------------------- atomic_path


def test_atomic_path_keeps_suffix_and_renames_on_success(tmp_path):
    target = tmp_path / "plots" / "overlay.png"
    with atomic_path(target) as tmp:
        assert tmp.parent == target.parent
        assert tmp.suffix == ".png" and tmp.name.endswith("overlay.png")
        assert not tmp.exists()
        tmp.write_bytes(b"\x89PNG")
        assert not target.exists()
    assert target.read_bytes() == b"\x89PNG"
    assert _names(target.parent) == ["overlay.png"]


def test_atomic_path_deletes_temp_and_keeps_old_file_on_exception(tmp_path):
    target = tmp_path / "mesh.vtu"
    target.write_text("old mesh")
    with pytest.raises(RuntimeError, match="writer crashed"):
        with atomic_path(target) as tmp:
            tmp.write_text("half a mesh")
            raise RuntimeError("writer crashed")
    assert target.read_text() == "old mesh"
    assert _names(tmp_path) == ["mesh.vtu"]


def test_atomic_path_without_write_raises_and_keeps_old_file(tmp_path):
    target = tmp_path / "rose.png"
    target.write_text("old")
    with pytest.raises(FileNotFoundError, match="nothing was written"):
        with atomic_path(target):
            pass
    assert target.read_text() == "old"
    assert _names(tmp_path) == ["rose.png"]
