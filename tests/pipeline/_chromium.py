"""Headless Chromium for the report tests (``report.html`` of ``rockmass run`` and ``rockmass study``).

- :func:`chromium`: the browser binary, or ``None`` (tests skip with :data:`SKIP_REASON`);
- :func:`count_loaded_images`: open a page, return (images decoded, images) once it has loaded;
- :func:`screenshot`: a PNG of the page, copied to ``$ROCKMASS_TEST_ARTIFACTS`` when that is set
  (``.ci/run`` sets it to ``test-artifacts/``).

Every call uses a fresh, empty profile folder and flags that keep Chromium off the network (no
QUIC, no background or component updates, no sync, no first-run page), so a page that fetched
anything remote would show broken images instead of passing by luck.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

__all__ = ["SKIP_REASON", "chromium", "count_loaded_images", "screenshot"]

SKIP_REASON = "headless Chromium is not installed"

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars")


def chromium() -> str | None:
    """Path of chromium / chromium-browser / google-chrome on PATH, or None."""
    return next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome")
                 if shutil.which(n)), None)


def _run(args: list[str], timeout: float) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory(prefix="chromium-profile-") as profile:
        return subprocess.run([chromium(), *FLAGS, f"--user-data-dir={profile}", *args],
                              capture_output=True, text=True, timeout=timeout, check=False)


def count_loaded_images(page: Path, work: Path, timeout: float = 120) -> tuple[int, int]:
    """(images with ``complete`` and ``naturalWidth > 0``, all ``<img>``) of ``page``.

    The page is opened in an iframe of a probe page written to ``work``; once it has loaded, a
    script counts its decoded images and writes the result into the probe's DOM, which Chromium
    dumps.
    """
    probe = Path(work) / "probe.html"
    probe.write_text(
        '<!DOCTYPE html><html><body><iframe id="f" src="' + Path(page).resolve().as_uri()
        + '" width="1200" height="800"></iframe><script>document.getElementById("f").onload = '
        "function () { var im = this.contentDocument.images, ok = 0; for (var i = 0; i < "
        "im.length; i++) if (im[i].complete && im[i].naturalWidth > 0) ok++; "
        'document.body.setAttribute("data-result", ok + "/" + im.length); };</script></body>'
        "</html>", encoding="utf-8")
    dom = _run(["--allow-file-access-from-files", "--virtual-time-budget=15000", "--dump-dom",
                probe.as_uri()], timeout).stdout
    found = re.search(r'data-result="(\d+)/(\d+)"', dom)
    if found is None:
        raise AssertionError(f"the probe page did not report its images; DOM dump: {dom[:500]!r}")
    loaded, total = map(int, found.groups())
    return loaded, total


def screenshot(page: Path, target: Path, size: tuple[int, int] = (1250, 2400),
               timeout: float = 120) -> Path:
    """Save a PNG screenshot of ``page`` to ``target``; also copy it to ``$ROCKMASS_TEST_ARTIFACTS``
    (created if needed) when that is set. Returns ``target``."""
    target = Path(target)
    _run([f"--window-size={size[0]},{size[1]}", f"--screenshot={target}",
          Path(page).resolve().as_uri()], timeout)
    if os.environ.get("ROCKMASS_TEST_ARTIFACTS"):
        folder = Path(os.environ["ROCKMASS_TEST_ARTIFACTS"])
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copy(target, folder / target.name)
    return target
