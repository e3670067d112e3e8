"""numba's kernel cache: start-up stays free of numba, and a read-only install still gets a cache."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from rockmass import kernel_cache


def test_help_imports_no_numba():
    code = ("import sys\nfrom rockmass.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n"
            "    pass\nprint('numba' in sys.modules, 'llvmlite' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip().splitlines()[-1] == "False False"


def test_a_set_cache_dir_is_left_alone(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert kernel_cache.ensure_writable_cache() is None
    assert kernel_cache.os.environ["NUMBA_CACHE_DIR"] == str(tmp_path)


def test_a_writable_install_changes_nothing(monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", "")  # unset for numba; restored afterwards
    monkeypatch.setattr(kernel_cache, "_writable", lambda folder: True)
    assert kernel_cache.ensure_writable_cache() is None
    assert kernel_cache.os.environ["NUMBA_CACHE_DIR"] == ""


def test_a_read_only_install_uses_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", "")  # unset for numba; restored afterwards
    user = tmp_path / "user"
    monkeypatch.setattr(kernel_cache, "_user_cache_dir", lambda: user)
    monkeypatch.setattr(kernel_cache, "_writable", lambda folder: folder == user)
    assert kernel_cache.ensure_writable_cache() is None  # numba falls back to it by itself
    assert kernel_cache.os.environ["NUMBA_CACHE_DIR"] == ""


def test_nothing_writable_falls_back_to_the_temporary_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", "")  # unset for numba; restored afterwards
    fallback = tmp_path / "fallback"
    monkeypatch.setattr(kernel_cache, "fallback_cache_dir", lambda: fallback)
    monkeypatch.setattr(kernel_cache, "_user_cache_dir", lambda: tmp_path / "user")
    monkeypatch.setattr(kernel_cache, "_writable", lambda folder: folder == fallback)
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)  # restored afterwards
    assert kernel_cache.ensure_writable_cache() == str(fallback)
    assert kernel_cache.os.environ["NUMBA_CACHE_DIR"] == str(fallback)
    assert numba.config.CACHE_DIR == str(fallback)


def test_the_user_cache_folder_is_numbas_own_without_importing_numba():
    code = ("import sys; from rockmass import kernel_cache as k; p = k._user_cache_dir(); "
            "print('numba' in sys.modules); from numba.misc.appdirs import AppDirs; "
            "print(str(p) == AppDirs(appname='numba', appauthor=False).user_cache_dir)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="POSIX permissions")
def test_a_fallback_folder_others_can_write_is_not_used(tmp_path, monkeypatch):
    """numba's cache index is a pickle: a planted, world-writable folder of the predictable name
    is refused for a fresh private one."""
    monkeypatch.setattr(kernel_cache.tempfile, "gettempdir", lambda: str(tmp_path))
    planted = tmp_path / f"rockmass-numba-cache-{os.getuid()}"
    planted.mkdir()
    planted.chmod(0o777)
    chosen = kernel_cache.fallback_cache_dir()
    assert chosen != planted and chosen.parent == tmp_path
    assert chosen.stat().st_mode & 0o077 == 0
    planted.chmod(0o700)
    assert kernel_cache.fallback_cache_dir() == planted
