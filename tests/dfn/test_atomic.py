"""The shared atomic-write primitives (docs/design.md §3.7), beyond what the trace writers already exercise.

The byte, text, JSON and path writers of ``rockmass.atomic`` are built on these; their round trips
and failure paths are tested in ``tests/pipeline/test_atomic.py``.
"""

from __future__ import annotations

import os
import stat

import pytest

from rockmass.dfn.atomic import atomic_open, atomic_path

posix_only = pytest.mark.skipif(os.name != "posix", reason="permission bits are POSIX")


@posix_only
@pytest.mark.parametrize("writer", ["atomic_open", "atomic_path"])
def test_replacing_a_file_keeps_its_permission_bits(tmp_path, writer):
    target = tmp_path / "private.txt"
    target.write_text("old")
    os.chmod(target, 0o600)
    if writer == "atomic_open":
        with atomic_open(target) as handle:
            handle.write("new")
    else:
        with atomic_path(target) as tmp:
            tmp.write_text("new")
    assert target.read_text() == "new"
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o600


@posix_only
def test_binary_file_has_the_permissions_of_a_normally_created_file(tmp_path):
    (tmp_path / "plain.bin").write_bytes(b"x")
    with atomic_open(tmp_path / "atomic.bin", "wb") as handle:
        handle.write(b"x")
    assert os.stat(tmp_path / "atomic.bin").st_mode == os.stat(tmp_path / "plain.bin").st_mode


def test_text_mode_writes_utf8_and_translates_no_newline_when_asked(tmp_path):
    with atomic_open(tmp_path / "t.csv", newline="") as handle:
        handle.write("σ,τ\r\n")
    assert (tmp_path / "t.csv").read_bytes() == "σ,τ\r\n".encode()


@pytest.mark.parametrize(
    ("mode", "kwargs", "message"),
    [("a", {}, r"mode must be one of \['w', 'wb'\], got 'a'"),
     ("wb", {"encoding": "utf-8"}, "encoding and newline apply to text mode 'w' only"),
     ("wb", {"newline": ""}, "encoding and newline apply to text mode 'w' only")],
)
def test_bad_mode_is_refused_before_any_file_is_created(tmp_path, mode, kwargs, message):
    with pytest.raises(ValueError, match=message):
        with atomic_open(tmp_path / "x", mode, **kwargs):
            pass
    assert list(tmp_path.iterdir()) == []


def test_missing_folder_raises_oserror_and_creates_nothing(tmp_path):
    with pytest.raises(FileNotFoundError):
        with atomic_open(tmp_path / "absent" / "x.txt"):
            pass
    assert list(tmp_path.iterdir()) == []

