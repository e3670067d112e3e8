"""Where numba keeps rockmass's compiled kernels, and a fallback when nowhere can be written.

Every kernel is ``@njit(cache=True)``: the first call compiles it and writes the machine code to
numba's on-disk cache, and every later process reads it from there (README, "Compiled kernels").
numba picks the cache folder, in this order:

1. ``NUMBA_CACHE_DIR``, when set (a folder of its own per interpreter and source file);
2. ``__pycache__`` beside each kernel module, when that folder can be written (a source checkout,
   a virtualenv the user owns);
3. the user's cache folder, ``$XDG_CACHE_HOME/numba`` or ``~/.cache/numba`` (a read-only install:
   system site-packages, a shared environment, a container image).

When none of these can be written, numba refuses to import a cached kernel ("cannot cache function
...: no locator available"). :func:`ensure_writable_cache` then points ``NUMBA_CACHE_DIR`` at a
folder in the temporary directory, so the command still runs. The command line calls it before any
subcommand; it imports nothing heavy (no numba) and leaves a working setup alone; its fallback
folder is private to the user.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["KERNEL_PACKAGES", "cache_location", "ensure_writable_cache", "fallback_cache_dir"]

#: The subpackages that hold numba kernels (their ``_*kernels.py`` modules).
KERNEL_PACKAGES = ("solver", "dfn", "fractal", "imaging", "blockgen")


def _writable(folder: Path) -> bool:
    """Whether ``folder`` exists or can be made, and a file can be created in it (numba's own test)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


def _user_cache_dir() -> Path:
    """numba's user-wide cache folder on this system, as its bundled ``appdirs`` names it
    (``user_cache_dir('numba')``), worked out here so that the check imports no numba:
    ``%LOCALAPPDATA%\\numba\\Cache`` on Windows, ``~/Library/Caches/numba`` on macOS,
    ``$XDG_CACHE_HOME/numba`` (default ``~/.cache/numba``) elsewhere."""
    import sys

    if sys.platform.startswith("win"):
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
        return Path(base) / "numba" / "Cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "numba"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "numba"


def fallback_cache_dir() -> Path:
    """The folder :func:`ensure_writable_cache` uses when numba has none: per user, in the
    temporary directory — private to the user (mode 0700, owned by them: numba's cache index is
    a pickle, so a folder another user could write into must not be read). When that name is
    taken by a folder that is not private to the user, a fresh private folder (``mkdtemp``)."""
    import getpass

    user = os.getuid() if hasattr(os, "getuid") else getpass.getuser()
    folder = Path(tempfile.gettempdir()) / f"rockmass-numba-cache-{user}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        st = folder.lstat()
        private = (not folder.is_symlink() and (not hasattr(os, "getuid") or st.st_uid == os.getuid())
                   and not st.st_mode & 0o022)
    except OSError:
        private = False
    return folder if private else Path(tempfile.mkdtemp(prefix="rockmass-numba-"))


def _kernel_pycache_folders() -> list[Path]:
    """The ``__pycache__`` folders beside the kernel modules (numba's choice 2)."""
    from importlib.util import find_spec

    package = Path(__file__).resolve().parent
    folders = []
    for name in KERNEL_PACKAGES:
        try:
            spec = find_spec(f"{__package__}.{name}")
        except (ImportError, ValueError):
            spec = None
        locations = list(spec.submodule_search_locations or []) if spec else [package / name]
        folders += [Path(loc) / "__pycache__" for loc in locations]
    return folders


def cache_location() -> str:
    """Where numba writes the kernels now, in words (``rockmass warmup`` prints it): the folder
    ``NUMBA_CACHE_DIR`` names, the kernels' ``__pycache__`` folders, or numba's user cache folder.
    Call it after :func:`ensure_writable_cache`."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return f"{os.environ['NUMBA_CACHE_DIR']} (NUMBA_CACHE_DIR)"
    folders = _kernel_pycache_folders()
    if all(_writable(f) for f in folders):
        return f"__pycache__ beside the kernel modules in {folders[0].parent.parent}"
    return f"{_user_cache_dir()} (numba's user cache folder)"


def ensure_writable_cache() -> str | None:
    """Make sure numba can write its cache; returns the ``NUMBA_CACHE_DIR`` set, else None.

    Nothing changes when ``NUMBA_CACHE_DIR`` is set, or when the kernels' own ``__pycache__``
    folders or numba's user cache folder can be written. Otherwise ``NUMBA_CACHE_DIR`` is set to
    :func:`fallback_cache_dir` (before numba is imported; if it already is, its config too).
    """
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    if all(_writable(f) for f in _kernel_pycache_folders()):
        return None
    if _writable(_user_cache_dir()):
        return None
    folder = fallback_cache_dir()
    if not _writable(folder):
        return None
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    import sys

    if "numba" in sys.modules:  # already imported: numba read the variable then
        sys.modules["numba"].config.CACHE_DIR = str(folder)
    return str(folder)
