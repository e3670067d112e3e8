"""Clean shutdown (issue 18, item 7): a study stopped by SIGTERM (or killed) ends its pool workers.

Oracle: the process table. The study runs in a subprocess with two pool workers; once they exist,
the study is signalled, and a few seconds later none of its child processes may be alive (a
process left as a zombie has ended).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .test_study import BASE, STUDY

# the study of test_study with many quick cases: the pool is still busy when the signal comes
MANY = STUDY.replace("realizations = 2", "realizations = 40")
assert MANY != STUDY


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid`` (from /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def _alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie has ended: it only waits to be reaped)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def _start_study(tmp_path: Path) -> tuple[subprocess.Popen, list[int]]:
    """The study, started with two workers; returns it once its workers run, with their ids."""
    config = tmp_path / "study.toml"
    config.write_text(BASE + MANY)
    study = subprocess.Popen([sys.executable, "-m", "rockmass", "study", str(config), "--out",
                              str(tmp_path / "out"), "--workers", "2"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and study.poll() is None:
        children = _children(study.pid)
        if len(children) >= 3:  # two workers and the resource tracker
            time.sleep(1.0)
            return study, _children(study.pid)
        time.sleep(0.2)
    study.kill()
    pytest.fail("the study did not start two workers within 60 s")


def _survivors(children: list[int], wait_s: float) -> list[int]:
    deadline = time.monotonic() + wait_s
    while time.monotonic() < deadline:
        if not any(_alive(p) for p in children):
            return []
        time.sleep(0.2)
    return [p for p in children if _alive(p)]


@pytest.mark.slow  # a study with two spawned workers: about 10 s
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGKILL], ids=["sigterm", "sigkill"])
def test_a_signalled_study_leaves_no_worker_behind(tmp_path, how):
    study, children = _start_study(tmp_path)
    os.kill(study.pid, how)
    code = study.wait(timeout=30)
    survivors = _survivors(children, wait_s=5.0)
    for pid in survivors:  # do not leave them to the next test
        os.kill(pid, signal.SIGKILL)
    assert survivors == [], f"still running after the study ended ({code}): {survivors}"
    if how == signal.SIGTERM:
        assert code == 130  # handled as Ctrl-C: finished cases kept, exit 130
        assert (tmp_path / "out" / "results.csv").is_file()
