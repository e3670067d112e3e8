"""All-or-nothing output sets (issue 18, item 2) and confinement to --out (item 5).

Oracles: the bytes of the previous complete set, captured before a failing or killed command (they
must be found again, whole), the bytes of a user's own files in --out, and the folder listings
(no debris). Faults are injected at every rename (``os.replace``) a command makes, one at a time,
as a failed write (an exception) and as a kill (``os._exit`` in a forked child: no clean-up runs).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from rockmass.cli import main

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
TRACES = SAMPLES / "face_traces.geojson"


def _files(folder: Path) -> dict[str, bytes]:
    """relative path -> bytes of every file below ``folder``."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def _listing(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


class _FailAt:
    """``os.replace`` that fails with ``exc`` at its ``k``-th call (1-based) and works otherwise."""

    def __init__(self, k: int, exc: BaseException, real=os.replace):
        self.k, self.exc, self.real, self.calls = k, exc, real, 0

    def __call__(self, *args, **kwargs):
        self.calls += 1
        if self.calls == self.k:
            raise self.exc
        return self.real(*args, **kwargs)


# ------------------------------------------------------------------------------ a real command


@pytest.fixture
def boxcount_set(tmp_path):
    """``--out`` holding a complete boxcount set (grid 360) and a user's notes.txt and folder."""
    out = tmp_path / "work" / "out"
    assert main(["boxcount", str(TRACES), "--out", str(out)]) == 0
    (out / "notes.txt").write_text("my field notes\n")
    (out / "photos").mkdir()
    (out / "photos" / "face.jpg").write_bytes(b"\xff\xd8 not really a jpeg")
    return out, _files(out)


def test_user_files_in_out_survive_and_only_the_commands_files_are_replaced(boxcount_set):
    out, before = boxcount_set
    (out / ".tmp-0123456789abcdef-boxcount.json").write_text("{")  # debris of a killed writer
    assert main(["boxcount", str(TRACES), "--out", str(out), "--grid", "180"]) == 0
    after = _files(out)
    assert after["notes.txt"] == before["notes.txt"]
    assert after["photos/face.jpg"] == before["photos/face.jpg"]
    assert json.loads(after["boxcount.json"])["grid"] == 180
    assert _listing(out) == ["boxcount.json", "boxcount.png", "manifest.json", "notes.txt", "photos"]
    assert _listing(out.parent) == ["out"]  # no staging folder, no old set left beside it


@pytest.mark.slow  # about 8 s: the command once per rename
@pytest.mark.parametrize("in_place", [False, True], ids=["swap", "in-place"])
def test_a_failed_write_at_each_rename_leaves_the_previous_set_whole(boxcount_set, monkeypatch,
                                                                     capsys, in_place):
    out, before = boxcount_set
    top_level = _listing(out)
    if in_place:  # --out is the working directory: the set is committed entry by entry
        monkeypatch.chdir(out)
    k = 0
    while True:
        k += 1
        failing = _FailAt(k, OSError(28, "No space left on device"))
        monkeypatch.setattr(os, "replace", failing)
        code = main(["boxcount", str(TRACES), "--out", str(out), "--grid", "180"])
        monkeypatch.setattr(os, "replace", failing.real)
        err = capsys.readouterr().err
        if failing.calls < k:  # the command made fewer than k renames: it went through
            break
        assert code == 1, k
        assert _files(out) == before, f"rename {k} failed and the previous set changed"
        assert _listing(out) == top_level, k  # no staging folder left inside either
        assert _listing(out.parent) == ["out"], k
        assert "No space left on device" in err and ".tmp-" not in err and ".partial" not in err
        assert str(out) in err
    assert code == 0 and k > 4  # one rename per file, and the set's own swap
    assert json.loads((out / "boxcount.json").read_text())["grid"] == 180
    assert (out / "notes.txt").read_bytes() == before["notes.txt"]


def test_a_failed_write_into_a_new_out_leaves_nothing(tmp_path, monkeypatch):
    out = tmp_path / "new" / "out"
    monkeypatch.setattr(os, "replace", _FailAt(2, OSError(5, "Input/output error")))
    assert main(["boxcount", str(TRACES), "--out", str(out)]) == 1
    assert not out.exists() and _listing(out.parent) == []


def test_a_write_error_names_the_destination_not_the_temporary_file(boxcount_set, monkeypatch,
                                                                    capsys):
    from rockmass.fractal import plot

    out, before = boxcount_set

    def full_disk(result, path, **kwargs):  # the plotting library fails on the name it was given
        Path(path).write_bytes(b"\x89PNG half")
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(plot, "plot_box_count", full_disk)
    assert main(["boxcount", str(TRACES), "--out", str(out), "--grid", "180"]) == 1
    err = capsys.readouterr().err
    assert f"{out / 'boxcount.png'}: cannot write the outputs: No space left on device" in err
    assert ".tmp-" not in err and ".partial" not in err
    assert _files(out) == before


# -------------------------------------------------------------------- the swap, killed anywhere


def output_set(out, owns=()):
    """:func:`rockmass.outputs.output_set` (imported late: the command-level tests above run on
    code without it)."""
    from rockmass.outputs import output_set as api

    return api(out, owns=owns)


def recover_output_set(out):
    """:func:`rockmass.outputs.recover_output_set`."""
    from rockmass.outputs import recover_output_set as api

    return api(out)


def _write_set(folder: Path, tag: str, frames: int) -> None:
    """A set of outputs: two files, a subfolder, and ``frames`` numbered frames."""
    (folder / "result.json").write_text(json.dumps({"set": tag}))
    (folder / "history.csv").write_text(f"t,{tag}\n" * 50)
    (folder / "realization_0000").mkdir()
    (folder / "realization_0000" / "fractures.csv").write_text(tag)
    for i in range(frames):
        (folder / f"blocks_{i:04d}.vtu").write_text(f"{tag}{i}")


OWNS = (r"blocks_\d{4,}\.vtu", r"realization_\d{4,}")


def _old_set(out: Path) -> dict[str, bytes]:
    """Write set A (three frames) and a user's notes.txt into ``out``; return its files."""
    with output_set(out, owns=OWNS) as staging:
        _write_set(staging, "A", frames=3)
    (out / "notes.txt").write_text("mine")
    return _files(out)


@pytest.fixture
def old_set(tmp_path):
    out = tmp_path / "out"
    return out, _old_set(out)


def _expected_new(tmp_path) -> dict[str, bytes]:
    """The files of --out after set B (two frames) replaced set A: B and the user's notes.txt."""
    folder = tmp_path / "expected"
    folder.mkdir()
    _write_set(folder, "B", frames=2)
    (folder / "notes.txt").write_text("mine")
    return _files(folder)


def _killed_at(k: int, out: Path, in_place: bool) -> bool:
    """Write set B into ``out`` in a forked child that dies (``os._exit``: no clean-up, as under
    SIGKILL) at its ``k``-th ``os.replace``; True if it died, False if it finished first.
    ``in_place``: the child works inside ``out`` (``--out .``), so the set is committed in place."""
    pid = os.fork()
    if pid == 0:
        if in_place:
            os.chdir(out)
        real, calls = os.replace, [0]

        def die(*args, **kwargs):
            calls[0] += 1
            if calls[0] == k:
                os._exit(9)
            return real(*args, **kwargs)

        os.replace = die
        try:
            with output_set(out, owns=OWNS) as staging:
                _write_set(staging, "B", frames=2)
        finally:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    return os.waitstatus_to_exitcode(status) == 9


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
@pytest.mark.parametrize("in_place", [False, True], ids=["swap", "in-place"])
def test_a_kill_at_each_rename_leaves_the_old_or_the_new_set_whole(tmp_path, in_place):
    new = _expected_new(tmp_path)
    without_notes = {k: v for k, v in new.items() if k != "notes.txt"}
    outcomes = []
    for k in range(1, 20):
        out = tmp_path / f"k{k}" / "out"
        before = _old_set(out)
        killed = _killed_at(k, out, in_place)
        if k == 1:  # killed at its first rename: the staged set is where the mode puts it
            staged = out / ".rockmass-partial" if in_place else out.parent / ".out.rockmass-partial"
            assert (staged / "result.json").read_text() == '{"set": "B"}'
        if not in_place:  # right after the kill: one whole set (the notes maybe still in the old
            now = {n: v for n, v in _files(out).items() if n != ".rockmass-carry.json"} \
                if out.exists() else None  # folder), or briefly nothing; never a mix
            assert now in (None, before, new, without_notes), f"kill at rename {k}: a mixed set"
        recover_output_set(out)  # what the next command into --out does first
        after = _files(out)
        assert after in (before, new), f"kill at rename {k}: not recovered"
        assert _listing(out.parent) == ["out"], k
        outcomes.append("old" if after == before else "new")
        if not killed:
            assert after == new
            break
    assert outcomes[0] == "old" and outcomes[-1] == "new" and len(outcomes) > 4


def test_stale_frames_of_the_old_set_go_and_the_users_files_stay(old_set, tmp_path):
    out, _ = old_set
    with output_set(out, owns=OWNS) as staging:
        _write_set(staging, "B", frames=2)
    assert _files(out) == _expected_new(tmp_path)


def test_out_as_the_working_directory_is_committed_in_place(boxcount_set, monkeypatch):
    out, before = boxcount_set
    monkeypatch.chdir(out)
    assert main(["boxcount", str(TRACES), "--out", ".", "--grid", "180"]) == 0
    assert Path.cwd() == out and json.loads((out / "boxcount.json").read_text())["grid"] == 180
    assert (out / "notes.txt").read_bytes() == before["notes.txt"]
    assert _listing(out) == ["boxcount.json", "boxcount.png", "manifest.json", "notes.txt", "photos"]
    assert _listing(out.parent) == ["out"]


def test_an_exception_while_writing_leaves_the_old_set_and_no_staging_folder(old_set):
    out, before = old_set
    with pytest.raises(ZeroDivisionError):
        with output_set(out, owns=OWNS) as staging:
            _write_set(staging, "B", frames=2)
            1 / 0
    assert _files(out) == before and _listing(out.parent) == ["out"]


def test_debris_of_a_killed_command_is_cleaned_at_the_next(old_set):
    out, before = old_set
    (out.parent / ".out.rockmass-partial").mkdir()
    (out.parent / ".out.rockmass-partial" / "result.json").write_text("{")
    (out.parent / "out.old").mkdir()  # a user's backup of an earlier set: never ours
    (out.parent / "out.old" / "result.json").write_text("kept")
    (out / ".tmp-00112233445566ff-history.csv").write_text("t,")
    (out / ".tmp-notes").write_text("a user's file that only looks like debris")
    recover_output_set(out)
    assert _listing(out.parent) == ["out", "out.old"]
    assert (out.parent / "out.old" / "result.json").read_text() == "kept"
    assert _files(out) == {**before, ".tmp-notes": b"a user's file that only looks like debris"}


# ------------------------------------------------------------------------------- confinement


def test_a_realization_link_inside_out_is_not_written_through(tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "precious.txt").write_text("keep")
    out = tmp_path / "out"
    with output_set(out, owns=OWNS) as staging:
        _write_set(staging, "A", frames=1)
    import shutil

    shutil.rmtree(out / "realization_0000")
    (out / "realization_0000").symlink_to(elsewhere, target_is_directory=True)
    with output_set(out, owns=OWNS) as staging:
        _write_set(staging, "B", frames=1)
    assert _listing(elsewhere) == ["precious.txt"]
    assert not (out / "realization_0000").is_symlink()
    assert (out / "realization_0000" / "fractures.csv").read_text() == "B"


def _run_config(tmp_path: Path) -> Path:
    config = tmp_path / "run.toml"
    config.write_text(f'[run]\ntraces = {json.dumps(str(TRACES))}\nstages = ["boxcount"]\n')
    return config


def test_run_recomputes_a_reused_stage_whose_output_was_truncated(tmp_path, capsys):
    config, out = _run_config(tmp_path), tmp_path / "out"
    assert main(["run", str(config), "--out", str(out)]) == 0
    good = (out / "boxcount" / "boxcount.json").read_bytes()
    assert main(["run", str(config), "--out", str(out)]) == 0
    assert "reused boxcount" in capsys.readouterr().err
    (out / "boxcount" / "boxcount.json").write_bytes(good[: len(good) // 2])  # truncated
    assert main(["run", str(config), "--out", str(out)]) == 0
    assert "ran boxcount" in capsys.readouterr().err
    assert (out / "boxcount" / "boxcount.json").read_bytes() == good


def test_run_does_not_write_through_a_partial_link_and_cleans_debris(tmp_path, capsys):
    config, out = _run_config(tmp_path), tmp_path / "out"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out.mkdir()
    (out / "boxcount.partial").symlink_to(elsewhere, target_is_directory=True)
    (out / "boxcount.old").mkdir()  # left by a run killed after its swap
    (out / ".tmp-0123456789abcdef-run.json").write_text("{")
    (out / "notes.txt").write_text("mine")
    assert main(["run", str(config), "--out", str(out)]) == 0
    assert _listing(elsewhere) == []
    assert _listing(out) == ["boxcount", "manifest.json", "notes.txt", "report.html", "run.json"]


def test_study_refuses_a_cases_link_inside_out(tmp_path, capsys):
    from .test_study import BASE, STUDY

    config = tmp_path / "study.toml"
    config.write_text(BASE + STUDY)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "out"
    out.mkdir()
    (out / "cases").symlink_to(elsewhere, target_is_directory=True)
    assert main(["study", str(config), "--out", str(out), "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert "cases" in err and "symbolic link" in err
    assert _listing(elsewhere) == [] and _listing(out) == ["cases"]


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))


def test_dfn_does_not_write_through_a_realization_link_and_drops_stale_realizations(tmp_path):
    from .test_cli_dfn import CONFIG

    config = tmp_path / "site.toml"
    config.write_text(CONFIG)
    out = tmp_path / "out"
    assert main(["dfn", str(config), "--out", str(out)]) == 0  # three realizations
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    import shutil

    shutil.rmtree(out / "realization_0000")
    (out / "realization_0000").symlink_to(elsewhere, target_is_directory=True)
    assert main(["dfn", str(config), "--out", str(out), "--realizations", "1"]) == 0
    assert _listing(elsewhere) == []
    assert _listing(out) == ["manifest.json", "realization_0000"]
    assert not (out / "realization_0000").is_symlink()


def test_a_study_write_error_names_the_file_not_the_temporary_one(tmp_path):
    from rockmass.errors import RunError
    from rockmass.outputs import output_folder

    out = tmp_path / "study"
    with pytest.raises(RunError) as info:
        with output_folder(out) as folder:  # the folder a study writes its cases into, one by one
            raise OSError(28, "No space left on device",
                          str(folder / "cases" / ".tmp-0123456789abcdef-case.json"))
    assert str(info.value) == (f"{out / 'cases' / 'case.json'}: cannot write the outputs: "
                               "No space left on device")


@pytest.mark.slow  # about 4 s: the study twice
def test_study_removes_the_temporary_files_of_a_killed_study(tmp_path):
    from .test_study import BASE, STUDY

    config = tmp_path / "study.toml"
    config.write_text(BASE.split("[solve]")[0] + STUDY)  # blocks and D_box only: fast
    out = tmp_path / "out"
    assert main(["study", str(config), "--out", str(out), "--workers", "1"]) == 0
    case = next((out / "cases").iterdir())
    debris = [out / ".tmp-0123456789abcdef-results.csv", case / ".tmp-0123456789abcdef-case.json"]
    for path in debris:
        path.write_text("half")
    (out / "notes.txt").write_text("mine")
    assert main(["study", str(config), "--out", str(out), "--workers", "1"]) == 0
    assert not any(p.exists() for p in debris) and (out / "notes.txt").read_text() == "mine"
