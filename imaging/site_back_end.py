r"""The learned detector's back-end settings for a pixel model, chosen by cross-validation on a
site's labelled photographs (docs/imaging.md §3.2).

The hysteresis levels on the joint probability (``prob_low`` / ``prob_high``) and the trace length
floor (``min_trace_length_px``) of :class:`rockmass.imaging.extract.ExtractParams` were chosen for
the shipped model on one public set of rock faces (§3.1). A model trained on a site's photographs
gives probabilities of another calibration, and the site's labels may mark shorter or fainter
traces. So ``train_pixel_model --photos ... --choose-back-end`` chooses them on the user's photos:

1. the labelled photos, sorted by name, are cut into K folds of consecutive photos (photo k of n
   into fold ⌊kK/n⌋), so that overlapping shots taken one after another stay in one fold;
2. for each fold, a pixel model is trained on the other folds' photos (the caller's recipe) and
   every photo of the fold is extracted with each setting of :data:`BACK_END_GRID` (the other
   settings as given), its traces drawn as 1-px lines and scored against the label's centre lines
   at :data:`TOLERANCE_PX` pixels of the photograph (:func:`rockmass.imaging.metrics.raster_counts`,
   eqs. (8.5)-(8.6)); a photo whose label marks nothing is not scored;
3. each setting's score is the mean F1 over the scored photos, each scored by a model that did
   not see it, with the trace length error dP21 over all of them
   (:func:`rockmass.imaging.metrics.summarise_counts`);
4. the candidate is the setting of best mean F1 among those whose |dP21| is within
   :data:`LENGTH_TOLERANCE_PCT` (the rule that chose the shipped defaults, §3.1), or among all when
   none is (ties: the earlier setting of the grid, i.e. the higher levels and the longer floor);
5. the given settings (the defaults, chosen on 99 photographs of another set) are kept unless the
   candidate beats them by more than one standard error of the photos' paired F1 differences,
   :math:`\bar d > s_d / \sqrt{n}`, :math:`d_i = F1_i^{cand} - F1_i^{given}`: in the spirit of
   the one-standard-error rule of cross-validation (Breiman et al. 1984; Hastie, Tibshirani &
   Friedman 2009, §7.10), it keeps the grid's near-ties from being taken for gains.

The kept setting's cross-validated F1 is the best of ``len(BACK_END_GRID)`` on the same folds, so
it is an optimistic estimate. What the choice does on photos it did not see is estimated too
(:func:`held_out_score`, since session 21): each fold's photos are scored at the setting chosen by
rules 4-5 from the other folds' photos alone, the outer loop of a nested cross-validation (Varma &
Simon 2006). For a fixed model (``rockmass score --choose-back-end``) nothing else saw the fold;
for a trained one, the fold's photos still trained the models of the other folds, so a little of
them reaches the choice. Photographs kept out of the whole choice give the unbiased figure
(``benchmarks/bench_imaging_outcrop.py --site-models`` does that). The same photos are also
extracted with the shipped model at the given settings, for comparison. The probability map of a
photo is computed once per model for all the settings
(:func:`rockmass.imaging.reuse.shared_work`): they change nothing before it.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from . import label_scores

__all__ = ["BACK_END_GRID", "LENGTH_TOLERANCE_PCT", "TOLERANCE_PX", "BackEndScore", "BackEndChoice",
           "fold_of", "check_folds", "choose_setting", "held_out_score", "choose_back_end", "report_text",
           "chosen_settings", "recommended_settings", "unused_settings_note"]

#: The settings tried, in order; the defaults of ExtractParams (0.8, 0.97, 70 px) are among them.
BACK_END_GRID: tuple[Mapping[str, float], ...] = tuple(
    MappingProxyType({"prob_low": low, "prob_high": high, "min_trace_length_px": floor})
    for high, low, floor in itertools.product((0.97, 0.9), (0.8, 0.65, 0.5), (70.0, 50.0, 30.0)))
#: A setting is preferred when its trace length error is within this (%).
LENGTH_TOLERANCE_PCT = 15.0
#: Scoring tolerance: a drawn (labelled) pixel is matched within this distance of a labelled
#: (drawn) one, pixels of the photograph (the scores of ``rockmass score``).
TOLERANCE_PX = label_scores.TOLERANCE_PX


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
        The setting kept, with its cross-validated scores (optimistic when it is not the given
        one: the best of the grid on the same folds).
    at_given : BackEndScore
        The given settings, each photo scored by the model it was scored with (a model trained
        without its fold, or the one fixed model); ``"at_given_settings"`` in :meth:`record`
        (``"fold_models_at_given_settings"`` in model files made before session 22).
    shipped : BackEndScore
        The shipped model at the given settings, on the same photos.
    scores : tuple of BackEndScore
        Every setting of the grid, in grid order.
    folds : int
        K.
    skipped : tuple of str
        Photos not scored: their label marks nothing.
    base : mapping
        The other settings the choice was made with, where they differ from ExtractParams'
        defaults (``max_megapixels``, ``min_trace_contrast``, ...).
    held_out : BackEndScore or None
        What choosing does on photos the choice did not see (:func:`held_out_score`): each
        fold's photos scored at the setting chosen on the other folds' photos by the same rule;
        its ``settings`` are empty (they differ by fold: ``fold_settings``).
    fold_settings : tuple of mappings
        The setting chosen without each fold, in fold order.
    """

    chosen: BackEndScore
    at_given: BackEndScore
    shipped: BackEndScore
    scores: tuple[BackEndScore, ...] = field(repr=False)
    folds: int
    skipped: tuple[str, ...] = ()
    base: Mapping[str, Any] = field(default_factory=dict)
    held_out: BackEndScore | None = None
    fold_settings: tuple[Mapping[str, float], ...] = ()

    @property
    def settings(self) -> dict:
        """The chosen settings."""
        return dict(self.chosen.settings)

    @property
    def photos(self) -> int:
        """Photos scored (those whose label marks something)."""
        return len(self.at_given.photo_f1)

    @property
    def kept_given(self) -> bool:
        """The given settings were kept (no setting beat them by more than a standard error)."""
        return self.chosen is self.at_given

    def record(self) -> dict:
        """What the model file keeps in ``info["back_end"]``: the settings chosen, the other
        settings they were chosen with, how, and the scores behind the choice."""
        return {"settings": self.settings, "with": dict(self.base), "folds": self.folds,
                "photos": self.photos, "skipped_photos": list(self.skipped),
                "rule": f"best mean F1 at {TOLERANCE_PX:g} px among the settings with |dP21| <= "
                        f"{LENGTH_TOLERANCE_PCT:g} % (else among all), taken over the given "
                        "settings when its paired F1 gain exceeds one standard error "
                        "(rockmass.imaging.site_back_end)",
                "kept_given": self.kept_given,
                "cross_validated": self.chosen.record(),
                "chosen_without_the_photos_scored": None if self.held_out is None else {
                    **self.held_out.record(), "settings": [dict(f) for f in self.fold_settings]},
                "at_given_settings": self.at_given.record(),
                "shipped_model_at_given_settings": self.shipped.record()}

    def config_snippet(self, model_path) -> str:
        """The ``[imaging.params]`` table of a rockmass config that extracts with the model as it
        was chosen: its absolute path (none for the shipped model: ``model_path`` None; a shipped
        model's name, "mlp" or "cnn", as it is), the other settings of the choice and the chosen
        ones (TOML)."""
        from .learned import SHIPPED_MODELS

        model = ({} if model_path is None else {"pixel_model": str(model_path)}
                 if str(model_path) in SHIPPED_MODELS
                 else {"pixel_model": str(Path(model_path).resolve())})
        values = {**model, **self.base, **self.settings}
        return "\n".join(["[imaging.params]",
                          *(f"{name} = {_toml_value(value)}" for name, value in values.items())])


def _rounded(value: float, digits: int) -> float | None:
    """``value`` rounded, None when it is not defined (a precision with nothing drawn): JSON has
    no NaN."""
    return round(value, digits) if math.isfinite(value) else None


def _toml_value(value) -> str:
    r"""A setting's value as TOML: a bool, a basic string, a number (inf and nan as TOML spells
    them) or an array of them.

    Examples
    --------
    >>> [_toml_value(v) for v in (True, 'a "b"', -math.inf, 0.5, (2, 4))]
    ['true', '"a \\"b\\""', '-inf', '0.5', '[2, 4]']
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return repr(value)


def fold_of(k: int, n: int, folds: int) -> int:
    """The fold of the k-th of n photos (sorted by name): consecutive photos, ⌊kK/n⌋.

    Examples
    --------
    >>> [fold_of(k, 10, 4) for k in range(10)]
    [0, 0, 0, 1, 1, 2, 2, 2, 3, 3]
    """
    return k * folds // n


def check_folds(folds, n_photos: int, name: str = "folds") -> None:
    """Refuse (ValueError, naming ``name``) folds that are not an integer from 2 to the number
    of labelled photos: the check of :func:`choose_back_end`, which the commands make before any
    work.

    Examples
    --------
    >>> check_folds(3, 3)
    >>> check_folds(4, 3, "--choose-back-end: FOLDS")
    Traceback (most recent call last):
    ...
    ValueError: --choose-back-end: FOLDS must be an integer from 2 to the number of labelled photos (3), got 4
    """
    if isinstance(folds, bool) or not (isinstance(folds, int) and 2 <= folds <= n_photos):
        raise ValueError(f"{name} must be an integer from 2 to the number of labelled photos "
                         f"({n_photos}), got {folds!r}")


def choose_setting(scores: Sequence[BackEndScore], given: BackEndScore) -> BackEndScore:
    """Rules 4 and 5 of the module notes: the candidate among ``scores`` (the best mean F1 among
    the settings whose |dP21| <= :data:`LENGTH_TOLERANCE_PCT`, or among all), kept only when its
    paired F1 gain over ``given`` photo by photo, d_i, has a mean above its standard error,
    d̄ > s_d / √n; else ``given``.

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
    gain = np.subtract(candidate.photo_f1, given.photo_f1)
    error = gain.std(ddof=1) / np.sqrt(gain.size) if gain.size > 1 else np.inf
    return candidate if gain.mean() > error else given


def held_out_score(grid_counts, given_counts, photo_folds, grid, given):
    """What choosing the setting does on photographs the choice did not see: for each fold f,
    the setting :func:`choose_setting` picks from the other folds' photos, scored on fold f's
    photos; then those photos' counts, every photo at its own fold's choice, summarised as one
    :class:`BackEndScore` (the outer loop of a nested cross-validation; the grid's best on the
    same photos, :attr:`BackEndChoice.chosen`, is optimistic, this is not).

    Parameters
    ----------
    grid_counts : sequence of sequences
        Per setting of ``grid``, the raster_counts of each scored photo (photo order).
    given_counts : sequence
        The raster_counts of each scored photo at the given settings.
    photo_folds : sequence of int
        The fold of each scored photo.
    grid : sequence of mappings
    given : mapping
        The given settings.

    Returns
    -------
    (BackEndScore, tuple of mappings)
        The score (empty ``settings``) and the setting chosen without each fold, in fold order
        (folds without a scored photo left out).

    Examples
    --------
    Two settings, four photos in two folds; "b" is better on every photo, so each fold's choice
    made on the other fold is "b":

    >>> a, b = (5, 10, 5, 10), (9, 10, 9, 10)
    >>> score, chosen = held_out_score([[a] * 4, [b] * 4], [a] * 4, [0, 0, 1, 1],
    ...                                [{"x": 1}, {"x": 2}], {"x": 1})
    >>> round(score.f1, 3), [dict(c) for c in chosen]
    (0.9, [{'x': 2}, {'x': 2}])
    """
    folds = np.asarray(photo_folds)
    out = [None] * folds.size
    chosen = []
    for fold in np.unique(folds):
        inside = np.flatnonzero(folds != fold)
        if inside.size:
            scores = [_score(settings, [c[i] for i in inside])
                      for settings, c in zip(grid, grid_counts)]
            at_given = _score(given, [given_counts[i] for i in inside])
            pick = choose_setting(scores, at_given)
        else:  # no other fold has a scored photo: nothing to choose on, the given settings stay
            scores, at_given = [], BackEndScore(MappingProxyType(dict(given)), math.nan, math.nan,
                                                math.nan, math.nan)
            pick = at_given
        chosen.append(MappingProxyType(dict(pick.settings)))
        source = (given_counts if pick is at_given
                  else grid_counts[next(k for k, sc in enumerate(scores) if sc is pick)])
        for i in np.flatnonzero(folds == fold):
            out[i] = source[i]
    return _score({}, out), tuple(chosen)


def _score(settings, counts) -> BackEndScore:
    """The :class:`BackEndScore` of one setting from the photos' raster_counts (in photo order)."""
    from .metrics import image_f1, summarise_counts

    summary = summarise_counts(counts)
    return BackEndScore(MappingProxyType(dict(settings)), summary["F1"], summary["P"], summary["R"],
                        summary["dP21_pct"], tuple(float(f) for f in image_f1(counts)))


def _photo_counts(image, lines, params, joint_width_px=None) -> tuple[int, int, int, int]:
    """raster_counts of one photo's traces (``params``) against its label's centre lines."""
    from .extract import extract
    from .label_scores import score_traces

    result = extract(image, m_per_px=1.0, joint_width_px=joint_width_px,  # "metres" = pixels
                     params=params)
    return score_traces(result.traces, lines, tolerance_px=TOLERANCE_PX)[0]


def _read_pair(photo, label):
    """(RGB or grey image, label centre lines at the photo's size) of one labelled photo."""
    from .enhance import read_photo
    from .labels import photo_centre_lines

    image = read_photo(photo)
    return image, photo_centre_lines(label, photo, image.shape)


def choose_back_end(pairs: Sequence[tuple], train: Callable[[list, int], Path], *, folds: int = 5,
                    base=None, grid: Sequence[Mapping[str, float]] = BACK_END_GRID,
                    progress: Callable[[str], None] | None = None,
                    joint_width_px: float | None = None) -> BackEndChoice:
    """Choose the learned detector's back-end settings for a pixel model by K-fold
    cross-validation (module notes).

    Parameters
    ----------
    pairs : sequence of (photo path, label path)
        The labelled photographs, in the order folds are cut (sorted by name).
    train : callable
        ``train(pairs_to_train_on, fold)`` trains a pixel model on those pairs and returns the
        path of its file (a fixed model's path chooses the back end for that model).
    folds : int, default 5
        K, at least 2 and at most the number of photos.
    base : ExtractParams, optional
        The other settings (default ``ExtractParams()``); its detector is set to "learned".
    grid : sequence of mappings
        The settings tried (default :data:`BACK_END_GRID`), each of the same names.
    progress : callable, optional
        Called with a line of text after each fold.
    joint_width_px : float, optional
        The expected joint width, pixels of the photographs (:func:`rockmass.imaging.extract`'s
        default when None).

    Returns
    -------
    BackEndChoice

    Raises
    ------
    ValueError
        Bad ``folds`` or ``grid``; a label of another size than its photo; no label marks
        anything.
    """
    from . import learned
    from .extract import ExtractParams
    from .reuse import shared_work

    n = len(pairs)
    check_folds(folds, n)
    if not grid or any(set(settings) != set(grid[0]) for settings in grid):
        raise ValueError("grid: give one or more settings, each of the same names")
    base = replace(base or ExtractParams(), detector="learned")
    shipped_params = replace(base, pixel_model=None)
    shipped_model = Path(learned.MODEL_FILE).resolve()
    given = {name: base.resolved(name) for name in grid[0]}
    # the given settings are usually a setting of the grid (the defaults are): not extracted twice
    given_index = next((i for i, settings in enumerate(grid) if dict(settings) == given), None)
    counts = {"grid": [[] for _ in grid], "given": [], "shipped": []}  # per photo, in photo order
    skipped, photo_folds = [], []
    for fold in range(folds):
        held = [k for k in range(n) if fold_of(k, n, folds) == fold]
        model = str(train([pair for k, pair in enumerate(pairs) if k not in held], fold))
        is_shipped = Path(model).resolve() == shipped_model
        fold_params = replace(base, pixel_model=model)
        for k in held:
            image, lines = _read_pair(*pairs[k])
            if not lines.any():
                skipped.append(str(pairs[k][0]))
                continue
            with shared_work():  # one map and its chains per model: the settings come after them
                for photo_counts, settings in zip(counts["grid"], grid):
                    photo_counts.append(_photo_counts(image, lines, replace(fold_params, **settings),
                                                      joint_width_px))
                counts["given"].append(counts["grid"][given_index][-1] if given_index is not None
                                       else _photo_counts(image, lines, fold_params, joint_width_px))
                counts["shipped"].append(counts["given"][-1] if is_shipped
                                         else _photo_counts(image, lines, shipped_params,
                                                            joint_width_px))
            photo_folds.append(fold)
        if progress is not None:
            progress(f"fold {fold + 1}/{folds}: {len(held)} photos scored with {len(grid)} settings")
    if not counts["given"]:
        raise ValueError("no label marks any trace: nothing to choose the settings on")
    scores = tuple(_score(settings, c) for settings, c in zip(grid, counts["grid"]))
    at_given = _score(given, counts["given"])
    held_out, fold_settings = held_out_score(counts["grid"], counts["given"], photo_folds, grid,
                                             given)
    defaults = ExtractParams(detector="learned")
    differ = {f.name: getattr(base, f.name) for f in fields(base)
              if f.name not in ("detector", "pixel_model", *grid[0])
              and getattr(base, f.name) != getattr(defaults, f.name)}
    return BackEndChoice(chosen=choose_setting(scores, at_given), at_given=at_given,
                         shipped=_score(given, counts["shipped"]), scores=scores, folds=folds,
                         skipped=tuple(skipped), base=MappingProxyType(differ),
                         held_out=held_out, fold_settings=fold_settings)


def report_text(choice: BackEndChoice, model_path, *, trained: bool = True) -> str:
    """The back-end choice as a user reads it: the scores, then the ``[imaging.params]`` to
    extract with (:meth:`BackEndChoice.config_snippet`). ``trained``: the fold models were trained
    for the choice (``train_pixel_model``), else one fixed model was scored (``rockmass score``)."""
    def line(name, score):
        precision = "-" if math.isnan(score.precision) else f"{score.precision:.3f}"
        return (f"  {name}\n      F1 {score.f1:.3f}  P {precision}  R {score.recall:.3f}  "
                f"dP21 {score.dp21_pct:+.0f} %")

    this = "this recipe" if trained else "this model"
    settings = ", ".join(f"{name} = {value:g}" for name, value in choice.settings.items())
    skipped = (f"; {len(choice.skipped)} photos whose label marks nothing not scored"
               if choice.skipped else "")
    how = ("by a model of this recipe that did not see it" if trained
           else "by the model, with each setting tried")
    lines = [f"back end chosen by {choice.folds}-fold cross-validation on {choice.photos} "
             f"photographs (each scored {how}; F1 at {TOLERANCE_PX:g} px, docs/imaging.md "
             f"§3.2{skipped}):"]
    if trained:
        lines.append(line("shipped model, given settings", choice.shipped))
    lines.append(line(f"{this}, given settings", choice.at_given))
    if choice.kept_given:
        lines.append("  no setting tried beat the given settings by more than a standard error: "
                     "they are kept")
    else:
        lines += [line(f"{this}, {settings}", choice.chosen),
                  f"  (the best of the {len(choice.scores)} settings tried on these photos: "
                  "optimistic)"]
    if choice.held_out is not None:
        lines.append(line(f"{this}, each fold at the setting chosen on the other folds (what "
                          "choosing does on photos the choice did not see)", choice.held_out))
    lines += ["to extract with it, put in the config of rockmass extract / run (--config):",
              choice.config_snippet(model_path)]
    return "\n".join(lines)


def chosen_settings(model_info: Mapping) -> dict | None:
    """The back-end settings a model file's ``info`` records as chosen for it
    (``train_pixel_model --choose-back-end``), or None."""
    settings = (model_info.get("back_end") or {}).get("settings")
    return dict(settings) if settings else None


def recommended_settings(model_info: Mapping) -> dict | None:
    """:func:`chosen_settings` and the other settings the choice was made with (``with``), or
    None."""
    chosen = chosen_settings(model_info)
    return None if chosen is None else {**model_info["back_end"].get("with", {}), **chosen}


def unused_settings_note(model_info: Mapping, params) -> str | None:
    """A warning when settings a pixel model's back end was chosen with
    (:func:`recommended_settings`) differ from those of ``params`` (ExtractParams of the learned
    detector, as given: pixel lengths of the reference grid), else None. Names this rockmass does
    not know are left out.

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
    known = {f.name for f in fields(params)}
    settings = {name: value for name, value in settings.items() if name in known}
    differ = [name for name, value in settings.items() if not _same(_used(params, name), value)]
    if not differ:
        return None
    chosen = ", ".join(f"{name} = {_toml_value(value)}" for name, value in settings.items())
    used = ", ".join(f"{name} = {_toml_value(_used(params, name))}" for name in differ)
    return (f"the pixel model's back end was chosen for it by cross-validation on its photographs "
            f"({chosen}); this run uses {used}: set them in [imaging.params] to extract as the "
            f"model was validated (train_pixel_model printed them; docs/imaging.md §3.2)")


def _used(params, name: str):
    """The value of setting ``name`` in ``params``, a detector default resolved."""
    from .extract import DETECTOR_DEFAULTS

    return params.resolved(name) if name in DETECTOR_DEFAULTS else getattr(params, name)


def _same(a, b) -> bool:
    """Two setting values agree (numbers to rounding, lists element by element)."""
    if isinstance(a, (list, tuple)) or isinstance(b, (list, tuple)):
        return (isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)) and len(a) == len(b)
                and all(_same(x, y) for x, y in zip(a, b)))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return a == b or math.isclose(a, b)
    return a == b
