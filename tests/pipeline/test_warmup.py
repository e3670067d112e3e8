"""``rockmass warmup``: fills numba's cache and nothing else, so that a later run compiles nothing."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from rockmass import kernel_cache, warmup
from rockmass.cli import main

REPO = Path(__file__).resolve().parents[2]


def _cache_files(folder: Path) -> dict[str, int]:
    """numba's cache files below ``folder``: relative path -> modification time (ns)."""
    return {str(p.relative_to(folder)): p.stat().st_mtime_ns
            for p in folder.rglob("*") if p.suffix in (".nbi", ".nbc")}


def _kernel_folders_files() -> dict[str, int]:
    """numba's cache files beside the kernel modules (where numba writes without NUMBA_CACHE_DIR)."""
    files = {}
    for folder in kernel_cache._kernel_pycache_folders():
        if folder.is_dir():
            files.update({f"{folder}/{k}": v for k, v in _cache_files(folder).items()})
    return files


def _warmup(args: list[str], cache: Path, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run([sys.executable, "-m", "rockmass", "warmup", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, check=False)


@pytest.fixture(scope="module")
def warmed(tmp_path_factory):
    """``rockmass warmup --workers 1`` with an empty cache, run in an empty folder: (process,
    cache folder, that folder, cache files beside the kernels before it ran)."""
    tmp = tmp_path_factory.mktemp("warmup")
    cache, cwd = tmp / "cache", tmp / "cwd"
    cache.mkdir()
    cwd.mkdir()
    beside_kernels = _kernel_folders_files()
    return _warmup(["--workers", "1"], cache, cwd), cache, cwd, beside_kernels


@pytest.mark.slow  # compiles the kernels with an empty cache: about 20 s on one core
def test_warmup_fills_only_the_cache_it_is_given(warmed):
    proc, cache, cwd, beside_kernels = warmed
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    for name in ("extract", "dfn", "boxcount", "blocks", "solve"):  # one line per part, timed
        assert any(line.startswith(f"{name} ") and " s " in line for line in lines), proc.stdout
    assert "zones" not in proc.stdout and "blocks3d" not in proc.stdout  # only with --all
    assert str(cache) in lines[-1]  # says where the kernels went
    written = _cache_files(cache)
    assert any(k.endswith(".nbc") for k in written) and any(k.endswith(".nbi") for k in written)
    assert {p.suffix for p in cache.rglob("*") if p.is_file()} <= {".nbi", ".nbc"}
    assert not any(cwd.iterdir())  # nothing in the current folder
    assert _kernel_folders_files() == beside_kernels  # nor beside the kernels

    # two worker processes, reading that cache: every kernel was there, none compiled again
    proc = _warmup(["--workers", "2"], cache, cwd)
    assert proc.returncode == 0, proc.stderr
    assert "2 processes" in proc.stdout.splitlines()[-1]
    after = _cache_files(cache)
    assert after == written, sorted(k for k in after.keys() | written.keys()
                                    if after.get(k) != written.get(k))
    assert not any(cwd.iterdir())


@pytest.mark.slow  # the quickstart with the kernels cached: about 10 s
def test_the_quickstart_after_warmup_compiles_nothing(warmed, tmp_path):
    proc, cache, _, _ = warmed
    assert proc.returncode == 0, proc.stderr
    _compiles_nothing(cache, ["run", str(REPO / "samples" / "quickstart.toml"), "--out", str(tmp_path / "out")])


@pytest.mark.slow  # warmup --all on the warmed cache (the zone and 3D kernels), then the sample
def test_the_3d_blocks_sample_after_warmup_all_compiles_nothing(warmed, tmp_path):
    """Before session 24 no warmup compiled the polyhedron kernels, so the first ``blocks3d`` run
    did (19 s for the sample, 9 s for four realizations after); ``--all`` does now."""
    proc, cache, cwd, _ = warmed
    assert proc.returncode == 0, proc.stderr
    every = _warmup(["--all", "--workers", "2"], cache, cwd)
    assert every.returncode == 0, every.stderr
    assert "blocks3d " in every.stdout and "zones " in every.stdout
    _compiles_nothing(cache, ["blocks3d", str(REPO / "samples" / "blocks3d_seed001.toml"),
                              "--out", str(tmp_path / "out")])


def _compiles_nothing(cache: Path, argv: list[str]) -> None:
    """``rockmass ARGV`` with the kernels of ``cache`` succeeds and compiles no kernel (a new
    signature would rewrite an index file, a new kernel add files)."""
    before = _cache_files(cache)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "ROCKMASS_QUIET": "1"}
    run = subprocess.run([sys.executable, "-m", "rockmass", *argv], env=env, capture_output=True,
                         text=True, check=False)
    assert run.returncode == 0, run.stderr
    after = _cache_files(cache)
    assert after == before, sorted(k for k in after.keys() | before.keys()
                                   if after.get(k) != before.get(k))


@pytest.mark.parametrize("args", [["--workers", "0"], ["--workers", "two"], ["--bogus"]])
def test_a_bad_option_exits_2(args, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["warmup", *args])
    assert exc.value.code == 2
    assert args[0] in capsys.readouterr().err  # argparse names the option


def test_the_deformable_part_only_with_all():
    plain = [name for group in warmup.groups(False) for name in group]
    assert sorted(plain) == ["blocks", "boxcount", "dfn", "extract", "solve"]
    every = warmup.groups(True)
    assert ["solve", "zones"] in every  # one process: zones reuse the solver's kernels
    assert sorted(n for g in every for n in g) == sorted(warmup.PARTS)


def test_it_names_the_cache_it_fills(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert str(tmp_path) in kernel_cache.cache_location()
    monkeypatch.setenv("NUMBA_CACHE_DIR", "")  # unset for numba; restored afterwards
    monkeypatch.setattr(kernel_cache, "_writable", lambda folder: True)
    assert kernel_cache.cache_location().startswith("__pycache__ beside the kernel modules")
    user = tmp_path / "user"
    monkeypatch.setattr(kernel_cache, "_user_cache_dir", lambda: user)
    monkeypatch.setattr(kernel_cache, "_writable", lambda folder: folder == user)
    assert kernel_cache.cache_location().startswith(str(user))
