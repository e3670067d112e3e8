"""Extracted traces scored against a user's own hand-traced photographs (docs/imaging.md §3.5).

A site geologist who has traced the joints of a few face photographs can measure how well the
detector does on that site before trusting it on the rest, compare settings or a site model
(§3.2), and see where it goes wrong. Each photo is extracted, its traces drawn as 1-px lines on the
photo's grid, and compared with its label's centre lines (:mod:`rockmass.imaging.labels`) as the
benchmarks compare them (§8.1):

- precision P = share of the drawn pixels within ``tolerance_px`` of a labelled pixel, recall R =
  share of the labelled pixels within ``tolerance_px`` of a drawn one, F1 = 2PR / (P + R) (eqs.
  (8.5)-(8.6), :func:`rockmass.imaging.metrics.raster_counts`); the default tolerance is 5 px,
  as in the benchmarks of §8;
- ΔP21 = drawn / labelled line length − 1 (the pixel counts of 1-px lines);
- ΔP20 = number of traces / number of labelled traces − 1, the labelled traces being the label
  skeleton's branches chained straight through junctions (:func:`label_trace_count`).

Over a set of photos the scores are the means of the photos' F1, P and R, and the length error of
all the photos' lines together (:func:`rockmass.imaging.metrics.summarise_counts`), as §8 reports
them. A photo whose label marks nothing cannot be scored and is reported, not averaged in.

:func:`review_image` draws what went right and wrong on the photo: drawn pixels near a label in
green, drawn pixels far from any label (false traces) in red, labelled pixels far from any drawn
one (missed joints) in blue.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

__all__ = ["TOLERANCE_PX", "LABEL_MIN_TRACE_PX", "PhotoScore", "label_trace_count", "score_traces",
           "score_labelled_photos", "summarise_photo_scores", "review_image", "review_names"]

#: Matching tolerance, pixels of the photograph (the benchmarks' 5 px, docs/imaging.md §8.1).
TOLERANCE_PX = 5.0
#: A labelled trace shorter than this (pixels) is not counted in ΔP20.
LABEL_MIN_TRACE_PX = 10.0
#: Colours (RGB) of the review image: drawn near a label, drawn far from any, label missed.
REVIEW_COLOURS = {"matched": (40, 200, 60), "false": (230, 40, 40), "missed": (40, 110, 255)}


@dataclass(frozen=True)
class PhotoScore:
    """The scores of one labelled photograph.

    Attributes
    ----------
    photo, label : str
        The files.
    counts : tuple of int
        (drawn pixels near a label, drawn pixels, labelled pixels near a drawn one, labelled
        pixels): :func:`rockmass.imaging.metrics.raster_counts` of the 1-px lines.
    traces, labelled_traces : int
        Traces extracted; labelled traces (:func:`label_trace_count`).
    detector : str
        The detector whose traces were kept ("learned" or "ridge"; "auto" chooses per photo).
    seconds : float
        Run time of the extraction.
    """

    photo: str
    label: str
    counts: tuple[int, int, int, int]
    traces: int
    labelled_traces: int
    detector: str
    seconds: float

    @cached_property
    def _scores(self) -> dict:
        """:func:`rockmass.imaging.metrics.summarise_counts` of this one photo."""
        from .metrics import summarise_counts

        return summarise_counts([self.counts])

    @property
    def precision(self) -> float:
        """Share of drawn pixels within the tolerance of a label (NaN when nothing was drawn)."""
        return self._scores["P"]

    @property
    def recall(self) -> float:
        """Share of labelled pixels within the tolerance of a drawn one (NaN without a label)."""
        return self._scores["R"]

    @property
    def f1(self) -> float:
        """Harmonic mean of precision and recall; 0 when nothing was drawn."""
        return self._scores["F1"]

    @property
    def length_error_pct(self) -> float:
        """ΔP21: drawn / labelled line length − 1, % (NaN without a label)."""
        return self._scores["dP21_pct"] if self.counts[3] else float("nan")

    @property
    def count_error_pct(self) -> float:
        """ΔP20: traces / labelled traces − 1, % (NaN without a labelled trace)."""
        if not self.labelled_traces:
            return float("nan")
        return 100.0 * (self.traces / self.labelled_traces - 1.0)

    def to_dict(self) -> dict:
        """The scores as plain values (NaN where undefined)."""
        return {"photo": self.photo, "label": self.label, "F1": self.f1, "precision": self.precision,
                "recall": self.recall, "dP21_pct": self.length_error_pct,
                "dP20_pct": self.count_error_pct, "traces": self.traces,
                "labelled_traces": self.labelled_traces, "drawn_px": self.counts[1],
                "labelled_px": self.counts[3], "detector": self.detector, "seconds": self.seconds}


def label_trace_count(lines: np.ndarray, min_length_px: float = LABEL_MIN_TRACE_PX) -> int:
    """Number of labelled traces of a label's centre lines: the skeleton's branches, spurs under
    5 px pruned, chained straight through junctions as the extraction chains its traces (its
    default turn limit, :func:`rockmass.imaging.skeleton_graph.chain_traces`), those at least
    ``min_length_px`` long.

    Examples
    --------
    >>> lines = np.zeros((40, 40), bool); lines[20, 2:38] = True; lines[2:38, 20] = True
    >>> label_trace_count(lines)  # a cross: two straight traces through the junction
    2
    """
    from . import link, skeleton_graph
    from .extract import ExtractParams

    graph = skeleton_graph.prune_spurs(skeleton_graph.build_graph(np.asarray(lines, bool)), 5.0)
    chains = skeleton_graph.chain_traces(graph, max_turn_deg=ExtractParams().max_turn_deg)
    return sum(link.polyline_length_px(c) >= min_length_px for c in chains)


def score_traces(traces, lines: np.ndarray, *, m_per_px: float = 1.0,
                 tolerance_px: float = TOLERANCE_PX) -> tuple[tuple[int, int, int, int], np.ndarray]:
    """Compare a trace map with a label's centre lines on the photo's grid.

    Parameters
    ----------
    traces : TraceMap
        Traces in the photograph's frame (:func:`rockmass.imaging.extract`), in metres at
        ``m_per_px`` (pixels when the extraction had no scale: ``m_per_px`` = 1).
    lines : (H, W) bool array
        The label's centre lines at the photograph's size.
    m_per_px : float, default 1
        The scale the traces were extracted with.
    tolerance_px : float, default :data:`TOLERANCE_PX`
        Matching distance, pixels of the photograph.

    Returns
    -------
    counts : tuple of int
        :func:`rockmass.imaging.metrics.raster_counts` of the drawn traces against ``lines``.
    drawn : (H, W) bool array
        The traces drawn as 1-px lines.
    """
    from .metrics import raster_counts, render_traces

    drawn = render_traces(traces, lines.shape, m_per_px)
    return raster_counts(drawn, lines, tolerance_px=tolerance_px), drawn


def score_labelled_photos(pairs: Sequence[tuple], extract_photo: Callable, *,
                          tolerance_px: float = TOLERANCE_PX, on_photo: Callable | None = None,
                          read_lines: Callable | None = None) -> tuple[list[PhotoScore], list[str]]:
    """Extract and score each labelled photograph.

    Parameters
    ----------
    pairs : sequence of (photo path, label path)
        E.g. :func:`rockmass.imaging.labels.labelled_pairs`.
    extract_photo : callable
        ``extract_photo(path) -> (image, Extraction, m_per_px)``: reads the photo and extracts its
        traces with the caller's settings; ``m_per_px`` is the scale of the traces (1 for pixels).
    tolerance_px : float, default :data:`TOLERANCE_PX`
    on_photo : callable, optional
        Called as ``on_photo(score, image, drawn, lines)`` after each scored photo (review images,
        progress).
    read_lines : callable, optional
        ``read_lines(label, photo, photo_shape)``: the label's centre lines at the photo's size
        (default :func:`rockmass.imaging.labels.photo_centre_lines`).

    Returns
    -------
    scores : list of PhotoScore
        In the order of ``pairs``, photos with an empty label left out.
    skipped : list of str
        The photos whose label marks nothing.

    Raises
    ------
    ValueError
        A label of another size than its photograph (naming both).
    OSError
        A label that cannot be read.
    """
    from .labels import photo_centre_lines

    read_lines = read_lines or photo_centre_lines
    scores, skipped = [], []
    for photo, label in pairs:
        t0 = time.perf_counter()
        image, result, m_per_px = extract_photo(photo)
        seconds = time.perf_counter() - t0
        lines = read_lines(label, photo, image.shape)
        if not lines.any():
            skipped.append(str(photo))
            continue
        counts, drawn = score_traces(result.traces, lines, m_per_px=m_per_px,
                                     tolerance_px=tolerance_px)
        choice = result.detector_choice
        detector = choice["kept"] if choice else "learned" if result.detector_model else "ridge"
        score = PhotoScore(str(photo), str(label), tuple(int(c) for c in counts),
                           result.traces.n_traces, label_trace_count(lines), detector, seconds)
        scores.append(score)
        if on_photo is not None:
            on_photo(score, image, drawn, lines)
    return scores, skipped


def summarise_photo_scores(scores: Sequence[PhotoScore]) -> dict:
    """Scores over a set of photos: ``photos``; ``F1``, ``precision``, ``recall``: means over the
    photos (:func:`rockmass.imaging.metrics.summarise_counts`); ``F1_pooled``: F1 of all pixels
    together; ``dP21_pct``: drawn over labelled line length of all photos − 1; ``dP20_pct``: all
    traces over all labelled traces − 1; ``seconds``: total extraction time.

    Examples
    --------
    >>> a = PhotoScore("a.jpg", "a.png", (8, 10, 8, 8), 2, 2, "learned", 1.0)
    >>> b = PhotoScore("b.jpg", "b.png", (0, 0, 0, 4), 0, 1, "learned", 1.0)
    >>> s = summarise_photo_scores([a, b])
    >>> round(s["F1"], 3), s["recall"], round(s["dP21_pct"], 1), round(s["dP20_pct"], 1)
    (0.444, 0.5, -16.7, -33.3)
    """
    from .metrics import summarise_counts

    if not scores:
        raise ValueError("no photo was scored")
    summary = summarise_counts([s.counts for s in scores])
    traces = sum(s.traces for s in scores)
    labelled = sum(s.labelled_traces for s in scores)
    return {"photos": len(scores), "F1": summary["F1"], "precision": summary["P"],
            "recall": summary["R"], "F1_pooled": summary["F1_pooled"],
            "dP21_pct": summary["dP21_pct"],
            "dP20_pct": 100.0 * (traces / labelled - 1.0) if labelled else float("nan"),
            "seconds": float(sum(s.seconds for s in scores))}


def review_image(image: np.ndarray, drawn: np.ndarray, lines: np.ndarray, *,
                 tolerance_px: float = TOLERANCE_PX, line_px: int | None = None) -> np.ndarray:
    """The photograph, greyed and dimmed, with the drawn traces and the label coloured by whether
    they match (:data:`REVIEW_COLOURS`): drawn within ``tolerance_px`` of the label green, drawn
    farther red (false traces), label farther than ``tolerance_px`` from any drawn pixel blue
    (missed joints).

    Parameters
    ----------
    image : (H, W) or (H, W, 3) uint8 array
        The photograph (RGB).
    drawn, lines : (H, W) bool arrays
        The traces drawn as 1-px lines (:func:`score_traces`) and the label's centre lines.
    tolerance_px : float
    line_px : int, optional
        Thickness of the lines drawn (default: 1 px per 800 px of the photo's longer side, at
        least 1), so that they show on a large photograph.

    Returns
    -------
    (H, W, 3) uint8 array, RGB
    """
    import cv2

    from .metrics import matched_pixels

    drawn_near, lines_near = matched_pixels(drawn, lines, tolerance_px=tolerance_px)
    grey = image if image.ndim == 2 else cv2.cvtColor(np.ascontiguousarray(image[..., :3]),
                                                      cv2.COLOR_RGB2GRAY)
    out = np.repeat((0.55 * grey.astype(np.float32) + 40.0).astype(np.uint8)[..., None], 3, axis=2)
    width = line_px or max(1, round(max(grey.shape) / 800))
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * (width // 2) + 1,) * 2)
    layers = (("missed", lines & ~lines_near), ("false", drawn & ~drawn_near),
              ("matched", drawn_near))
    for name, mask in layers:  # matched last: where lines cross, the match shows
        thick = cv2.dilate(mask.astype(np.uint8), kernel) > 0 if width > 1 else mask
        out[thick] = REVIEW_COLOURS[name]
    return out


def review_names(photos: Sequence) -> dict[str, str]:
    """The file name each photo's review image is written under: its stem as PNG, or its whole
    name as PNG where two photos share a stem (``face.jpg``, ``face.tif``).

    Examples
    --------
    >>> review_names(["a/f1.jpg", "a/f2.jpg", "a/f2.tif"])
    {'a/f1.jpg': 'f1.png', 'a/f2.jpg': 'f2.jpg.png', 'a/f2.tif': 'f2.tif.png'}
    """
    stems = [Path(p).stem for p in photos]
    return {str(p): f"{Path(p).stem if stems.count(Path(p).stem) == 1 else Path(p).name}.png"
            for p in photos}
