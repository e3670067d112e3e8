"""Progress bars: drawn on a terminal only, one per long stage, labelled by what they count."""

import numpy as np
import pytest

from rockmass import progress
from rockmass.cli import main
from rockmass.imaging.extract import STEPS, extract


class _FakeBar:
    """Stands in for tqdm: records the label, the total, the count and whether it was closed."""

    made: list["_FakeBar"] = []

    def __init__(self, total, desc, unit, **_):
        self.total, self.desc, self.unit, self.n, self.closed, self.postfix = total, desc, unit, 0, False, []
        _FakeBar.made.append(self)

    def update(self, k):
        self.n += k

    def set_postfix_str(self, text, refresh=True):
        self.postfix.append(text)

    def close(self):
        self.closed = True


@pytest.fixture
def bars(monkeypatch):
    """Bars on, as on a terminal (pytest's stderr is not one); returns the bars made."""
    monkeypatch.setattr(progress, "bars_enabled", lambda: True)
    monkeypatch.setattr(progress, "_tqdm", _FakeBar)
    _FakeBar.made = []
    return _FakeBar.made


def test_no_bars_off_a_terminal(monkeypatch):
    class Pipe:
        def isatty(self):
            return False

    monkeypatch.setattr("sys.stderr", Pipe())
    monkeypatch.delenv("ROCKMASS_QUIET", raising=False)
    for bars in (progress.solver_bar(), progress.step_bar("x", ["a"]),
                 progress.count_bar("x", 5, "item")):
        with bars as bar:
            assert bar is None


def test_quiet_variable_turns_bars_off(monkeypatch):
    class Tty:
        def isatty(self):
            return True

    monkeypatch.setattr("sys.stderr", Tty())
    monkeypatch.delenv("ROCKMASS_QUIET", raising=False)
    assert progress.bars_enabled()
    monkeypatch.setenv("ROCKMASS_QUIET", "1")
    assert not progress.bars_enabled()


def test_extract_reports_every_step_in_order():
    img = np.full((120, 160), 180, dtype=np.uint8)
    img[58:62, 20:140] = 60
    seen = []
    extract(img, m_per_px=0.01, progress=seen.append)
    assert seen == list(STEPS)


def test_solver_bar_starts_a_bar_per_stage_labelled_by_its_name(bars):
    with progress.solver_bar() as bar:
        for stage, total in (("equilibrium", 1000), ("excavate tunnel", 600),
                             ("excavate tunnel", 600)):
            for done in range(200, total + 1, 200):  # the same name after a restart: a new bar
                bar(done, total, stage)
    assert [(b.desc, b.unit, b.n, b.total, b.closed) for b in bars] == [
        ("solve: equilibrium", "step", 1000, 1000, True),
        ("solve: excavate tunnel", "step", 600, 600, True),
        ("solve: excavate tunnel", "step", 600, 600, True)]


def test_dfn_bar_counts_realizations(bars, tmp_path):
    from .test_cli_dfn import CONFIG

    config = tmp_path / "site.toml"
    config.write_text(CONFIG)
    assert main(["dfn", str(config), "--out", str(tmp_path / "out")]) == 0
    assert [(b.desc, b.unit, b.n, b.total, b.closed) for b in bars] == [
        ("dfn", "realization", 3, 3, True)]


def test_extract_command_bar_goes_through_every_step(bars, tmp_path):
    import cv2

    img = np.full((120, 160), 180, dtype=np.uint8)
    img[58:62, 20:140] = 60
    photo = tmp_path / "face.png"
    cv2.imwrite(str(photo), img)
    assert main(["extract", str(photo), "--m-per-px", "0.01", "--out", str(tmp_path / "out")]) == 0
    assert [(b.desc, b.n, b.total, b.closed) for b in bars] == [("extract", len(STEPS), len(STEPS),
                                                                 True)]
    assert bars[0].postfix == list(STEPS)


def test_solve_command_bar_per_dem_stage(bars, tmp_path):
    from .test_cli_solve import _tiny

    import json

    assert main(["solve", str(_tiny(tmp_path)), "--out", str(tmp_path / "out")]) == 0
    stages = json.loads((tmp_path / "out" / "result.json").read_text())["stages"]
    assert [b.desc for b in bars] == ["solve: gravity", "solve: shake"]
    # each bar ends at the steps its stage took, out of its step budget (the static stage's
    # max_steps = 3000; the dynamic one's duration / step)
    assert [b.n for b in bars] == [s["steps"] for s in stages]
    assert bars[0].total == 3000 and all(b.closed and b.n <= b.total for b in bars)
