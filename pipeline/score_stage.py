"""The work of ``rockmass score``: the detector scored against a user's hand-traced photographs.

Every photo of ``--photos`` that has a label of the same name in ``--labels`` is extracted with the
settings ``rockmass extract`` would use (``--config``'s ``[imaging]``, then the flags) and scored
against the label (:mod:`rockmass.imaging.label_scores`, docs/imaging.md §3.5). With ``--out`` it
writes ``scores.csv`` (one row per photo), ``summary.json`` (the settings, the scores over all
photos and per photo, the photos not scored), ``manifest.json``, with ``--review``
``review/<photo>.png``, and with ``--choose-back-end`` ``back_end.toml`` (the learned detector's
back end chosen for the model on these photos) — all of them or none.
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from .errors import InputError, reading
from .extract_stage import extract_params, imaging_settings, read_photograph
from .progress import count_bar

__all__ = ["compute", "produce", "SCORE_COLUMNS"]

#: Entries of --out the command writes in some runs and not others: a new set drops the old ones.
_OWNED = (r"review", r"back_end\.toml")
#: Folds of ``--choose-back-end`` without a number (fewer with fewer photos).
DEFAULT_FOLDS = 5
#: Columns of scores.csv, in order (PhotoScore.to_dict keys).
SCORE_COLUMNS = ("photo", "label", "F1", "precision", "recall", "dP21_pct", "dP20_pct", "traces",
                 "labelled_traces", "drawn_px", "labelled_px", "detector", "seconds")


def _pairs(args):
    """The (photo, label) pairs, or bad input naming the folder."""
    from .imaging.labels import labelled_pairs

    try:
        return labelled_pairs(args.photos, args.labels)
    except (OSError, ValueError) as exc:  # missing, empty, unlistable, labels mixed up
        plain = isinstance(exc, (ValueError, FileNotFoundError))  # the message names the folder
        text = exc if plain else f"cannot list the folders: {exc}"
        raise InputError(f"--photos / --labels: {text}") from None


def _labelled(pairs) -> tuple[list, list]:
    """Every label read before any photo is extracted: (the pairs whose label marks traces, those
    whose label marks nothing). A label that cannot be read, or whose size is neither the
    photo's nor the photo's turned a quarter (EXIF orientation is applied when it is decoded),
    is bad input naming it."""
    from .image_limits import image_size
    from .imaging.labels import label_mask

    kept, empty = [], []
    for photo, label in pairs:
        mask = _label_read(label, label_mask, label)
        size = image_size(photo)
        if size is not None and mask.shape not in (size[::-1], tuple(size)):
            raise InputError(f"{label}: label is {mask.shape[1]} x {mask.shape[0]} px, its photo "
                             f"{Path(photo).name} {size[0]} x {size[1]} px")
        (kept if mask.any() else empty).append((photo, label))
    return kept, empty


def _read_lines(label, photo, shape):
    """The label's centre lines at the photo's size; bad input naming the label."""
    from .imaging.labels import photo_centre_lines

    return _label_read(label, photo_centre_lines, label, photo, shape)


def _label_read(label, read, *args):
    """``read(*args)`` of a label file: what its content or an unreadable file raises is bad
    input naming it."""
    try:
        with reading(label, "--labels"):
            return read(*args)
    except OSError as exc:  # cv2 cannot decode it (or read it at all)
        text = str(exc)
        raise InputError(text if str(label) in text else f"{label}: --labels: {text}") from None


def _folds(args, n_photos: int, params) -> int | None:
    """The folds of ``--choose-back-end`` (None without it): the number given, or 5 (fewer when
    there are fewer photos); checked before any photo is extracted."""
    if args.choose_back_end is None:
        return None
    if params.detector == "ridge":  # named, or chosen by --bright-lines
        raise InputError("--choose-back-end chooses the learned detector's settings: not with the "
                         "ridge detector (--detector ridge, --bright-lines)")
    from .imaging.site_back_end import check_folds

    folds = min(DEFAULT_FOLDS, n_photos) if args.choose_back_end == 0 else args.choose_back_end
    try:
        check_folds(folds, n_photos, "--choose-back-end: FOLDS")  # photos whose label marks traces
    except ValueError as exc:
        raise InputError(str(exc)) from None
    return folds


def _photo_extractor(settings: dict, params, max_pixels_option):
    """``extract_photo(path) -> (image, Extraction, m_per_px)`` for
    :func:`rockmass.imaging.label_scores.score_labelled_photos`, with the run's settings; the
    extraction's warnings are collected per photo instead of printed."""
    from .imaging import extract

    # without a scale the traces are in pixels: m_per_px = 1 says so without the warning that
    # rockmass extract gives (the scores are in pixels of the photograph either way)
    m_per_px = settings["m_per_px"] or 1.0

    def extract_photo(path):
        image, _ = read_photograph(Path(path), max_pixels_option)
        with warnings.catch_warnings(), reading(path):
            warnings.simplefilter("ignore", UserWarning)  # kept in the result's warnings
            result = extract(image, m_per_px=m_per_px, joint_width_px=settings["joint_width_px"],
                             joint_width_m=settings["joint_width_m"], params=params)
        return image, result, m_per_px

    return extract_photo


def _finite(value):
    """``value``, or None for NaN (JSON has no NaN; an undefined score is null)."""
    return None if isinstance(value, float) and math.isnan(value) else value


def compute(args, review_folder: Path | None = None) -> dict:
    """Score every labelled photo; return the summary document (``settings``, ``tolerance_px``,
    ``overall``, ``photos``, ``skipped``, ``warnings``, and ``back_end`` with
    ``--choose-back-end``); with ``review_folder``, each photo's review image is written there."""
    import dataclasses

    from .imaging.extract import infinities_as_text
    from .imaging.label_scores import score_labelled_photos, summarise_photo_scores

    settings = imaging_settings(args)
    if settings["m_per_px"] is None and settings["joint_width_m"] is not None:
        raise InputError(f"{args.config}: imaging.joint_width_m needs imaging.m_per_px (the photos' "
                         "scale); or give the width in pixels: --joint-width")
    params = extract_params(settings, args.config)
    if not (math.isfinite(args.tolerance) and args.tolerance > 0):
        raise InputError(f"--tolerance: expected a distance in pixels > 0, got {args.tolerance:g}")
    pairs, empty = _labelled(_pairs(args))
    empty = [str(photo) for photo, _ in empty]
    if not pairs:
        raise InputError(f"{args.labels}: no label marks any trace ({len(empty)} labels are "
                         "empty): nothing to score")
    folds = _folds(args, len(pairs), params)
    on_photo = None if review_folder is None else _review_writer(review_folder, pairs,
                                                                  args.tolerance)
    notes: dict[str, list[str]] = {}
    extract_photo = _photo_extractor(settings, params, args.max_pixels)

    def extract_and_note(path):
        image, result, scale = extract_photo(path)
        if result.warnings:
            notes[str(path)] = list(result.warnings)
        return image, result, scale

    t0 = time.perf_counter()
    with count_bar("score", len(pairs), "photo") as bar:
        done = []

        def after_photo(*scored):  # the review image, then the bar
            if on_photo is not None:
                on_photo(*scored)
            done.append(True)
            if bar is not None:
                bar(len(done))

        scores, skipped = score_labelled_photos(pairs, extract_and_note,
                                                tolerance_px=args.tolerance, on_photo=after_photo,
                                                read_lines=_read_lines)
    overall = summarise_photo_scores(scores)
    back_end = None if folds is None else _back_end(pairs, folds, settings, params)
    return {**({} if back_end is None else {"back_end": back_end}),
            "settings": {**settings, "params": infinities_as_text(dataclasses.asdict(params))},
            "tolerance_px": args.tolerance,
            "overall": {key: _finite(value) for key, value in overall.items()},
            "photos": [{key: _finite(value) for key, value in score.to_dict().items()}
                       for score in scores],
            "skipped": empty + skipped, "warnings": notes,
            "seconds": time.perf_counter() - t0}


def _back_end(pairs, folds: int, settings, params) -> dict:
    """The learned detector's back end chosen for the run's model on the photos
    (:func:`rockmass.imaging.site_back_end.choose_back_end`, the model fixed): its record (with the
    joint width it was chosen at), the config to extract with (``config``: ``[imaging]``'s joint
    width when one was given, and ``[imaging.params]``) and the printed ``report``."""
    from .imaging import learned
    from .imaging.extract import infinities_as_text
    from .imaging.site_back_end import choose_back_end, report_text

    model = params.pixel_model or learned.MODEL_FILE
    width = settings["joint_width_px"]
    if width is None and settings["joint_width_m"] is not None:
        width = settings["joint_width_m"] / settings["m_per_px"]
    def report(line):  # the choice runs 18 settings per photo: say where it is
        print(f"rockmass score: back end: {line}", file=sys.stderr, flush=True)

    choice = choose_back_end(pairs, lambda photos, fold: model, folds=folds, base=params,
                             joint_width_px=width, progress=report)
    shipped = params.pixel_model is None
    config = choice.config_snippet(None if shipped else model)
    if width is not None:  # the width the settings were chosen at goes with them
        config = f"[imaging]\njoint_width_px = {width!r}\n\n{config}"
    record = choice.record()
    record["with"] = infinities_as_text({**record["with"], "joint_width_px": width})
    return {**record, "model": "shipped" if shipped else str(model), "config": config,
            "report": report_text(choice, None if shipped else model, trained=False)}


def csv_rows(document: dict) -> str:
    """scores.csv: a header of :data:`SCORE_COLUMNS` and a row per photo (empty where undefined)."""
    from .outputs import csv_text

    return csv_text({name: [row[name] for row in document["photos"]] for name in SCORE_COLUMNS})


def produce(args, out_dir=None) -> dict:
    """Score, and write the outputs into ``out_dir`` when given (all of them or none); return the
    summary document."""
    if not out_dir:
        if args.review:
            raise InputError("--review writes review images: give --out")
        return compute(args)
    from contextlib import ExitStack

    from .atomic import atomic_path, atomic_write_json, atomic_write_text
    from .manifest import build_manifest
    from .outputs import output_set

    with output_set(out_dir, owns=_OWNED) as out, ExitStack() as stack:
        document = compute(args, out / "review" if args.review else None)
        csv = stack.enter_context(atomic_path(out / "scores.csv"))
        atomic_write_text(csv, csv_rows(document))
        js = stack.enter_context(atomic_path(out / "summary.json"))
        atomic_write_json(js, document, nan_as_null=True)
        inputs = [p for row in document["photos"] for p in (row["photo"], row["label"])]
        manifest = build_manifest(command=args.argv, config={"imaging": document["settings"]},
                                  inputs=inputs, timings_s={"score_s": document["seconds"]},
                                  extra={"F1": document["overall"]["F1"]})
        if "back_end" in document:
            toml = stack.enter_context(atomic_path(out / "back_end.toml"))
            atomic_write_text(toml, document["back_end"]["config"] + "\n")
        mf = stack.enter_context(atomic_path(out / "manifest.json"))
        atomic_write_json(mf, manifest, nan_as_null=True)
    return document


def _review_writer(folder: Path, pairs, tolerance_px: float):
    """``on_photo`` writing each photo's review image (PNG) into ``folder``
    (:func:`rockmass.imaging.label_scores.review_image`)."""
    from .imaging.label_scores import review_names

    names = review_names([photo for photo, _ in pairs])

    def write(score, image, drawn, lines):
        import cv2

        from .atomic import atomic_write_bytes
        from .imaging.label_scores import review_image

        rgb = review_image(image, drawn, lines, tolerance_px=tolerance_px)
        ok, png = cv2.imencode(".png", np.ascontiguousarray(rgb[..., ::-1]))
        if not ok:
            raise OSError(f"cannot encode the review image of {score.photo}")
        atomic_write_bytes(folder / names[score.photo], png.tobytes())

    return write
