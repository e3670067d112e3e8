"""Train the learned joint detector's pixel model on synthetic faces only, reproducibly.

    OMP_NUM_THREADS=1 python -m rockmass.imaging.train_pixel_model [--out FILE] [--faces N] [--seed S]
                      [--wide-crevices [SHARE] [--crevice-width LO HI]] [--photos DIR --labels DIR
                      [--choose-back-end [FOLDS] [--config FILE]]]

Training data (docs/imaging.md §3.1): per stage, ``--faces`` field-like faces
(:func:`rockmass.imaging.synthetic_field.field_face`, 400 x 400 px) and a quarter as many faces of
the plain generator (:func:`rockmass.imaging.synthetic.synthetic_face`, "moderate" and "hard",
500 x 750 px), so the model keeps finding thin joints. Stage 1 is fitted on the faces of seeds
``seed, seed + 1, ...``, stage 2 on the next ones, with stage 1's probability maps of faces stage 1
never saw (so the context it learns from is as good as at run time, not better). No real
photograph is used. Each face is flattened (:func:`rockmass.imaging.learned.model_input`), its
features computed, and pixels sampled: positives within 1 px of a true centre line, negatives
farther than 3 px (pixels in between are left out), half of the negatives drawn from the 10 % with
the strongest dark-ridge response (the confusable ones). Every tenth face of the second lot is held out
and the log loss of each stage on it reported. ``--stages 1`` (the default: stage 2 learned the
synthetic faces' context too well and doubled the false traces on real photographs) fits stage 1
only.

Two options change the faces, not the default recipe: ``--tunnel-style`` draws the field faces in
:data:`rockmass.imaging.synthetic_field.TUNNEL_STYLE` (blast half-casts, shotcrete), and
``--ignore-minor-cracks`` leaves the field faces' unlabelled minor cracks
(:func:`rockmass.imaging.synthetic_field.minor_crack_mask`, 2 px margin) out of the negatives, so
that a thin dark line is not taught to be "no joint" when the plain faces teach that it is one.
``benchmarks/bench_pixel_training.py`` compares them; neither lifts the plain faces' F1 at the
detector's defaults, whose loss lies in the trace filters (docs/imaging.md §3.1).
``--wide-crevices [SHARE]`` draws a share (default 0.25,
:data:`rockmass.imaging.synthetic_field.CREVICE_STYLE`) of the field faces' major joints as wide
open crevices, dark cores ``--crevice-width LO HI`` px across (default 12-30), labelled at their
centre line as every major joint is: on real photographs the model marked a wide dark crevice's
two edges, not its centre. The other joints and everything else on the faces stay as drawn
without it (the crevices have a random stream of their own). It lifts real ``train/`` F1 at every
training seed but not ``val/`` (``bench_pixel_training.py --seed-spread``), so it is not the
shipped recipe.

Your own photographs (docs/imaging.md §3.2): ``--photos DIR --labels DIR --out FILE`` adds the
labelled photographs of DIR (labels of the same name and size, traces painted red or white on
black, :mod:`rockmass.imaging.labels`) to the first lot, every tenth held out for the loss (with
fewer than ten photos and no synthetic faces there is no held-out loss, and the command says so);
``--faces 0`` trains on them alone. Each photo is read when it is used (not all held in memory)
and put on the working grid extraction runs the model on (``--max-megapixels``, the default of
:class:`rockmass.imaging.extract.ExtractParams`): a model trained on full-size 24 MP photos would
see joints wider in pixels than it is later shown. ``rockmass extract --pixel-model FILE`` then
uses the model. ``--choose-back-end [FOLDS]`` (default 5) also chooses the learned detector's
hysteresis levels and trace length floor for the model by cross-validation on the photos
(:mod:`rockmass.imaging.site_back_end`: a model of this recipe trained per fold, every photo
scored by one that did not see it), records them in the model's ``info["back_end"]`` and prints
them as the ``[imaging.params]`` of a config, with the shipped model's score on the same photos;
``--config FILE`` gives the other settings the choice starts from (its ``[imaging.params]``).

Each perceptron (eq. (3.2)) is fitted by minimising the class-balanced binary cross-entropy with Adam
(Kingma & Ba 2015) on mini-batches, from a fixed seed. The default ``--seed`` (10 000) keeps the
training faces apart from the seeds tests and benchmarks use (0-999). The matrix products of the
fit sum in one fixed order (:func:`_product`, since session 20), so a model is the same whatever
the machine's number of BLAS threads. The shipped file was fitted in session 15 and is the one
every benchmark measures; run today, the command gives a model of other weights
(docs/imaging.md §3.1).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from .features import CONTEXT_NAMES, FEATURE_NAMES, context_features, pixel_features
from .learned import MAX_STRETCH, MIN_SPREAD, MODEL_FILE, PixelModel, Stage, model_input
from .synthetic_field import CREVICE_STYLE, TUNNEL_STYLE, FieldStyle

__all__ = ["face_samples", "sample_faces", "training_faces", "field_style", "labelled_photo",
           "fit_mlp", "main"]

POSITIVE_PX = 1.0
NEGATIVE_PX = 3.0


def face_samples(features, centre_lines, rng, *, ignore=None, n_positive=2500, n_negative=5000):
    """Indices and labels of pixels sampled from one face's (F, H, W) features (module notes);
    pixels of the bool mask ``ignore`` are never negatives."""
    import cv2

    distance = cv2.distanceTransform(np.where(centre_lines, 0, 255).astype(np.uint8), cv2.DIST_L2,
                                     cv2.DIST_MASK_PRECISE).ravel()
    positive = np.flatnonzero(distance <= POSITIVE_PX)
    far = distance > NEGATIVE_PX
    negative = np.flatnonzero(far if ignore is None else far & ~np.asarray(ignore, bool).ravel())
    ridge = features[FEATURE_NAMES.index("ridge_dark_2")].ravel()[negative]
    hard = negative[ridge >= np.quantile(ridge, 0.9)] if negative.size else negative
    pick = [rng.choice(positive, min(n_positive, positive.size), replace=False),
            rng.choice(negative, min(n_negative // 2, negative.size), replace=False),
            rng.choice(hard, min(n_negative // 2, hard.size), replace=False)]
    labels = np.concatenate([np.ones(pick[0].size), np.zeros(pick[1].size + pick[2].size)])
    return np.concatenate(pick), labels.astype(np.float32)


def training_faces(first_seed: int, n_field: int, n_plain: int, *, style=None,
                   ignore_minor_cracks: bool = False):
    """(seed, grey image, centre-line mask, ignore mask or None) of ``n_field`` field-like faces
    (of ``style``) and ``n_plain`` plain synthetic faces, seeds from ``first_seed`` on; with
    ``ignore_minor_cracks`` the field faces' minor cracks are to be left out of the negatives."""
    from .metrics import render_traces
    from .synthetic import synthetic_face
    from .synthetic_field import centre_line_mask, field_face, minor_crack_mask

    for i in range(n_field + n_plain):
        seed = first_seed + i
        ignore = None
        if i < n_field:
            face = field_face(seed=seed, style=style)
            lines = centre_line_mask(face)
            ignore = minor_crack_mask(face) if ignore_minor_cracks else None
        else:
            face = synthetic_face(("moderate", "hard")[i % 2], seed=seed, shape_px=(500, 750),
                                  m_per_px=0.016)
            lines = render_traces(face.truth, face.image.shape, face.m_per_px)
        yield seed, face.image, lines, ignore


def field_style(*, tunnel: bool = False, crevice_share: float | None = None,
                crevice_width_px=None) -> FieldStyle | None:
    """The style of the field training faces: :data:`TUNNEL_STYLE` with ``tunnel``, a share
    ``crevice_share`` of the major joints drawn as wide crevices ``crevice_width_px`` (lo, hi) wide
    when given; None (the default :class:`FieldStyle`) when neither is asked for."""
    if not tunnel and crevice_share is None:
        return None
    style = TUNNEL_STYLE if tunnel else FieldStyle()
    if crevice_share is not None:
        width = tuple(crevice_width_px) if crevice_width_px else CREVICE_STYLE.crevice_width_px
        style = replace(style, crevice_share=float(crevice_share), crevice_width_px=width)
    return style


def labelled_photo(photo, label, max_megapixels: float) -> tuple[np.ndarray, np.ndarray]:
    """(grey image in [0, 1], label centre lines) of one labelled photograph, on the working grid
    :func:`rockmass.imaging.extract.extract` would run the model on (the photo area-averaged to at
    most ``max_megapixels``): the centre lines are thinned at the photo's size, carried to the
    grid (a grid pixel any centre line crosses) and thinned again.

    Raises
    ------
    ValueError
        The label's size differs from the photograph's.
    """
    import cv2

    from .enhance import read_photo, to_grey
    from .extract import working_grid
    from .labels import photo_centre_lines
    from .skeleton_graph import skeletonize

    grey = to_grey(read_photo(photo), name=str(photo))
    lines = photo_centre_lines(label, photo, grey.shape)
    grey, (h, w), _ = working_grid(grey, max_megapixels, [])
    if lines.shape != (h, w):
        coverage = cv2.resize(lines.astype(np.float32), (w, h), interpolation=cv2.INTER_AREA)
        lines = skeletonize(coverage > 0)
    return grey, lines


def _data_note(n_synthetic: int, photos: list, photos_dir) -> str:
    """What the model was trained on, for its ``info``."""
    parts = ["synthetic faces (field_face, synthetic_face)"] if n_synthetic else []
    if photos:
        held = sum(_held_photo(k, photos) for k in range(len(photos)))
        parts.append(f"{len(photos)} labelled photographs of {photos_dir} ({held} held out)")
    return " and ".join(parts) + ("" if photos else " only")


def _held_photo(k: int, photos: list) -> bool:
    """Every tenth photograph is held out (when there are at least ten)."""
    return len(photos) >= 10 and k % 10 == 9


def fit_mlp(x, y, *, hidden=(32, 16), epochs=12, batch=1024, learning_rate=3e-3, seed=0):
    """Fit eq. (3.2) by Adam on the class-balanced cross-entropy; return (mean, std, weights, biases).

    Gradients by back-propagation of :math:`L = -\\sum_i c_i [y_i \\log p_i + (1 - y_i) \\log(1 - p_i)]
    / \\sum_i c_i`, :math:`c_i` = 1 / (share of y_i's class); Adam with β = (0.9, 0.999), ε = 1e-8.
    """
    rng = np.random.default_rng(seed)
    mean = x.mean(axis=0).astype(np.float32)
    std = np.maximum(x.std(axis=0), 1e-6).astype(np.float32)
    z = np.clip((x - mean) / std, -6, 6).astype(np.float32)
    share = y.mean()
    weight = np.where(y > 0.5, 0.5 / share, 0.5 / (1 - share)).astype(np.float32)
    sizes = (z.shape[1], *hidden, 1)
    params = []
    for a, b in zip(sizes[:-1], sizes[1:]):  # He initialisation
        params += [rng.normal(0, np.sqrt(2.0 / a), (a, b)).astype(np.float32), np.zeros(b, np.float32)]
    m = [np.zeros_like(p) for p in params]
    v = [np.zeros_like(p) for p in params]
    step = 0
    for _ in range(epochs):
        order = rng.permutation(len(z))
        for start in range(0, len(z), batch):
            idx = order[start:start + batch]
            acts = [z[idx]]
            for k in range(0, len(params), 2):
                out = _product(acts[-1], params[k]) + params[k + 1]
                acts.append(np.maximum(out, 0) if k < len(params) - 2 else out)
            p = 1.0 / (1.0 + np.exp(-np.clip(acts[-1][:, 0], -30, 30)))
            c = weight[idx] / weight[idx].sum()
            delta = ((p - y[idx]) * c)[:, None]
            grads = [None] * len(params)
            for k in range(len(params) - 2, -1, -2):
                grads[k] = _product(acts[k // 2].T, delta)
                grads[k + 1] = delta.sum(axis=0)
                if k:
                    delta = _product(delta, params[k].T) * (acts[k // 2] > 0)
            step += 1
            for i, g in enumerate(grads):
                m[i] = 0.9 * m[i] + 0.1 * g
                v[i] = 0.999 * v[i] + 0.001 * g * g
                m_hat, v_hat = m[i] / (1 - 0.9**step), v[i] / (1 - 0.999**step)
                params[i] -= learning_rate * m_hat / (np.sqrt(v_hat) + 1e-8)
    return mean, std, tuple(params[0::2]), tuple(params[1::2])


def _product(a, b):
    """a @ b summed in one fixed order, whatever the number of BLAS threads (NumPy's einsum
    without BLAS): a threaded matrix product splits its sums across threads, so the fitted weights
    would depend on the machine's thread count."""
    return np.einsum("ij,jk->ik", a, b, optimize=False)


def _log_loss(p, y):
    p = np.clip(p, 1e-6, 1 - 1e-6)
    return float(-np.mean(y * np.log(p) + (1 - y) * np.log(1 - p)))


def _stage(x, y, **kwargs) -> Stage:
    mean, std, weights, biases = fit_mlp(x, y, **kwargs)
    return Stage(mean=mean, std=std, weights=weights, biases=biases)


def main(argv=None) -> int:
    import cv2

    from .extract import ExtractParams
    from .labels import labelled_pairs

    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(MODEL_FILE), help=f"model file (default {MODEL_FILE})")
    parser.add_argument("--faces", type=int, default=80,
                        help="field-like training faces per stage (default 80)")
    parser.add_argument("--seed", type=int, default=10_000, help="first face seed (default 10000)")
    parser.add_argument("--epochs", type=int, default=12)
    parser.add_argument("--hidden", type=int, nargs="+", default=[32, 16])
    parser.add_argument("--stages", type=int, choices=(1, 2), default=1,
                        help="1: pixel features only (default); 2: add an auto-context stage")
    parser.add_argument("--plain-faces", type=int, dest="plain_faces",
                        help="plain synthetic faces per stage (default a quarter of --faces)")
    parser.add_argument("--tunnel-style", action="store_true",
                        help="field faces of TUNNEL_STYLE (half-casts, shotcrete)")
    parser.add_argument("--ignore-minor-cracks", action="store_true",
                        help="leave the field faces' minor cracks out of the negatives")
    parser.add_argument("--wide-crevices", type=float, nargs="?", metavar="SHARE",
                        const=CREVICE_STYLE.crevice_share,
                        help="draw this share of the field faces' major joints as wide dark "
                             f"crevices, labelled at the centre line (default share "
                             f"{CREVICE_STYLE.crevice_share:g})")
    parser.add_argument("--crevice-width", type=float, nargs=2, metavar=("LO", "HI"),
                        help="core width range of the wide crevices in pixels (default "
                             f"{CREVICE_STYLE.crevice_width_px[0]:g} {CREVICE_STYLE.crevice_width_px[1]:g})")
    parser.add_argument("--photos", metavar="DIR",
                        help="also train on your own photographs in DIR (with --labels; needs --out)")
    parser.add_argument("--labels", metavar="DIR",
                        help="their hand-traced labels, same file names: traces painted red, or "
                             "white on black (rockmass.imaging.labels)")
    parser.add_argument("--max-megapixels", type=float, default=ExtractParams().max_megapixels,
                        help="photos are trained on down-sampled to this, as extract runs the model "
                             "(default: ExtractParams' max_megapixels, %(default)g)")
    parser.add_argument("--choose-back-end", type=int, nargs="?", metavar="FOLDS", const=5,
                        help="with --photos: choose the learned detector's hysteresis levels and "
                             "trace length floor for this model by FOLDS-fold cross-validation on "
                             "the photos (default 5; rockmass.imaging.site_back_end), record them "
                             "in the model and print them as [imaging.params]")
    parser.add_argument("--config", metavar="FILE",
                        help="with --choose-back-end: the [imaging.params] of this rockmass config "
                             "are the settings the choice starts from (e.g. min_trace_contrast = "
                             "-inf for joints that show bright); pixel_model there is ignored")
    args = parser.parse_args(argv)
    if args.config is not None and args.choose_back_end is None:
        parser.error("--config goes with --choose-back-end")
    if args.choose_back_end is not None and args.photos is None:
        parser.error("--choose-back-end chooses settings on your labelled --photos; give them")
    if (args.photos is None) != (args.labels is None):
        parser.error("--photos and --labels go together")
    if args.photos is not None and args.out == str(MODEL_FILE):
        parser.error("give --out for a model trained on your photos (the default replaces the "
                     "model shipped with rockmass)")
    if args.crevice_width is not None and args.wide_crevices is None:
        parser.error("--crevice-width goes with --wide-crevices")
    if args.wide_crevices is not None and not 0.0 < args.wide_crevices <= 1.0:
        parser.error("--wide-crevices: the share must be in (0, 1]")
    if args.crevice_width is not None and not 0 < args.crevice_width[0] <= args.crevice_width[1]:
        parser.error("--crevice-width: give 0 < LO <= HI")
    if args.photos is not None and args.stages == 2:
        parser.error("--stages 2 trains on synthetic faces only; use --stages 1 with --photos")
    n_plain = args.plain_faces
    if n_plain is None:  # a quarter of the field faces, at least one when there are any
        n_plain = max(args.faces // 4, 1) if args.faces else 0
    photos = labelled_pairs(args.photos, args.labels) if args.photos is not None else []
    if not photos and args.faces + n_plain == 0:
        parser.error("nothing to train on: --faces 0 and no --photos")
    if args.choose_back_end is not None:
        from .site_back_end import check_folds

        try:
            check_folds(args.choose_back_end, len(photos), "--choose-back-end: FOLDS")
        except ValueError as error:
            parser.error(str(error))
    fit = dict(hidden=tuple(args.hidden), epochs=args.epochs, seed=args.seed)
    base = None if args.config is None else _config_params(args.config, parser,
                                                           args.max_megapixels)

    t0 = time.perf_counter()
    rng = np.random.default_rng(args.seed)
    style = field_style(tunnel=args.tunnel_style, crevice_share=args.wide_crevices,
                        crevice_width_px=args.crevice_width)
    faces = dict(style=style, ignore_minor_cracks=args.ignore_minor_cracks)
    synthetic = sample_faces(((image.astype(np.float32) / 255.0, lines, ignore) for _, image, lines,
                              ignore in training_faces(args.seed, args.faces, n_plain, **faces)), rng)
    trained = [pair for k, pair in enumerate(photos) if not _held_photo(k, photos)]
    own = sample_faces(_photo_faces(trained, args.max_megapixels), rng)
    stage1 = _stage(*_joined(synthetic, own), **fit)
    n_stage1 = len(synthetic[1]) + len(own[1])
    t_stage1 = time.perf_counter() - t0

    xs, ys, held = [], [], []
    second = args.seed + args.faces + n_plain
    for k, (seed, image, lines, ignore) in enumerate(training_faces(second, args.faces, n_plain,
                                                                    **faces)):
        if args.stages == 1 and k % 10 != 9:
            continue  # stage 1 alone: the second lot only provides the held-out faces
        features = pixel_features(model_input(image.astype(np.float32) / 255.0))
        both = features
        if args.stages == 2:
            p1 = stage1.predict(features.reshape(features.shape[0], -1)).reshape(features.shape[1:])
            both = np.concatenate([features, context_features(p1)])
        index, labels = face_samples(features, lines, rng, ignore=ignore)
        xs.append(both.reshape(both.shape[0], -1)[:, index].T)
        ys.append(labels)
        held.append(np.full(len(labels), k % 10 == 9))
    for k, (photo, label) in enumerate(photos):
        if _held_photo(k, photos):  # measured, never fitted
            grey, lines = labelled_photo(photo, label, args.max_megapixels)
            features = pixel_features(model_input(grey))
            index, labels = face_samples(features, lines, rng)
            xs.append(features.reshape(features.shape[0], -1)[:, index].T)
            ys.append(labels)
            held.append(np.ones(len(labels), dtype=bool))
    if not xs and args.stages == 2:
        parser.error("--stages 2 fits its second stage on the second lot of faces: give at least "
                     "ten --faces")
    if not xs:  # fewer than ten photos and faces: the model is fitted, its loss not measured
        print("train_pixel_model: no held-out faces or photos (fewer than ten of each): no "
              "held-out loss; --choose-back-end scores the model on photos it did not see",
              file=sys.stderr)
        xs, ys = [np.empty((0, len(FEATURE_NAMES)), np.float32)], [np.empty(0, np.float32)]
        held = [np.empty(0, bool)]
    x, y, held = np.concatenate(xs), np.concatenate(ys), np.concatenate(held)
    n_features = len(FEATURE_NAMES)
    if args.stages == 2:
        stages, names = (stage1, _stage(x[~held], y[~held], **fit)), FEATURE_NAMES + CONTEXT_NAMES
    else:  # the second lot of faces only measures stage 1
        stages, names = (stage1,), FEATURE_NAMES
    info = {"command": "python -m rockmass.imaging.train_pixel_model " + " ".join(argv or sys.argv[1:]),
            "seed": args.seed, "stages": args.stages, "field_faces_per_stage": args.faces,
            "plain_faces_per_stage": n_plain,
            "samples": [n_stage1, int((~held).sum())], "held_out_samples": int(held.sum()),
            "hidden": list(args.hidden), "epochs": args.epochs,
            "held_out_log_loss": None if not held.any() else
            [round(_log_loss(stage.predict(x[held][:, :len(names) if i else n_features].T), y[held]), 4)
             for i, stage in enumerate(stages)],
            "stage1_s": round(t_stage1, 1), "total_s": round(time.perf_counter() - t0, 1),
            "python": platform.python_version(), "numpy": np.__version__,
            "data": _data_note(args.faces + n_plain, photos, args.photos),
            "photos": args.photos, "labels": args.labels,
            # the stretch model_input applied to flat faces: extract warns when a run's differs
            "input": {"min_face_spread": MIN_SPREAD, "max_stretch": MAX_STRETCH}}
    if args.wide_crevices is not None:
        info["wide_crevices"] = {"share": style.crevice_share,
                                 "width_px": list(style.crevice_width_px)}
    choice = None
    if args.choose_back_end is not None:
        choice = _choose_back_end(photos, synthetic, args.choose_back_end, args.seed,
                                  args.max_megapixels, info["input"], fit, base)
        info["back_end"] = choice.record()
        info["total_s"] = round(time.perf_counter() - t0, 1)
    model = PixelModel(stages=stages, feature_names=names, info=info)
    path = model.save(args.out)
    print(json.dumps(info, indent=2))
    if choice is not None:
        from .site_back_end import report_text

        print(report_text(choice, path))
    print(f"wrote {path} ({path.stat().st_size} bytes) in {time.perf_counter() - t0:.1f} s")
    return 0


def _config_params(path, parser, max_megapixels: float):
    """ExtractParams of the ``[imaging.params]`` of a rockmass config file
    (:func:`rockmass.config.load_config`, which names the file and the field of any problem), the
    settings the back-end choice starts from: its ``pixel_model`` left out (the model is the one
    being trained), ``max_megapixels`` the training's. A parser error (exit 2) when the config is
    refused, the learned detector cannot run with it, or its ``max_megapixels`` differs from the
    training's."""
    from ..config import load_config
    from ..errors import ConfigError
    from .extract import ExtractParams

    try:
        document = load_config(path)
    except ConfigError as error:
        parser.error(f"--config {error}")
    table = {} if document.imaging is None else dict(document.imaging.params)
    table.pop("pixel_model", None)
    if table.get("max_megapixels", max_megapixels) != max_megapixels:
        parser.error(f"--config {path}: imaging.params.max_megapixels = {table['max_megapixels']} "
                     f"differs from the training's --max-megapixels {max_megapixels:g}: give the "
                     f"same to both, so the model is trained on the grid it will run on")
    try:
        return replace(ExtractParams(**table), detector="learned", max_megapixels=max_megapixels)
    except ValueError as error:
        parser.error(f"--config {path}: imaging.{error}")


def _choose_back_end(photos, synthetic, folds, seed, max_megapixels, input_record, fit, base):
    """:func:`rockmass.imaging.site_back_end.choose_back_end` with fold models of this recipe: the
    same synthetic samples, the fold's training photos sampled from a stream of their own
    (seed, fold), no photo held out for a loss (the final model holds out every tenth).
    ``base``: the settings to start from (None: the defaults), at ``max_megapixels``."""
    import tempfile

    from .extract import ExtractParams
    from .site_back_end import choose_back_end

    def report(line):
        print(f"train_pixel_model: back end: {line}", file=sys.stderr, flush=True)

    base = replace(base or ExtractParams(detector="learned"), max_megapixels=max_megapixels)
    with tempfile.TemporaryDirectory() as folder:
        def train_fold(pairs, fold):
            own = sample_faces(_photo_faces(pairs, max_megapixels),
                               np.random.default_rng([seed, fold]))
            model = PixelModel(stages=(_stage(*_joined(synthetic, own), **fit),),
                               feature_names=FEATURE_NAMES, info={"input": input_record})
            return model.save(Path(folder) / f"fold_{fold}.npz")

        return choose_back_end(photos, train_fold, folds=folds, base=base, progress=report)


def sample_faces(faces, rng) -> tuple[np.ndarray, np.ndarray]:
    """(N, F) sampled features and (N,) labels of ``faces``, (grey image in [0, 1], centre-line
    mask, ignore mask or None) triples (:func:`face_samples`)."""
    xs, ys = [np.empty((0, len(FEATURE_NAMES)), np.float32)], [np.empty(0, np.float32)]
    for grey, lines, ignore in faces:
        features = pixel_features(model_input(grey))
        index, labels = face_samples(features, lines, rng, ignore=ignore)
        xs.append(features.reshape(features.shape[0], -1)[:, index].T)
        ys.append(labels)
    return np.concatenate(xs), np.concatenate(ys)


def _photo_faces(pairs, max_megapixels):
    """The labelled photographs as :func:`sample_faces` takes them, read when used."""
    return ((*labelled_photo(photo, label, max_megapixels), None) for photo, label in pairs)


def _joined(*samples):
    """(x, y) of several (x, y) sample sets."""
    return np.concatenate([x for x, _ in samples]), np.concatenate([y for _, y in samples])


if __name__ == "__main__":
    sys.exit(main())
