"""Photo -> traces on real labelled photographs (validation only), and on synthetic faces.

    python benchmarks/bench_imaging_real.py [--quick] [--detectors ridge,learned,auto]
                                            [--splits val,train] [--no-synthetic] [--no-settings]
                                            [--face-masks full,border,off] [--upsampled 2,4]
                                            [--agreement-only] [--stages-only] [--spreads-only]

1. Real faces: ``../shared/data/rock-face-fractures`` (natural rock faces, 300-400 px, with
   hand-traced major fractures painted red about 5 px wide; AGPL-3.0, read from the shared data
   folder, never copied into the package and never trained on). ``val/`` (44 images) is only
   measured; ``train/`` (99) is where the learned detector's thresholds and trace filters were
   chosen, printed beside it so the two can be compared. Labels are skeletonised (the red strokes
   only; the label files' 1-px white frame is not a label), the extracted traces are drawn as 1-px
   lines, and each image is scored by :func:`rockmass.imaging.metrics.raster_match` at a 5 px
   tolerance (docs/imaging.md §8, eqs. (8.5)-(8.6)). Rows give the mean over images of F1,
   precision and recall (F1 = 0 for an image with nothing drawn), the pooled ("micro") F1 over all
   pixels, dP21 = drawn / labelled line length - 1 over all images (lengths as 1-px line pixel
   counts, %), dP20 = number of traces / number of labelled traces - 1 over all images (labelled
   traces: the label skeleton's branches chained straight through junctions, as the chain does,
   those of 10 px or more; %), the extraction time per image and the MP/s of the input. Besides
   the defaults, the learned detector is run at a few other settings (not with ``--no-settings``):
   the defaults of the last session and the steps added since, one at a time. When the folder is
   absent the section is skipped with a message (exit code 0). ``ROCKMASS_REAL_DATA`` points at
   another copy.
2. Synthetic faces, the two generators (1000 x 1500 px, 0.008 m/px; seeds 1-3, not the tuning seeds
   100+ nor the training seeds of the learned model, 10_000+): the chain's own "moderate" faces
   (:func:`rockmass.imaging.synthetic_face`), the same in flat light (grey levels pulled towards
   the median to 0.35 of their spread, :func:`rockmass.imaging.synthetic.in_flat_light`) and
   "hard", and field-like faces (:func:`rockmass.imaging.synthetic_field.field_face`), buffered F1
   at 3 px, dP21, dP20, run time; the learned detector also at session 7's setting and with the
   contrast floor fixed at 0.25 as before session 17 (not with ``--no-settings``).

   With ``--face-masks`` (e.g. ``full,border,off``), each detector's defaults are run once per
   ``ExtractParams.face_mask`` mode listed (docs/imaging.md §2.1), the extraction time including
   the mask's; the default mode alone otherwise (the same for the synthetic faces of section 2).
   Section 4 then times the mask by itself.

3. Throughput (not with ``--quick``): one 12 MP moderate face (4000 x 3000 px, processed
   down-sampled to the default 4 MP), whole ``extract`` call per detector, MP/s of the input
   ("auto" runs the ridge chain on a second thread beside the learned one).

4. Face mask alone (with ``--face-masks``): :func:`rockmass.imaging.face_mask.face_mask` on a
   12 MP (3000 x 4000) RGB photo (the moderate face of section 3 in colour), best of 5, one core.

5. Photo size (with ``--upsampled``, e.g. ``2,4``): the real photos of ``--splits`` enlarged that
   many times (bicubic) with their labels, scored at the tolerance times the enlargement, at the
   defaults with the joint width not given and given as 3 px times the enlargement, and for the
   learned detector also on the working grid alone (``learned_levels = []``, as before session
   18). The same scenes at more pixels: how far the chain's pixel-valued settings tie it to the
   photos' size. ``train/`` is where ``learned_levels`` and its rule were chosen.

6. The two detectors' agreement (with the "auto" detector among ``--detectors``; alone with
   ``--agreement-only``): :func:`rockmass.imaging.extract.detector_agreement`, the share of the
   ridge filter's trace length within 5 px of the learned detector's traces, by which
   ``detector = "auto"`` keeps the ridge traces (above ``ExtractParams.auto_agreement``) or the
   learned ones. Its smallest, median and largest value and the share of photos on which the
   ridge traces are kept, on the real ``train/`` photos (where ``auto_agreement`` was chosen, with
   the synthetic faces), the real ``val/`` photos (measured only), and synthetic faces: plain
   easy / moderate / hard faces at 1000 x 1500 px (seeds 1-10) and moderate at 400 x 600 px
   (0.02 m/px, seeds 1-5), field-like and tunnel-style faces (seeds 1-10); and both detectors'
   F1 and dP21 on the field-like and tunnel-style faces on which the ridge traces are kept.

7. Where the learned detector loses the joints (``--stages-only``): on plain moderate faces (seeds
   1-3) and field-like and tunnel-style faces (seeds 1-6), 1000 x 1500 px, the share of the true
   centre lines' length lying within 3 px of what each stage of the chain keeps: the pixels of
   probability >= ``prob_low``, the hysteresis mask (seeds >= ``prob_high``, small objects removed,
   holes filled), its skeleton, the pruned skeleton graph, and the traces after linking and the
   length, contrast and width filters; and the traces' precision at 3 px. Rows in
   ``results/bench_imaging_real_stages.json``.

8. Faces of low contrast (``--spreads-only``): the relative spread s = 1.4826 MAD / median of the
   learned detector's flattened input (:func:`rockmass.imaging.vectorize.face_levels`) on the
   faces the shipped model was trained on (its recipe: 80 field-like and 20 plain faces, seeds
   10 000+), the real ``train/`` and ``val/`` photos and the synthetic faces of section 2; the
   smallest, median and largest s, how many faces are stretched (s < ``min_face_spread``), and,
   extracting with the learned detector, on how many its contrast floor was lowered
   (``face_contrast_share``; not for the training faces). Rows in
   ``results/bench_imaging_real_spreads.json`` (with the lowest floor of each set).

Each photo is extracted once per setting: the joint-score rows and section 1b reuse the traces
(and report the time of that one extraction).

The header names the shipped model file and its size. Rows also go to
benchmarks/results/bench_imaging_real.json (``..._quick.json`` with ``--quick``; the runs with
``--face-masks`` or ``--upsampled`` to ``..._face_mask.json`` or ``..._enlarged.json``).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

from _common import detector_params, header, save, table

from rockmass.imaging.label_scores import TOLERANCE_PX, label_trace_count
from rockmass.imaging.metrics import summarise_counts

DATA = Path(os.environ.get("ROCKMASS_REAL_DATA",
                           Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
                           / "rock-face-fractures")).resolve()

REAL_COLUMNS = [("split", "s"), ("detector", "s"), ("setting", "s"), ("images", "d"), ("F1", ".3f"),
                ("P", ".3f"), ("R", ".3f"), ("F1_pooled", ".3f"), ("dP21_pct", "+.0f"),
                ("dP20_pct", "+.0f"), ("s_per_image", ".2f"), ("MP_per_s", ".2f")]
SYNTH_COLUMNS = [("detector", "s"), ("faces", "s"), ("F1", ".3f"), ("P", ".3f"), ("R", ".3f"),
                 ("dP21_%", "+.1f"), ("dP20_%", "+.1f"), ("time_s", ".2f")]
#: Settings of the learned detector measured besides its defaults on the real faces: the defaults
#: of the previous round (hysteresis 0.85 / 0.97, 50 px floor, no hole filling or trace filters),
#: then the steps added since, one at a time (docs/imaging.md §3.1).
LEARNED_SETTINGS = (
    ("session-7 defaults (0.85/0.97, 50 px)",
     dict(prob_low=0.85, fill_holes_px=0, min_trace_length_px=50.0, min_trace_contrast=float("-inf"),
          min_trace_width=0.0)),
    ("+ holes, 0.80/0.97, 70 px",
     dict(min_trace_contrast=float("-inf"), min_trace_width=0.0)),
    ("+ width >= 1 joint width (3 px)", dict(min_trace_contrast=float("-inf"))),
    ("+ contrast >= 0.20", dict(min_trace_contrast=0.20)),
    ("+ contrast >= 0.30", dict(min_trace_contrast=0.30)),
    ("contrast floor fixed at 0.25 (face_contrast_share = inf, before session 17)",
     dict(face_contrast_share=float("inf"))),
    ("working grid only (learned_levels = [], before session 18)", dict(learned_levels=())),
)
#: The rows of LEARNED_SETTINGS also run on the synthetic faces: the oldest setting and the steps
#: of the last two sessions.
SYNTHETIC_SETTINGS = (LEARNED_SETTINGS[0], LEARNED_SETTINGS[-2], LEARNED_SETTINGS[-1])


def label_skeleton(path: Path, upsample: float = 1.0) -> np.ndarray:
    """Skeleton of the red strokes of a label image (bool mask), the label image enlarged
    ``upsample`` times first (nearest neighbour); :mod:`rockmass.imaging.labels`."""
    import cv2

    from rockmass.imaging.labels import label_centre_lines

    if upsample == 1.0:
        return label_centre_lines(path)
    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise OSError(f"{path}: cannot read the label image")
    big = cv2.resize(bgr, None, fx=upsample, fy=upsample, interpolation=cv2.INTER_NEAREST)
    return label_centre_lines(np.ascontiguousarray(big[..., ::-1]))


def real_pairs(split: str = "val") -> list[tuple[Path, Path]]:
    """(image, label) paths of one split of the labelled set, sorted by name."""
    images = sorted((DATA / split / "images").glob("*.jpg"))
    return [(p, DATA / split / "labels" / f"{p.stem}.png") for p in images]


def confident(traces, min_joint_score):
    """The traces whose ``joint_score`` reaches ``min_joint_score`` (all of them when it is None)."""
    if min_joint_score is None or traces.n_traces == 0:
        return traces
    return traces.subset(np.asarray(traces.attributes["joint_score"]) >= min_joint_score)


_EXTRACTIONS: dict = {}


def _extract_real(image_path: Path, shape, params, joint_width_px, upsample: float):
    """(traces, seconds) of one real photo; see :func:`_extraction_real`."""
    result, seconds = _extraction_real(image_path, shape, params, joint_width_px, upsample)
    return result.traces, seconds


def _extraction_real(image_path: Path, shape, params, joint_width_px, upsample: float):
    """(Extraction, seconds) of one real photo (enlarged to ``shape`` when ``upsample`` != 1;
    ``shape`` is not used otherwise); each (photo, settings, model) is extracted once per run and
    its first time reported again. The key
    holds the model file the learned detector would read (``params.pixel_model``, else the
    module's ``MODEL_FILE`` at call time), so another model never gets cached traces."""
    import cv2

    from rockmass.imaging import learned
    from rockmass.imaging.extract import extract

    model = str(Path(params.pixel_model or learned.MODEL_FILE).resolve())
    key = (str(image_path), repr(params), model, joint_width_px, upsample)
    if key not in _EXTRACTIONS:
        image = cv2.imread(str(image_path), cv2.IMREAD_COLOR)[..., ::-1]  # RGB, as read_photo
        if upsample != 1.0:
            image = cv2.resize(image, shape[::-1], interpolation=cv2.INTER_CUBIC)
        t0 = time.perf_counter()
        result = extract(np.ascontiguousarray(image), m_per_px=1.0, joint_width_px=joint_width_px,
                         params=params)
        _EXTRACTIONS[key] = (result, time.perf_counter() - t0)
    return _EXTRACTIONS[key]


def score_real(pairs, params, joint_width_px: float | None, min_joint_score=None,
               upsample: float = 1.0) -> dict:
    """Mean and pooled scores of one setting over the labelled images (of the traces whose joint
    score reaches ``min_joint_score``, when given). With ``upsample`` > 1 each photo is enlarged
    that many times (bicubic) and its label with it, and the tolerance grows in proportion: the
    same scene at a higher pixel count. ``band_px`` is the length-weighted median of the traces'
    ``band_width_px``."""
    from rockmass.imaging.label_scores import score_traces

    counts, elapsed, megapixels, n_traces = [], 0.0, 0.0, np.zeros(2)
    bands, lengths = [], []
    for image_path, label_path in pairs:
        truth = label_skeleton(label_path, upsample)
        traces, seconds = _extract_real(image_path, truth.shape, params, joint_width_px, upsample)
        elapsed += seconds
        megapixels += truth.size / 1e6
        traces = confident(traces, min_joint_score)
        counts.append(score_traces(traces, truth, tolerance_px=TOLERANCE_PX * upsample)[0])
        n_traces += (traces.n_traces, label_trace_count(truth))
        if traces.n_traces:
            bands.append(np.asarray(traces.attributes["band_width_px"], dtype=float))
            lengths.append(traces.lengths_m())
    return dict(images=len(pairs), **summarise_counts(counts),
                dP20_pct=float(100 * (n_traces[0] / max(n_traces[1], 1) - 1)),
                s_per_image=elapsed / max(len(pairs), 1), MP_per_s=megapixels / max(elapsed, 1e-9),
                band_px=_weighted_median(np.concatenate(bands), np.concatenate(lengths))
                if bands else float("nan"))


def agreement_row(name: str, agreements, auto_agreement: float) -> dict:
    """Smallest, median and largest detector agreement over a set of photos, and the share of them
    on which "auto" keeps the ridge traces."""
    values = np.asarray(agreements, dtype=float)
    return {"photos": name, "n": int(values.size), "min": float(values.min()),
            "median": float(np.median(values)), "max": float(values.max()),
            "ridge_kept": float(np.mean(values > auto_agreement))}


def agreement_section(splits, quick: bool) -> tuple[list[dict], list[dict]]:
    """Section 6: the detector agreement on the real photos of ``splits`` and on synthetic faces;
    and, for each field-like or tunnel-style face on which "auto" keeps the ridge traces, both
    detectors' buffered F1 (3 px) and dP21 there."""
    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.metrics import trace_accuracy
    from rockmass.imaging.synthetic import synthetic_face
    from rockmass.imaging.synthetic_field import TUNNEL_STYLE, field_face

    auto = ExtractParams(detector="auto")
    rows = []
    for split in splits:
        if not (DATA / split / "images").is_dir():
            continue
        pairs = real_pairs(split)[:12] if quick else real_pairs(split)
        choices = [_extraction_real(image_path, None, auto, 3.0, 1.0)[0].detector_choice
                   for image_path, _ in pairs]  # the photo as it is: no shape to enlarge to
        role = "chosen on" if split == "train" else "measured only"
        rows.append(agreement_row(f"real {split}/ ({role})", [c["agreement"] for c in choices],
                                  auto.auto_agreement))
    n = 2 if quick else 10
    makers = [(f"{level}, 1000 x 1500 px", lambda s, level=level: synthetic_face(
                   level, seed=s, shape_px=(1000, 1500), m_per_px=0.008), n)
              for level in ("easy", "moderate", "hard")]
    makers += [("moderate, 400 x 600 px", lambda s: synthetic_face(
                    "moderate", seed=s, shape_px=(400, 600), m_per_px=0.02), min(n, 5)),
               ("field-like, 1000 x 1500 px", lambda s: field_face(
                    seed=s, shape_px=(1000, 1500), m_per_px=0.008), n),
               ("tunnel-style, 1000 x 1500 px", lambda s: field_face(
                    seed=s, shape_px=(1000, 1500), m_per_px=0.008, style=TUNNEL_STYLE), n)]
    crossed = []
    for name, make, count in makers:
        values = []
        for seed in range(1, count + 1):
            face = make(seed)
            values.append(extract(face.image, m_per_px=face.m_per_px,
                                  params=auto).detector_choice["agreement"])
            if values[-1] > auto.auto_agreement and not name.startswith(("easy", "moderate")):
                row = {"faces": name, "seed": seed, "agreement": values[-1]}
                for detector in ("learned", "ridge"):
                    result = extract(face.image, m_per_px=face.m_per_px,
                                     params=detector_params(detector))
                    acc = trace_accuracy(result.traces, face.truth,
                                         m_per_px=face.m_per_px / result.scale.work_factor)
                    row.update({f"F1_{detector}": acc.f1, f"dP21_{detector}_%": 100 * acc.p21_rel_error})
                crossed.append(row)
        rows.append(agreement_row(f"synthetic {name}, seeds 1-{count}", values, auto.auto_agreement))
    return rows, crossed


def stages_section() -> list[dict]:
    """Section 7 on plain moderate (seeds 1-3), field-like and tunnel-style faces (seeds 1-6)."""
    from rockmass.imaging.synthetic import synthetic_face
    from rockmass.imaging.synthetic_field import TUNNEL_STYLE, field_face

    makers = (("moderate (synthetic_face)", lambda s: synthetic_face(
                   "moderate", seed=s, shape_px=(1000, 1500), m_per_px=0.008), [1, 2, 3]),
              ("field-like (field_face)", lambda s: field_face(
                   seed=s, shape_px=(1000, 1500), m_per_px=0.008), list(range(1, 7))),
              ("tunnel-style (TUNNEL_STYLE)", lambda s: field_face(
                   seed=s, shape_px=(1000, 1500), m_per_px=0.008, style=TUNNEL_STYLE),
               list(range(1, 7))))
    return [{"faces": f"{name}, seeds {seeds[0]}-{seeds[-1]}", **stage_recall(make, seeds)}
            for name, make, seeds in makers]


def spreads_section(splits) -> list[dict]:
    """Section 8: the relative spread of the learned detector's flattened input, per set of faces,
    and how often the stretch and the lowered contrast floor act (read from each extraction's
    ``face_contrast`` record; for the training faces, the spread as training computes it)."""
    import cv2

    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.learned import flattened
    from rockmass.imaging.vectorize import face_levels
    from rockmass.imaging.synthetic import in_flat_light, synthetic_face
    from rockmass.imaging.synthetic_field import field_face
    from rockmass.imaging.train_pixel_model import training_faces

    params = ExtractParams(detector="learned")

    def row(name, spreads, records=None) -> dict:
        s = np.asarray(spreads)
        out = {"faces": name, "n": int(s.size), "min": float(s.min()), "median": float(np.median(s)),
               "max": float(s.max()), "stretched": "-", "floor_lowered": "-", "floor_min": None}
        if records is not None:
            floors = np.array([r["contrast_floor"] for r in records])
            out.update(stretched=str(sum(r["stretch"] > 1.0 for r in records)),
                       floor_lowered=str(int(np.sum(floors < params.resolved("min_trace_contrast")))),
                       floor_min=float(floors.min()))
        return out

    def extracted(name, faces) -> dict:  # faces: (image, m_per_px) pairs
        records = [extract(image, m_per_px=scale, params=params).face_contrast for image, scale in faces]
        return row(name, [r["spread"] for r in records], records)

    training = [face_levels(flattened(image.astype(np.float32) / 255.0)).spread
                for _, image, _, _ in training_faces(10_000, 80, 20)]
    rows = [row("training faces of the shipped model (80 field-like, 20 plain)", training)]
    for split in splits:
        if (DATA / split / "images").is_dir():
            rows.append(extracted(f"real {split}/", [
                (np.ascontiguousarray(cv2.imread(str(p), cv2.IMREAD_COLOR)[..., ::-1]), 1.0)
                for p, _ in real_pairs(split)]))
    makers = (("moderate", lambda s: synthetic_face("moderate", seed=s, shape_px=(1000, 1500),
                                                    m_per_px=0.008)),
              ("moderate in flat light (x 0.35)", lambda s: in_flat_light(synthetic_face(
                  "moderate", seed=s, shape_px=(1000, 1500), m_per_px=0.008), 0.35)),
              ("hard", lambda s: synthetic_face("hard", seed=s, shape_px=(1000, 1500), m_per_px=0.008)),
              ("field-like", lambda s: field_face(seed=s, shape_px=(1000, 1500), m_per_px=0.008)))
    for name, make in makers:
        faces = [make(seed) for seed in (1, 2, 3)]
        rows.append(extracted(f"synthetic {name}, seeds 1-3", [(f.image, f.m_per_px) for f in faces]))
    return rows


def stage_recall(make, seeds) -> dict:
    """Section 7: the share of the truth's centre-line length within 3 px of each stage's pixels
    (learned detector, defaults), summed over ``seeds``; and the final traces' precision."""
    import cv2

    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.metrics import raster_counts, render_traces

    params = ExtractParams(detector="learned")
    stages = ("probability >= prob_low", "hysteresis mask", "skeleton", "pruned graph", "traces")
    counts = np.zeros((len(stages), 4))  # raster_counts of each stage against the truth
    for seed in seeds:
        face = make(seed)
        result = extract(face.image, m_per_px=face.m_per_px, params=params, debug=True)
        truth = render_traces(face.truth, face.image.shape, face.m_per_px)
        masks = (result.debug["joint_probability"] >= params.prob_low, result.debug["binary"],
                 result.debug["skeleton"], result.debug["pruned"],
                 render_traces(result.traces, face.image.shape, face.m_per_px))
        for k, mask in enumerate(masks):
            mask = np.asarray(mask, dtype=np.uint8)
            if mask.shape != truth.shape:  # the working grid, when the face was down-sampled
                mask = cv2.resize(mask, truth.shape[::-1], interpolation=cv2.INTER_NEAREST)
            counts[k] += raster_counts(mask, truth, tolerance_px=3.0)
    recall = counts[:, 2] / np.maximum(counts[:, 3], 1)
    return {**{name: float(r) for name, r in zip(stages, recall)},
            "precision": float(counts[-1, 0] / max(counts[-1, 1], 1))}


def _weighted_median(values, weights) -> float:
    """The value below which half the total weight lies."""
    order = np.argsort(values)
    cumulative = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def score_synthetic(make_face, seeds, params, min_joint_score=None) -> dict:
    """Mean buffered scores (3 px) and dP21 of one setting over synthetic faces (of the traces whose
    joint score reaches ``min_joint_score``, when given)."""
    from rockmass.imaging.extract import extract
    from rockmass.imaging.metrics import trace_accuracy

    rows = []
    for seed in seeds:
        face = make_face(seed)
        t0 = time.perf_counter()
        result = extract(face.image, m_per_px=face.m_per_px, params=params)
        elapsed = time.perf_counter() - t0
        acc = trace_accuracy(confident(result.traces, min_joint_score), face.truth,
                             m_per_px=face.m_per_px / result.scale.work_factor)
        rows.append((acc.f1, acc.precision, acc.recall, 100 * acc.p21_rel_error,
                     100 * acc.p20_rel_error, elapsed))
    f1, p, r, dp21, dp20, t = np.mean(rows, axis=0)
    return {"F1": f1, "P": p, "R": r, "dP21_%": dp21, "dP20_%": dp20, "time_s": t}


def trace_ordering(pairs, params, joint_width_px: float) -> dict:
    """How well each per-trace attribute orders the traces: the probability that a random true
    trace ranks above a random false one (ties count half), each trace weighted by its drawn length
    (a true trace has at least half its pixels within the tolerance of a label; 0.5 is chance)."""
    from rockmass.imaging.train_trace_score import trace_labels

    keys = ("joint_score", "confidence", "contrast", "length")
    values, true, weight = {k: [] for k in keys}, [], []
    for image_path, label_path in pairs:
        truth = label_skeleton(label_path)
        traces, _ = _extract_real(image_path, truth.shape, params, joint_width_px, 1.0)
        labels, pixels = trace_labels(traces, truth, 1.0, tolerance_px=TOLERANCE_PX)
        drawn = pixels > 0
        true.append(labels[drawn] > 0.5)
        weight.append(pixels[drawn])
        for k in keys:
            column = traces.lengths_m() if k == "length" else traces.attributes[k]
            values[k].append(np.asarray(column, dtype=float)[drawn])
    true, weight = np.concatenate(true), np.concatenate(weight).astype(float)
    return {k: pairwise_order(np.concatenate(values[k]), true, weight) for k in keys}


def pairwise_order(score, true, weight) -> float:
    """Weighted P(score of a true item > score of a false one), ties counting half (NaN when one
    class is empty)."""
    if true.all() or not true.any():
        return float("nan")
    s_false, w_false = score[~true], weight[~true]
    order = np.argsort(s_false)
    s_sorted, w_cum = s_false[order], np.concatenate([[0.0], np.cumsum(w_false[order])])
    below = w_cum[np.searchsorted(s_sorted, score[true], side="left")]
    up_to = w_cum[np.searchsorted(s_sorted, score[true], side="right")]
    wins = (below + 0.5 * (up_to - below)) * weight[true]
    return float(wins.sum() / (weight[true].sum() * w_false.sum()))


def main(argv=None) -> int:
    import cv2

    from rockmass.imaging.extract import ExtractParams, extract
    from rockmass.imaging.learned import MODEL_FILE
    from rockmass.imaging.synthetic import in_flat_light, synthetic_face
    from rockmass.imaging.trace_score import LOW_SCORE

    cv2.setNumThreads(1)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="12 real images, one synthetic seed")
    parser.add_argument("--detectors", default="ridge,learned,auto",
                        help="comma-separated ExtractParams.detector values (default all three)")
    parser.add_argument("--stages-only", action="store_true",
                        help="section 7 only: the joints' length each stage of the learned chain keeps")
    parser.add_argument("--spreads-only", action="store_true",
                        help="section 8 only: faces of low contrast, the stretch and the floor")
    parser.add_argument("--agreement-only", action="store_true",
                        help="section 6 only: the two detectors' agreement, by which 'auto' keeps one")
    parser.add_argument("--splits", default="val,train",
                        help="comma-separated folders of the labelled set (default val,train)")
    parser.add_argument("--no-synthetic", action="store_true", help="real images only")
    parser.add_argument("--no-settings", action="store_true",
                        help="real images at the defaults only (not the other learned settings)")
    parser.add_argument("--upsampled", default="",
                        help="comma-separated enlargements of the val/ photos for section 5 "
                             "(e.g. 2,4); default: no section 5")
    parser.add_argument("--face-masks", default="",
                        help="comma-separated ExtractParams.face_mask modes to compare on the real "
                             "faces (full, border, off); default: the default mode only")
    args = parser.parse_args(argv)
    detectors = [d.strip() for d in args.detectors.split(",") if d.strip()]
    splits = [d.strip() for d in args.splits.split(",") if d.strip()]
    masks = [m.strip() for m in args.face_masks.split(",") if m.strip()]
    if args.stages_only:
        print(header("where the learned detector loses the joints, stage by stage"))
        rows = stages_section()
        print("\n7. share of the true centre lines' length within 3 px of each stage (learned "
              "detector, defaults), and the traces' precision at 3 px")
        print(table(rows, [("faces", "s"), ("probability >= prob_low", ".2f"),
                           ("hysteresis mask", ".2f"), ("skeleton", ".2f"), ("pruned graph", ".2f"),
                           ("traces", ".2f"), ("precision", ".2f")]))
        path = save("bench_imaging_real_stages", {"stages": rows})
        print(f"\nrows saved to {path}")
        return 0
    if args.spreads_only:
        print(header("faces of low contrast: the learned detector's stretch and contrast floor"))
        rows = spreads_section(splits)
        print(f"\n8. relative spread s = 1.4826 MAD / median of the flattened face; stretched: s < "
              f"min_face_spread ({ExtractParams().min_face_spread:g}); floor_lowered: faces on which the "
              f"learned detector's contrast floor was lowered (face_contrast_share)")
        print(table(rows, [("faces", "s"), ("n", "d"), ("min", ".3f"), ("median", ".3f"),
                           ("max", ".3f"), ("stretched", "s"), ("floor_lowered", "s")]))
        path = save("bench_imaging_real_spreads", {"spreads": rows})
        print(f"\nrows saved to {path}")
        return 0
    if args.agreement_only:
        print(header("the ridge and learned detectors' agreement (ExtractParams.detector = 'auto')"))
        rows, crossed = agreement_section(splits, args.quick)
        _print_agreement(rows, crossed)
        path = save("bench_imaging_real_agreement" + ("_quick" if args.quick else ""),
                    {"data": str(DATA), "agreement": rows, "ridge_kept_on_field_faces": crossed})
        print(f"\nrows saved to {path}")
        return 0

    print(header("photo -> traces on real labelled faces and synthetic faces"))
    print(f"learned model: {MODEL_FILE.name}, {MODEL_FILE.stat().st_size} bytes")
    payload: dict = {"data": str(DATA), "tolerance_px": TOLERANCE_PX, "real": [], "synthetic": []}
    settings = ([("defaults", {})] if not masks else
                [(f"face_mask={m}" + (" (default)" if m == ExtractParams().face_mask else ""),
                  {"face_mask": m}) for m in masks])
    for split in splits:
        pairs = real_pairs(split) if (DATA / split / "images").is_dir() else []
        if not pairs:
            print(f"\n1. real faces: skipped, no labelled images at {DATA / split} "
                  "(set ROCKMASS_REAL_DATA to a copy of rock-face-fractures)")
            continue
        pairs = pairs[:12] if args.quick else pairs
        rows = []
        order_rows = []
        for detector in detectors:
            extra_settings = LEARNED_SETTINGS if detector == "learned" and not args.no_settings else ()
            for label, extra in (*settings, *extra_settings):
                row = score_real(pairs, detector_params(detector, **extra), 3.0)
                rows.append({"split": split, "detector": detector, "setting": label, **row})
            row = score_real(pairs, detector_params(detector), 3.0, min_joint_score=LOW_SCORE)
            rows.append({"split": split, "detector": detector,
                         "setting": f"defaults, joint score >= {LOW_SCORE:g}", **row})
            order_rows.append({"split": split, "detector": detector,
                               **trace_ordering(pairs, detector_params(detector), 3.0)})
        role = ("only measured, never tuned on" if split == "val"
                else "the learned detector's settings were chosen here")
        print(f"\n1. real faces: {DATA / split} ({len(pairs)} images, {role}; labels skeletonised, "
              f"{TOLERANCE_PX:g} px tolerance, joint width 3 px; F1, P, R are means over images)")
        print(table(rows, REAL_COLUMNS))
        payload["real"] += rows
        print(f"\n1b. {split}/: how well each trace attribute orders true above false traces "
              "(length-weighted; 0.5 = chance), detector defaults")
        print(table(order_rows, [("split", "s"), ("detector", "s"), ("joint_score", ".3f"),
                                 ("confidence", ".3f"), ("contrast", ".3f"), ("length", ".3f")]))
        payload.setdefault("ordering", []).extend(order_rows)

    if not args.no_synthetic:
        from rockmass.imaging.synthetic_field import TUNNEL_STYLE, field_face

        seeds = [1] if args.quick else [1, 2, 3]
        makers = {"moderate (synthetic_face)":
                  lambda s: synthetic_face("moderate", seed=s, shape_px=(1000, 1500), m_per_px=0.008),
                  "moderate in flat light (grey levels x 0.35 about the median)":
                  lambda s: in_flat_light(synthetic_face("moderate", seed=s, shape_px=(1000, 1500),
                                                         m_per_px=0.008), 0.35),
                  "hard (synthetic_face)":
                  lambda s: synthetic_face("hard", seed=s, shape_px=(1000, 1500), m_per_px=0.008),
                  "field-like (field_face)":
                  lambda s: field_face(seed=s, shape_px=(1000, 1500), m_per_px=0.008),
                  "tunnel (field_face, TUNNEL_STYLE: half-casts, shotcrete)":
                  lambda s: field_face(seed=s, shape_px=(1000, 1500), m_per_px=0.008,
                                       style=TUNNEL_STYLE)}
        rows = []
        for name, make in makers.items():
            for detector in detectors:
                for mode in masks or [None]:
                    label = detector if mode is None else f"{detector}, face_mask={mode}"
                    extra = {} if mode is None else {"face_mask": mode}
                    rows.append({"detector": label, "faces": f"{name}, seeds {seeds}",
                                 **score_synthetic(make, seeds, detector_params(detector, **extra))})
                rows.append({"detector": f"{detector}, joint score >= {LOW_SCORE:g}",
                             "faces": f"{name}, seeds {seeds}",
                             **score_synthetic(make, seeds, detector_params(detector),
                                               min_joint_score=LOW_SCORE)})
                if detector == "learned" and not args.no_settings:
                    for label, extra in SYNTHETIC_SETTINGS:
                        rows.append({"detector": f"learned, {label}", "faces": f"{name}, seeds {seeds}",
                                     **score_synthetic(make, seeds,
                                                       detector_params(detector, **extra))})
        print("\n2. synthetic faces (1000 x 1500 px; buffered F1 at 3 px, means over seeds)")
        print(table(rows, SYNTH_COLUMNS))
        payload["synthetic"] = rows
    if not args.quick:

        face = synthetic_face("moderate", seed=1, shape_px=(3000, 4000), m_per_px=0.003)
        rows = []
        for detector in detectors:
            t0 = time.perf_counter()
            extract(face.image, m_per_px=face.m_per_px, params=detector_params(detector))
            elapsed = time.perf_counter() - t0
            rows.append({"detector": detector, "MP": face.image.size / 1e6, "time_s": elapsed,
                         "MP_per_s": face.image.size / 1e6 / elapsed})
        print("\n3. throughput (12 MP moderate face, down-sampled to 4 MP; one core, and for "
              "auto a second thread running the ridge chain beside the learned one)")
        print(table(rows, [("detector", "s"), ("MP", ".1f"), ("time_s", ".2f"), ("MP_per_s", ".2f")]))
        payload["throughput"] = rows
    if masks:
        from rockmass.imaging.face_mask import face_mask

        grey = synthetic_face("moderate", seed=1, shape_px=(3000, 4000), m_per_px=0.003).image
        rgb = np.clip(np.stack([grey * 1.05, grey, grey * 0.9], axis=2) * 255, 0, 255).astype(np.uint8)
        rows = []
        for mode in [m for m in masks if m != "off"]:
            times = []
            for _ in range(5):
                t0 = time.perf_counter()
                face_mask(rgb, mode=mode)
                times.append(time.perf_counter() - t0)
            rows.append({"mode": mode, "MP": rgb.shape[0] * rgb.shape[1] / 1e6, "time_s": min(times)})
        print("\n4. face mask alone (12 MP RGB, best of 5; one core)")
        print(table(rows, [("mode", "s"), ("MP", ".1f"), ("time_s", ".3f")]))
        payload["face_mask_time"] = rows
    enlargements = [float(f) for f in args.upsampled.split(",") if f.strip()]
    if enlargements:
        rows = []
        for split in [s for s in splits if (DATA / s / "images").is_dir()]:
            pairs = real_pairs(split)[:12] if args.quick else real_pairs(split)
            for detector in detectors:
                variants = [("", {})] + ([("working grid only", {"learned_levels": ()})]
                                         if detector == "learned" else [])
                for factor in [1.0, *enlargements]:
                    for width in ([None] if factor == 1.0 else [None, 3.0 * factor]):
                        for label, extra in variants:
                            row = score_real(pairs, detector_params(detector, **extra), width,
                                             upsample=factor)
                            rows.append({"split": split, "detector": f"{detector}, {label}"
                                         if label else detector, "enlarged": factor,
                                         "joint_width_px": "default" if width is None else f"{width:g}",
                                         **row})
        print(f"\n5. the real photos enlarged (bicubic; labels with them, tolerance {TOLERANCE_PX:g} px "
              "x the enlargement): the same scenes at more pixels, the joint width not given or given "
              "in proportion; the learned detector also on the working grid alone (learned_levels "
              "= []); band_px = length-weighted median band width of the traces")
        print(table(rows, [("split", "s"), ("detector", "s"), ("enlarged", "g"),
                           ("joint_width_px", "s"), ("F1", ".3f"), ("P", ".3f"), ("R", ".3f"),
                           ("dP21_pct", "+.0f"), ("band_px", ".1f"), ("s_per_image", ".2f")]))
        payload["enlarged"] = rows
    if "auto" in detectors:
        payload["agreement"], payload["ridge_kept_on_field_faces"] = agreement_section(splits, args.quick)
        _print_agreement(payload["agreement"], payload["ridge_kept_on_field_faces"])
    suffix = "_face_mask" if masks else "_enlarged" if enlargements else ""
    path = save(("bench_imaging_real_quick" if args.quick else "bench_imaging_real") + suffix, payload)
    print(f"\nrows saved to {path}")
    return 0


def _print_agreement(rows, crossed) -> None:
    from rockmass.imaging.extract import ExtractParams

    print(f"\n6. agreement of the two detectors: share of the ridge traces' length within 5 px of "
          f"the learned traces; 'auto' keeps the ridge traces above "
          f"{ExtractParams().auto_agreement:g}")
    print(table(rows, [("photos", "s"), ("n", "d"), ("min", ".2f"), ("median", ".2f"),
                       ("max", ".2f"), ("ridge_kept", ".2f")]))
    if crossed:
        print("\n6b. field-like and tunnel-style faces on which 'auto' keeps the ridge traces: both "
              "detectors there (buffered F1 at 3 px, dP21)")
        print(table(crossed, [("faces", "s"), ("seed", "d"), ("agreement", ".2f"),
                              ("F1_learned", ".3f"), ("dP21_learned_%", "+.1f"), ("F1_ridge", ".3f"),
                              ("dP21_ridge_%", "+.1f")]))


if __name__ == "__main__":
    sys.exit(main())
