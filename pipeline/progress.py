"""Progress bars on stderr for the long stages (photo extraction, DFN realizations, DEM stepping).

Bars are drawn only when stderr is a terminal and ``ROCKMASS_QUIET`` is unset, so logs, pipes and
the test suite see none of them; the computations take plain callbacks (``progress=``) and never
import tqdm themselves. Each factory is a context manager that yields the bar, or ``None`` when bars
are off (which every callee accepts as "no progress reporting"), and closes it on the way out::

    with step_bar("extract", STEPS) as bar:
        extract(image, progress=bar)
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager


def bars_enabled() -> bool:
    """True when progress bars should be drawn: stderr is a terminal and ``ROCKMASS_QUIET`` is not
    set (to anything but an empty string)."""
    return sys.stderr.isatty() and not os.environ.get("ROCKMASS_QUIET")


def _tqdm(**kwargs):
    from tqdm import tqdm

    return tqdm(file=sys.stderr, leave=False, dynamic_ncols=True, **kwargs)


class StepBar:
    """A bar over named steps, fed by ``bar(step_name)`` after each step (e.g. the steps of
    :func:`rockmass.imaging.extract`); shows the step just finished."""

    def __init__(self, desc: str, steps: Sequence[str]) -> None:
        self.bar = _tqdm(total=len(steps), desc=desc, unit="step")

    def __call__(self, step: str) -> None:
        self.bar.set_postfix_str(step, refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()


class CountBar:
    """A bar over ``total`` items (DFN realizations), fed by ``bar(done)`` with the count so far."""

    def __init__(self, desc: str, total: int, unit: str) -> None:
        self.bar = _tqdm(total=total, desc=desc, unit=unit)
        self.last = 0

    def __call__(self, done: int) -> None:
        self.bar.update(done - self.last)
        self.last = done

    def close(self) -> None:
        self.bar.close()


class SolverBar:
    """One bar per DEM stage, labelled ``solve: <stage name>``, fed by ``bar(done, total, name)``
    (the ``progress`` callback of :func:`rockmass.solver.runner.run`): a new stage name, or a count
    that goes back, starts a new bar."""

    def __init__(self) -> None:
        self.bar = None
        self.stage: str | None = None
        self.last = 0

    def __call__(self, done: int, total: int, stage: str) -> None:
        if self.bar is None or stage != self.stage or done < self.last:
            self.close()
            self.bar = _tqdm(total=total, desc=f"solve: {stage}", unit="step")
            self.stage, self.last = stage, 0
        self.bar.update(done - self.last)
        self.last = done

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


@contextmanager
def _closing(bar) -> Iterator:
    try:
        yield bar
    finally:
        if bar is not None:
            bar.close()


def step_bar(desc: str, steps: Sequence[str]):
    """Context manager: a :class:`StepBar`, or ``None`` when bars are off."""
    return _closing(StepBar(desc, steps) if bars_enabled() else None)


def count_bar(desc: str, total: int, unit: str):
    """Context manager: a :class:`CountBar`, or ``None`` when bars are off (or there is at most
    one item)."""
    return _closing(CountBar(desc, total, unit) if bars_enabled() and total > 1 else None)


def solver_bar():
    """Context manager: a :class:`SolverBar`, or ``None`` when bars are off."""
    return _closing(SolverBar() if bars_enabled() else None)
