r"""The learned detector's back-end settings for a site's own pixel model, chosen by cross-validation
on the site's labelled photographs (docs/imaging.md §3.2).

The hysteresis levels on the joint probability (``prob_low`` / ``prob_high``) and the trace length
floor (``min_trace_length_px``) of :class:`rockmass.imaging.extract.ExtractParams` were chosen for
the shipped model on one public set of rock faces (§3.1). A model trained on a site's photographs
gives probabilities of another calibration, and the site's labels may mark shorter or fainter
traces; on the drone tiles of §8.2 these settings, not the pixel model, held recall down. So
``train_pixel_model --photos ... --choose-back-end`` chooses them on the user's photos:

1. the labelled photos, sorted by name, are dealt into K folds (photo k into fold k mod K);
2. for each fold, a pixel model is trained on the other folds' photos (the caller's recipe) and
   every photo of the fold is extracted with each setting of :data:`BACK_END_GRID` (the other
   settings as given), its traces drawn as 1-px lines and scored against the label's centre lines
   at 5 px (:func:`rockmass.imaging.metrics.raster_counts`, eqs. (8.5)-(8.6));
3. each setting's score is the mean F1 over all photos, each scored by a model that did not see
   it, with the trace length error dP21 over all of them
   (:func:`rockmass.imaging.metrics.summarise_counts`);
4. the candidate is the setting of best mean F1 among those whose |dP21| is within
   :data:`LENGTH_TOLERANCE_PCT` (the rule that chose the shipped defaults, §3.1), or among all when
   none is (ties: the earlier setting of the grid, i.e. the higher levels and the longer floor);
5. the given settings (the defaults, chosen on 99 photographs of another set) are kept unless the
   candidate beats them by more than one standard error of the photos' paired F1 differences,
   :math:`\bar d > s_d / \sqrt{n}`, :math:`d_i = F1_i^{cand} - F1_i^{given}` (a form of the
   one-standard-error rule of cross-validation: Breiman et al. 1984; Hastie, Tibshirani &
   Friedman 2009, §7.10), which keeps the grid's near-ties from being taken for gains, or when
   they are not within the length tolerance and the candidate is.

The kept setting's cross-validated F1 is the best of ``len(BACK_END_GRID)`` on the same folds, so
it is an optimistic estimate; photographs kept out of the whole choice give an unbiased one
(``benchmarks/bench_imaging_outcrop.py --site-models`` does that). The same photos are also
extracted with the shipped model at the given settings, for comparison.
"""

from __future__ import annotations

import itertools
import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np

__all__ = ["BACK_END_GRID", "LENGTH_TOLERANCE_PCT", "TOLERANCE_PX", "BackEndScore", "BackEndChoice",
           "fold_of", "choose_setting", "choose_back_end", "recommended_settings",
           "unused_settings_note"]

#: The settings tried, in order; the defaults of ExtractParams (0.8, 0.97, 70 px) are among them.
BACK_END_GRID: tuple[Mapping[str, float], ...] = tuple(
    MappingProxyType({"prob_low": low, "prob_high": high, "min_trace_length_px": floor})
    for high, low, floor in itertools.product((0.97, 0.9), (0.8, 0.65, 0.5), (70.0, 50.0, 30.0)))
#: A setting is preferred when its trace length error is within this (%).
LENGTH_TOLERANCE_PCT = 15.0
#: Scoring tolerance: a drawn (labelled) pixel is matched within this distance of a labelled
#: (drawn) one, pixels of the photograph.
TOLERANCE_PX = 5.0


@dataclass(frozen=True)
class BackEndScore:
    """Scores of one setting over the photos (see the module notes).

    Attributes
    ----------
    settings : mapping
        ``prob_low``, ``prob_high``, ``min_trace_length_px``.
    f1, precision, recall : float
        Means over the photos (5 px); the precision is NaN when no photo has a trace drawn.
    dp21_pct : float
        Drawn / labelled line length - 1 over all photos, %.
    photo_f1 : tuple of float
        The F1 of each photo, in the order of the photos.
    """

    settings: Mapping[str, float]
    f1: float
    precision: float
    recall: float
    dp21_pct: float
    photo_f1: tuple[float, ...] = field(default=(), repr=False)

    @property
    def within_length_tolerance(self) -> bool:
        """|dP21| <= :data:`LENGTH_TOLERANCE_PCT`."""
        return abs(self.dp21_pct) <= LENGTH_TOLERANCE_PCT

    def record(self) -> dict:
        """A plain dict for JSON (the model's ``info``)."""
        return {"settings": dict(self.settings), "F1": _rounded(self.f1, 4),
                "P": _rounded(self.precision, 4), "R": _rounded(self.recall, 4),
                "dP21_pct": _rounded(self.dp21_pct, 2)}


@dataclass(frozen=True)
class BackEndChoice:
    """The outcome of :func:`choose_back_end`.

    Attributes
    ----------
    chosen : BackEndScore
        The setting kept, with its (optimistic) cross-validated scores.
    site_defaults : BackEndScore
        The site models at the given settings (ExtractParams' defaults unless changed).
    shipped : BackEndScore
        The shipped model at the given settings, on the same photos.
    scores : tuple of BackEndScore
        Every setting of the grid, in grid order.
    folds, photos : int
        K, and the number of labelled photos.
    """

    chosen: BackEndScore
    site_defaults: BackEndScore
    shipped: BackEndScore
    scores: tuple[BackEndScore, ...] = field(repr=False)
    folds: int = 0
    photos: int = 0

    @property
    def settings(self) -> dict:
        """The chosen settings."""
        return dict(self.chosen.settings)

    def record(self) -> dict:
        """What the model file keeps in ``info["back_end"]``: the settings, how they were chosen
        and the scores behind the choice."""
        return {"settings": self.settings, "folds": self.folds, "photos": self.photos,
                "rule": f"best mean F1 at {TOLERANCE_PX:g} px among the settings with |dP21| <= "
                        f"{LENGTH_TOLERANCE_PCT:g} % (else among all), kept when it beats the "
                        "given settings by more than one standard error "
                        "(rockmass.imaging.site_back_end)",
                "cross_validated": self.chosen.record(),
                "site_model_at_given_settings": self.site_defaults.record(),
                "shipped_model_at_given_settings": self.shipped.record()}

    def config_snippet(self, model_path) -> str:
        """The ``[imaging.params]`` table of a rockmass config that uses the model with the
        chosen settings (TOML)."""
        lines = ["[imaging.params]", f"pixel_model = {_toml_string(str(model_path))}"]
        lines += [f"{name} = {value!r}" for name, value in self.settings.items()]
        return "\n".join(lines)


def _rounded(value: float, digits: int) -> float | None:
    """``value`` rounded, None when it is not defined (a precision with nothing drawn): JSON has
    no NaN."""
    return round(value, digits) if math.isfinite(value) else None


def _toml_string(text: str) -> str:
    """A TOML basic string."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def fold_of(k: int, folds: int) -> int:
    """The fold of the k-th photo (sorted by name)."""
    return k % folds


def choose_setting(scores: Sequence[BackEndScore], given: BackEndScore) -> BackEndScore:
    """Rules 4 and 5 of the module notes: the candidate among ``scores``, or ``given``.

    Examples
    --------
    >>> given = BackEndScore({"x": 0}, 0.50, 0.6, 0.4, -30.0, (0.4, 0.5, 0.6))
    >>> short = BackEndScore({"x": 1}, 0.70, 0.7, 0.7, -20.0, (0.6, 0.7, 0.8))
    >>> level = BackEndScore({"x": 2}, 0.55, 0.6, 0.5, +10.0, (0.45, 0.55, 0.65))
    >>> choose_setting([short, level], given).settings["x"]  # +0.05 on each photo: no spread
    2
    >>> noisy = BackEndScore({"x": 3}, 0.51, 0.6, 0.4, -30.0, (0.2, 0.73, 0.6))
    >>> choose_setting([noisy], given).settings["x"]  # +0.01, one standard error 0.12
    0
    """
    if not scores:
        raise ValueError("no settings to choose from")
    pool = [s for s in scores if s.within_length_tolerance] or list(scores)
    best = max(s.f1 for s in pool)
    candidate = next(s for s in pool if s.f1 == best)
    if candidate.within_length_tolerance and not given.within_length_tolerance:
        return candidate
    gain = np.subtract(candidate.photo_f1, given.photo_f1)
    error = gain.std(ddof=1) / np.sqrt(gain.size) if gain.size > 1 else np.inf
    return candidate if gain.mean() > error else given


def _score(settings, counts) -> BackEndScore:
    from .metrics import image_f1, summarise_counts

    summary = summarise_counts(counts)
    return BackEndScore(MappingProxyType(dict(settings)), summary["F1"], summary["P"], summary["R"],
                        summary["dP21_pct"], tuple(float(f) for f in image_f1(counts)))


def _photo_counts(image, lines, params) -> tuple[int, int, int, int]:
    """raster_counts of one photo's traces (``params``) against its label's centre lines."""
    from .extract import extract
    from .metrics import raster_counts, render_traces

    with warnings.catch_warnings():  # no scale: the traces are in pixels, as wanted
        warnings.simplefilter("ignore", UserWarning)
        result = extract(image, params=params)
    drawn = render_traces(result.traces, lines.shape, 1.0)
    return raster_counts(drawn, lines, tolerance_px=TOLERANCE_PX)


def _read_pair(photo, label):
    """(RGB or grey image, label centre lines at the photo's size) of one labelled photo."""
    from .enhance import read_photo
    from .labels import label_centre_lines

    image = read_photo(photo)
    lines = label_centre_lines(label)
    if lines.shape != image.shape[:2]:
        raise ValueError(f"{label}: label is {lines.shape[1]} x {lines.shape[0]} px, its photo "
                         f"{Path(photo).name} {image.shape[1]} x {image.shape[0]} px")
    return image, lines


def choose_back_end(pairs: Sequence[tuple], train: Callable[[list, int], Path], *, folds: int = 5,
                    base=None, grid: Sequence[Mapping[str, float]] = BACK_END_GRID,
                    progress: Callable[[str], None] | None = None) -> BackEndChoice:
    """Choose the learned detector's back-end settings for a site model by K-fold
    cross-validation (module notes).

    Parameters
    ----------
    pairs : sequence of (photo path, label path)
        The labelled photographs, in the order folds are dealt (sorted by name).
    train : callable
        ``train(pairs_to_train_on, fold)`` trains a pixel model on those pairs and returns the
        path of its file.
    folds : int, default 5
        K, at least 2 and at most the number of photos.
    base : ExtractParams, optional
        The other settings (default ``ExtractParams()``); its detector is set to "learned".
    grid : sequence of mappings
        The settings tried (default :data:`BACK_END_GRID`).
    progress : callable, optional
        Called with a line of text after each fold.

    Returns
    -------
    BackEndChoice
    """
    from .extract import ExtractParams

    if not (isinstance(folds, int) and 2 <= folds <= len(pairs)):
        raise ValueError(f"folds must be an integer from 2 to the number of labelled photos "
                         f"({len(pairs)}), got {folds!r}")
    if not grid:
        raise ValueError("grid: no settings to try")
    base = replace(base or ExtractParams(), detector="learned")
    shipped_params = replace(base, pixel_model=None)
    given = {name: base.resolved(name) for name in grid[0]}
    # the given settings are usually a setting of the grid (the defaults are): not extracted twice
    given_index = next((i for i, settings in enumerate(grid) if dict(settings) == given), None)
    site_counts = [[] for _ in grid]
    default_counts, shipped_counts = [], []
    for fold in range(folds):
        held = [k for k in range(len(pairs)) if fold_of(k, folds) == fold]
        model = str(train([p for k, p in enumerate(pairs) if fold_of(k, folds) != fold], fold))
        site = replace(base, pixel_model=model)
        for k in held:
            image, lines = _read_pair(*pairs[k])
            for counts, settings in zip(site_counts, grid):
                counts.append(_photo_counts(image, lines, replace(site, **settings)))
            default_counts.append(site_counts[given_index][-1] if given_index is not None
                                  else _photo_counts(image, lines, site))
            shipped_counts.append(_photo_counts(image, lines, shipped_params))
        if progress is not None:
            progress(f"fold {fold + 1}/{folds}: {len(held)} photos scored with {len(grid)} settings")
    scores = tuple(_score(settings, counts) for settings, counts in zip(grid, site_counts))
    at_given = _score(given, default_counts)
    return BackEndChoice(chosen=choose_setting(scores, at_given), site_defaults=at_given,
                         shipped=_score(given, shipped_counts), scores=scores, folds=folds,
                         photos=len(pairs))


def recommended_settings(model_info: Mapping) -> dict | None:
    """The back-end settings a model file's ``info`` records as chosen for it
    (``train_pixel_model --choose-back-end``), or None."""
    entry = model_info.get("back_end") or {}
    settings = entry.get("settings")
    return dict(settings) if settings else None


def unused_settings_note(model_info: Mapping, params) -> str | None:
    """A warning when the settings chosen for a pixel model (:func:`recommended_settings`) differ
    from those of ``params`` (ExtractParams of the learned detector), else None.

    Examples
    --------
    >>> from rockmass.imaging.extract import ExtractParams
    >>> info = {"back_end": {"settings": {"prob_low": 0.5, "min_trace_length_px": 70.0}}}
    >>> unused_settings_note(info, ExtractParams(detector="learned", prob_low=0.5)) is None
    True
    >>> print(unused_settings_note(info, ExtractParams(detector="learned")))  # doctest: +ELLIPSIS
    the pixel model's back end was chosen for it ... (prob_low = 0.5, ...); this run uses prob_low = 0.8: ...
    """
    settings = recommended_settings(model_info)
    if not settings:
        return None
    differ = [name for name, value in settings.items()
              if not math.isclose(float(params.resolved(name)), float(value))]
    if not differ:
        return None
    chosen = ", ".join(f"{name} = {value:g}" for name, value in settings.items())
    used = ", ".join(f"{name} = {params.resolved(name):g}" for name in differ)
    return (f"the pixel model's back end was chosen for it by cross-validation on its photographs "
            f"({chosen}); this run uses {used}: set them in [imaging.params] to extract as the "
            f"model was validated (train_pixel_model printed them; docs/imaging.md §3.2)")
