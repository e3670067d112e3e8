"""Photo -> traces: the whole extraction chain behind one function, :func:`extract`.

Chain (docs/imaging.md §2-§7), each step in its own module:

===================  ================================================  ===========================
step                 what                                              module
===================  ================================================  ===========================
read, grey           Pillow + EXIF orientation; RGB(A), 8/16 bit        :mod:`.enhance`
down-sample          to at most ``max_megapixels`` (area averaging)     here
face mask            rock face against border, lining, sky, machinery   :mod:`.face_mask`
                     (``face_mask``; a ROI replaces it)
flatten              grey closing + wide Gaussian, divide              :mod:`.enhance`
ridges               Sato tubeness, σ from the joint width             :mod:`.ridges`
  or learned         per-pixel features -> probability of a joint       :mod:`.features`,
                     centre line (``detector="learned"``, §3.1)         :mod:`.learned`
segment              hysteresis (median + k MAD, or fixed levels on     :mod:`.segment`
                     the probability), ROI, small objects
skeleton, graph      Zhang–Suen, skan pixel graph                      :mod:`.skeleton_graph`
prune, X, bridge     spurs, X crossings, gaps (distance and angle)     :mod:`.skeleton_graph`
chain                straight-through chaining at junctions            :mod:`.skeleton_graph`
link, border         join pieces that continue one another (gaps,       :mod:`.link`
                     crossings left as two Y nodes); ends to the border
vectorise            Douglas–Peucker, metres on the face frame;         :mod:`.vectorize`
                     per-trace confidence (mean response along it)
===================  ================================================  ===========================

Pixel-valued parameters in :class:`ExtractParams` are in pixels of the *working* image (the image
after down-sampling; the input itself when it is small enough), because that is the grid the chain
runs on: so the defaults behave the same at any input size. They were chosen for a working grid of
at most :data:`REFERENCE_MEGAPIXELS`; when ``max_megapixels`` is raised and the working grid is
larger, every pixel length is multiplied by :func:`grid_scale` (areas by its square), so that they
keep their size on the face (docs/imaging.md §1). The expected joint width is 3 working pixels
(times the same scale) unless given, in input pixels (``joint_width_px``) or in metres
(``joint_width_m``).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from .frame import check_scale, rc_to_uv
from .vectorize import image_window_uv_m

__all__ = ["ExtractParams", "ScaleInfo", "Extraction", "extract", "scale_from_control_points",
           "infinities_as_text", "EVERY_JOINT", "NO_TRACE_FILTERS"]

#: Smallest image side the chain accepts, pixels.
MIN_SIDE_PX = 16
#: Line detectors in front of the threshold (``ExtractParams.detector``).
DETECTORS = ("ridge", "learned")
#: ``ExtractParams.detector`` that runs both and keeps one per photo (:func:`detector_agreement`).
AUTO = "auto"
#: The shipped model (:data:`rockmass.imaging.learned.SHIPPED_MODELS`) that "auto" also runs the
#: learned chain with, the convolutional network (:func:`network_length_ratio`, docs/imaging.md §3.6).
AUTO_NETWORK = "cnn"
#: ``ExtractParams.auto_network_ratio``'s default: the least network-to-pixel-model trace length
#: ratio at which "auto" keeps the network's traces, chosen on the real train/ photographs
#: (``benchmarks/bench_network_ratio.py``, docs/imaging.md §3.6).
AUTO_NETWORK_RATIO = 1.3
#: The trace filters off: no contrast floor, no band-width floor, traces from 20 px (the ridge
#: filter's floor): what the joint score is fitted on (:mod:`rockmass.imaging.train_trace_score`)
#: and what a map of every joint keeps (:data:`EVERY_JOINT`).
NO_TRACE_FILTERS = MappingProxyType({"min_trace_contrast": float("-inf"), "min_trace_width": 0.0,
                                     "min_trace_length_px": 20.0})
#: Settings of a map of every joint the photograph shows, hairlines too (``rockmass extract
#: --joints all``, docs/imaging.md §8.4): the convolutional network's chain (dark joints) with
#: the trace filters the defaults chose on hand labels of major fractures turned off.
#: ``ExtractParams(**EVERY_JOINT)``.
EVERY_JOINT = MappingProxyType({"detector": "learned", "pixel_model": AUTO_NETWORK,
                                "line_polarity": "dark", **NO_TRACE_FILTERS})
#: ``Extraction.debug`` name of each chain's response.
_RESPONSE_NAMES = {"ridge": "ridge_response", "learned": "joint_probability",
                   AUTO_NETWORK: "network_probability"}
#: Distance (pixels of a working grid of :data:`REFERENCE_MEGAPIXELS`) within which a ridge trace
#: pixel counts as found by the learned detector too (:func:`detector_agreement`): the
#: tolerance the real labelled photographs are scored at.
AGREEMENT_RADIUS_PX = 5.0
#: Size of the working grid, megapixels, that the pixel-valued defaults were chosen for (the
#: default ``max_megapixels``). A larger working grid scales them by :func:`grid_scale`.
REFERENCE_MEGAPIXELS = 4.0
#: Expected joint width when none is given, pixels of a working grid of at most
#: :data:`REFERENCE_MEGAPIXELS`.
DEFAULT_JOINT_WIDTH_PX = 3.0
#: Settings of :class:`ExtractParams` that are lengths on the working grid, pixels (scaled by
#: :func:`grid_scale`). ``min_sigma_px`` is not: it is the finest scale the grid resolves.
PIXEL_LENGTHS = ("background_sigma_px", "spur_length_px", "crossing_link_px", "bridge_distance_px",
                 "tangent_skip_px", "tangent_reach_px", "link_gap_px", "link_offset_px",
                 "link_skip_px", "link_reach_px", "border_extend_px", "min_trace_length_px",
                 "simplify_tolerance_px")
#: Settings that are areas on the working grid, pixels (scaled by the square of :func:`grid_scale`).
PIXEL_AREAS = ("min_object_px", "fill_holes_px")


#: Defaults of the settings that are None unless given, per detector (a None here: no filter). The
#: learned detector's were chosen on the real training photographs (see ExtractParams).
DETECTOR_DEFAULTS = MappingProxyType({
    "fill_holes_px": MappingProxyType({"ridge": 0, "learned": 400}),
    "min_trace_length_px": MappingProxyType({"ridge": 20.0, "learned": 70.0}),
    "min_trace_contrast": MappingProxyType({"ridge": None, "learned": 0.25}),
    "face_contrast_share": MappingProxyType({"ridge": None, "learned": 0.8}),
    "min_trace_width": MappingProxyType({"ridge": None, "learned": 1.0}),
})


@dataclass(frozen=True)
class ExtractParams:
    """Every setting of the extraction chain, with the default it was tuned to.

    Defaults were tuned on synthetic faces of :func:`rockmass.imaging.synthetic_face` (seeds 100 and
    up, all three difficulties; tests use other seeds): see ``benchmarks/bench_imaging_extract.py``.
    Pixel values are on the working grid (see the module notes).

    Attributes
    ----------
    max_megapixels : float, default 4.0
        Larger images are down-sampled (area averaging) to this many pixels before anything else;
        24 MP then runs in a few seconds and < 1 GB. ``inf`` processes at full resolution.
    detector : {"auto", "learned", "ridge"} or None, default None
        What finds the joint pixels. None: "auto"; "ridge" when ``line_polarity`` is "bright";
        "learned" when a ``pixel_model`` is given (a model trained on the user's own photographs
        is trusted as it is).
        "auto": both detectors run and one is kept per photo: the ridge filter's traces when the
        photo is clean, i.e. when at least ``auto_agreement`` of their length lies within 5 px of
        the learned detector's traces, else the learned detector's (:func:`detector_agreement`,
        docs/imaging.md §3.3): the pixel model's, or the convolutional network's where it finds
        clearly more joint length (``auto_network_ratio``, §3.6). "learned": the shipped pixel
        classifier (:mod:`rockmass.imaging.learned`, docs/imaging.md §3.1), trained on synthetic
        faces only, whose probability of "joint centre line" is thresholded by ``prob_low`` /
        ``prob_high`` and whose traces are then filtered by length, contrast and width
        (``min_trace_length_px``, ``min_trace_contrast``, ``min_trace_width``); it ignores
        ``flatten_method``, ``clahe``, the filter scales and ``low_k`` / ``high_k``, and looks for
        dark joints of about 2-12 px (it refuses ``line_polarity = "bright"``). "ridge": Sato's
        multi-scale ridge filter with robust hysteresis thresholds (docs/imaging.md §3-§4; tuned on
        the plain synthetic faces), for bright joints, and for clean images whose faint hairlines
        count as joints. On the real labelled photographs (``val/``) the learned detector scores
        F1 0.903 against the ridge filter's 0.338 ("auto" 0.895); on the plain synthetic faces,
        whose truth includes every faint line, 0.830 against 0.971 ("auto" 0.971)
        (``benchmarks/bench_imaging_real.py``, docs/imaging.md §8.1).
    auto_agreement : float, default 0.55
        With ``detector = "auto"``: the share of the ridge filter's trace length that must lie
        within 5 px of the learned detector's traces for its traces to be kept. Chosen between
        the largest share among the 99 real training photographs of rock-face-fractures (0.42;
        the ridge filter draws several times their labelled length there) and the smallest on
        plain synthetic faces (0.61), whose thin faint lines the learned detector misses
        (``benchmarks/bench_imaging_real.py``, section 6). 1 keeps the learned traces always.
    auto_network_ratio : float, default 1.3
        With ``detector = "auto"`` and no ``pixel_model``: "auto" also runs the learned chain with
        the shipped convolutional network (``pixel_model = "cnn"``, docs/imaging.md §3.6) and
        keeps its traces instead of the pixel model's when their total length is at least this
        many times the pixel model's (:func:`network_length_ratio`); never instead of the ridge
        filter's. :data:`AUTO_NETWORK_RATIO` is the value chosen on the 99 real training
        photographs of rock-face-fractures, as the smallest at which the network costs their
        labels nothing, and measured on joints drawn over the same photographs
        (``benchmarks/bench_network_ratio.py``). The network runs only where "auto" keeps the
        pixel model's traces (there it adds 1-3 s to a 12-24 MP photo); ``inf`` never runs it
        (the two-detector "auto" of §3.3).
    line_polarity : {"dark", "bright"}, default "dark"
        Joints to look for: dark lines (open joints, shadowed traces) or bright ones (calcite- or
        clay-filled joints, veins, mortar). On ``skimage.data.brick()`` "dark" traces the brick
        edges on both sides of every mortar joint; "bright" traces the joints themselves, given
        their width (``joint_width_px`` ≈ 8): with the default 3 px the filter resolves the two
        bright rims of the recessed, shadow-centred joints on the right of the photo as separate
        lines and fragments them (vertical joints crossed per row, right third: 9.1 against 4.8
        bright intensity peaks in the photo; 4.9 at 8 px).
    flatten_method : {"divide", "subtract", "none"}, default "divide"
        Illumination flattening (:func:`rockmass.imaging.enhance.flatten_illumination`).
    background_sigma_px : float, default 40.0
        Scale of the illumination removed, pixels.
    clahe : bool, default False
        Contrast-limited adaptive histogram equalisation after flattening.
    clahe_clip_limit : float, default 0.01
    n_scales : int, default 3
        Ridge filter scales (:func:`rockmass.imaging.ridges.ridge_sigmas`).
    scale_spread : float, default 2.0
        Largest / smallest scale.
    min_sigma_px : float, default 1.0
        Smallest filter scale, pixels.
    low_k, high_k : float, default 1.5, 4.0
        Hysteresis thresholds in robust standard deviations (1.4826 MAD) above the median response.
        Tuned: (2, 5) loses faint stretches (moderate recall 0.93, P21 -11 %); (1, 4) lets texture
        in (moderate precision 0.965, hard P20 +54 %).
    prob_low, prob_high : float, default 0.8, 0.97
        Hysteresis thresholds on the learned detector's probability. Chosen on the real training
        photographs (rock-face-fractures ``train/``, 99 images, never on ``val/``) together with
        the trace filters below (``fill_holes_px``, ``min_trace_contrast``, ``min_trace_width``,
        ``min_trace_length_px``); see those. The synthetic training faces leave the model
        over-confident on real rock texture, hence the high values.
    min_face_spread : float, default 0.075
        The learned detector's input, the flattened face, is stretched about its median when its
        relative spread (1.4826 MAD / median) is under this, to this spread, at most 10 times
        (:func:`rockmass.imaging.learned.stretch_flat_face`): the same face in flatter light
        then gives the model the input it gives in ordinary light. 0.075 is the spread of the
        plain synthetic "moderate" faces, the flattest on which the model is measured
        (:data:`rockmass.imaging.learned.MIN_SPREAD`); 0 turns the stretch off (a smooth face
        whose low spread is its rock, not its light). Trace contrasts are measured on the face
        as it is (``face_contrast_share`` makes the floor follow its contrast); the factor is in
        ``Extraction.face_contrast``.
    min_object_px : int, default 40
        Smallest connected piece of the binary mask kept, pixels.
    fill_holes_px : int or None, default None
        Holes of the binary mask smaller than this (pixels, not touching the border) are filled
        before thinning (:func:`rockmass.imaging.segment.fill_holes`): a wide dark band cut by a
        brighter speck otherwise thins into a loop of two parallel traces. None: 400 px with the
        learned detector, 0 (off) with the ridge detector.
    spur_length_px : float, default 10.0
        End branches at junctions shorter than this are pruned (iteratively).
    crossing_link_px : float, default 10.0
        Two Y nodes joined by a branch up to this long are merged into an X when their branches
        pair into two straight lines.
    max_turn_deg : float, default 35.0
        A trace continues through a junction along a pair of branches turning by at most this.
    bridge_distance_px : float, default 25.0
        Longest gap between two line ends that is bridged.
    bridge_angle_deg : float, default 20.0
        Both end tangents must lie within this angle of the gap direction.
    tangent_skip_px, tangent_reach_px : float, default 2.0, 12.0
        Branch directions are measured between these arc lengths from the branch end.
    link_gap_px : float, default 50.0
        After chaining, two trace ends up to this far apart are joined when the pieces continue one
        another (:func:`rockmass.imaging.link.link_traces`): across hidden stretches longer than
        ``bridge_distance_px``, and through crossings the skeleton left as two Y nodes. 0 turns
        linking off. Tuned on moderate faces, seeds 100-102: without linking dP20 +19.5 %,
        node-count error 0.43; with it -2.1 % and 0.20, F1 0.976 -> 0.978, dP21 -5.0 -> -2.5 %;
        40 or 80 px change dP20 by about 1 % either way.
    link_turn_deg : float, default 15.0
        The two end tangents must be anti-parallel within this angle.
    link_offset_px : float, default 5.0
        Largest sideways offset between the two pieces' tangent lines (3 px misses wiggly traces
        across long gaps: dP20 +3.4 %, node error 0.24; 6 px gains nothing more).
    link_skip_px, link_reach_px : float, default 6.0, 25.0
        End tangents for linking are measured between these arc lengths from each end, past the
        hook a skeleton end makes into a junction or a gap's rounded edge (2 / 12 px: dP20 +5.6 %,
        node error 0.24).
    border_extend_px : float, default 12.0
        Trace ends that stop within this distance of the image border, pointing at it (within
        45° of its normal), are extended to it (the ridge filter fades near the border); 0 turns
        this off. The width of the face mask's border band (``face_mask``) is added to it.
    min_trace_length_px : float or None, default None
        Traces shorter than this (after linking) are dropped; None: 20 px with the ridge detector,
        70 px with the learned one (see ``min_trace_contrast``).
    min_trace_contrast : float or None, default None
        Traces whose mean grey level on the flattened image (sampled along the trace) is not at
        least this fraction below the face's median flattened grey level are dropped (the
        ``contrast`` attribute of a trace: 1 - mean / median; 0.25 = a quarter darker). None:
        0.25 with the learned detector, no filter with the ridge detector; ``-inf`` turns it off.
        On a face of low contrast the learned detector lowers it (``face_contrast_share``).
    face_contrast_share : float or None, default None
        On a face of low contrast the floor ``min_trace_contrast`` is lowered to this share of
        the face's own contrast C = 1 - q5(I) / med(I) (how much darker than the median the
        darkest 5 % of the flattened face are, :func:`rockmass.imaging.vectorize.face_levels`),
        when that is lower: on a face whose joints are all faint against its rock, a fixed floor
        drops them all. None: 0.8 with the learned detector, no lowering with the ridge detector;
        ``inf`` keeps the fixed floor, 0 lowers it to 0 on every face. Chosen on ``train/`` and
        the synthetic tuning faces (docs/imaging.md §3.1, "Faces of low contrast"). A face flatter
        overall, as in flat light, is first stretched
        (:func:`rockmass.imaging.learned.stretch_flat_face`).
    min_trace_width : float or None, default None
        Traces along which the binary mask is on average narrower than this many expected joint
        widths (``joint_width_px`` of :func:`extract`, scaled to the working grid; the mask's
        width is twice the distance from the trace to its edge, sampled along the trace) are
        dropped. None: 1.0 with the learned detector (3 px at the default joint width and full
        resolution), no filter with the ridge detector; 0 turns it off.

        These three trace filters and ``prob_low`` were chosen together on the real training
        photographs (rock-face-fractures ``train/``, 99 images, never ``val/``), by F1 among the
        settings whose trace length error there is within 15 %: F1 0.680, dP21 +13.6 % there
        (0.634, +43 % before). How well each tells a trace mostly within 5 px of a label from the
        others on ``train/`` (share of length-weighted pairs ordered right, 0.5 = chance): length
        0.85, contrast 0.84, width 0.79, mean probability 0.62. Neighbouring settings are listed
        in docs/imaging.md §3.1; ``benchmarks/bench_imaging_real.py`` measures the steps.
    simplify_tolerance_px : float, default 1.0
        Douglas–Peucker tolerance.
    face_mask : {"border", "full", "off"}, default "border"
        Where candidate joint pixels may lie (:mod:`rockmass.imaging.face_mask`, docs/imaging.md
        §2.1): "border" leaves out a band along the image border (1 % of the short side; trace
        ends are still carried across it to the border, see ``border_extend_px``); "full" also
        finds the rock face, leaving out over-exposed regions, large smooth regions such as
        shotcrete, lining or sky, and large strongly coloured regions such as machinery, each with
        a margin; "off" uses the whole image. A ``roi`` given to :func:`extract` replaces
        the mask. Pixels outside it are never candidates; the thresholds are set from the pixels
        inside. With "full", when the cues leave out more than the border band, the sampling
        window becomes the face's outline. On the real labelled photographs (rock-face-fractures
        ``val/``, learned detector) "border" and "full" both take F1 from 0.887 to 0.895 (ridge
        0.331 -> 0.338); on the synthetic field-like faces "full" costs 0.014 (learned) and 0.012
        (ridge) of F1 against "border" (its margin around bright patches removes joints there),
        and on the plain synthetic faces the band costs 0.008 (0.978 -> 0.970, ridge)
        (``benchmarks/bench_imaging_real.py --face-masks``): hence "border" by default,
        "full" for photos showing lining, sky or machinery (docs/imaging.md §2.1).
    learned_levels : tuple of int, default (2, 4)
        The learned detector also runs on the working grid coarsened by each of these factors
        (those whose grid keeps 64 px a side), and the grid whose traces have the highest
        length-weighted mean ``joint_score`` is kept (:mod:`rockmass.imaging.grid_levels`,
        docs/imaging.md §3.4), provided they add up to at least 30 % of the working grid's
        trace length, or a coarser grid whose joint-like length (length times mean score) is
        three times the finer one's: its model knows joints a few pixels wide, and a photograph
        with more pixels per joint width shows them wide and soft. ``()`` runs the working grid
        only. Not run while the joint score is off (``trace_score.unscored``).
        Chosen on the real ``train/`` photographs, as they are and enlarged 2 and 4 times
        (``benchmarks/bench_imaging_real.py --upsampled 2,4``).
    pixel_model : str or None, default None
        The learned detector's model file: a pixel model (``.npz``) or a convolutional network
        (``.onnx``, docs/imaging.md §3.6); None: the pixel model shipped in the package
        (:data:`rockmass.imaging.learned.MODEL_FILE`); "mlp" or "cnn": the shipped pixel model or
        network. A model trained on the user's own labelled
        photographs by ``python -m rockmass.imaging.train_pixel_model --photos DIR --labels DIR``
        (docs/imaging.md §3.2); a relative path is taken from the working directory. The
        thresholds and trace filters above were chosen for the shipped pixel model.
    """

    max_megapixels: float = 4.0
    detector: str | None = None
    auto_agreement: float = 0.55
    auto_network_ratio: float = AUTO_NETWORK_RATIO
    line_polarity: str = "dark"
    flatten_method: str = "divide"
    background_sigma_px: float = 40.0
    clahe: bool = False
    clahe_clip_limit: float = 0.01
    n_scales: int = 3
    scale_spread: float = 2.0
    min_sigma_px: float = 1.0
    low_k: float = 1.5
    high_k: float = 4.0
    prob_low: float = 0.8
    prob_high: float = 0.97
    min_face_spread: float = 0.075
    min_object_px: int = 40
    fill_holes_px: int | None = None
    spur_length_px: float = 10.0
    crossing_link_px: float = 10.0
    max_turn_deg: float = 35.0
    bridge_distance_px: float = 25.0
    bridge_angle_deg: float = 20.0
    tangent_skip_px: float = 2.0
    tangent_reach_px: float = 12.0
    link_gap_px: float = 50.0
    link_turn_deg: float = 15.0
    link_offset_px: float = 5.0
    link_skip_px: float = 6.0
    link_reach_px: float = 25.0
    border_extend_px: float = 12.0
    min_trace_length_px: float | None = None
    min_trace_contrast: float | None = None
    face_contrast_share: float | None = None
    min_trace_width: float | None = None
    simplify_tolerance_px: float = 1.0
    face_mask: str = "border"
    learned_levels: tuple[int, ...] = (2, 4)
    pixel_model: str | None = None

    def __post_init__(self) -> None:
        if self.detector is None:  # the default: auto, except for bright joints and own models
            object.__setattr__(self, "detector", "ridge" if self.line_polarity == "bright"
                               else "learned" if self.pixel_model is not None else AUTO)
        if self.detector not in (AUTO, *DETECTORS):
            raise ValueError(f"params.detector must be one of {', '.join((AUTO, *DETECTORS))}, "
                             f"got {self.detector!r}")
        if self.detector != "ridge" and self.line_polarity == "bright":
            raise ValueError(f"params.line_polarity = 'bright' needs params.detector = 'ridge': the "
                             f"{self.detector} detector finds dark joints with the learned one")
        value = self.auto_agreement
        if not (isinstance(value, (int, float)) and 0 <= value <= 1):
            raise ValueError(f"params.auto_agreement must be a share in 0-1, got {value!r}")
        value = self.auto_network_ratio
        if not (isinstance(value, (int, float)) and value > 0):
            raise ValueError(f"params.auto_network_ratio must be a positive ratio (inf: never keep "
                             f"the network's traces), got {value!r}")
        from .face_mask import FACE_MASK_MODES

        if self.face_mask not in FACE_MASK_MODES:
            raise ValueError(f"params.face_mask must be one of {', '.join(FACE_MASK_MODES)}, "
                             f"got {self.face_mask!r}")
        if self.pixel_model is not None and self.detector == "ridge":
            raise ValueError(f"params.pixel_model ({self.pixel_model!r}) is the learned detector's "
                             f"model; params.detector is {self.detector!r}")
        if self.line_polarity not in ("dark", "bright"):
            raise ValueError(f"params.line_polarity must be 'dark' or 'bright', got {self.line_polarity!r}")
        positive = ("max_megapixels", "background_sigma_px", "scale_spread", "min_sigma_px",
                    "tangent_reach_px", "clahe_clip_limit", "link_reach_px")
        non_negative = ("low_k", "high_k", "spur_length_px", "crossing_link_px", "bridge_distance_px",
                        "tangent_skip_px", "min_trace_length_px", "simplify_tolerance_px",
                        "link_gap_px", "link_offset_px", "link_skip_px", "border_extend_px",
                        "min_trace_width")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and value > 0 and not np.isnan(value)):
                raise ValueError(f"params.{name} must be a number > 0, got {value!r}")
        for name in non_negative:
            value = getattr(self, name)
            if name in DETECTOR_DEFAULTS and value is None:
                continue
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
                raise ValueError(f"params.{name} must be a finite number >= 0, got {value!r}")
        for name in ("max_turn_deg", "bridge_angle_deg", "link_turn_deg"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and 0 <= value <= 90):
                raise ValueError(f"params.{name} must be an angle in 0-90 degrees, got {value!r}")
        value = self.min_face_spread
        if isinstance(value, bool) or not (isinstance(value, (int, float)) and np.isfinite(value)
                                           and 0 <= value < 1):
            raise ValueError(f"params.min_face_spread must be a number in [0, 1) (0: no stretch), "
                             f"got {value!r}")
        for name in ("prob_low", "prob_high"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and 0 <= value <= 1):
                raise ValueError(f"params.{name} must be a probability in 0-1, got {value!r}")
        if self.prob_low > self.prob_high:
            raise ValueError(f"params.prob_low ({self.prob_low}) must not exceed params.prob_high "
                             f"({self.prob_high})")
        if self.low_k > self.high_k:
            raise ValueError(f"params.low_k ({self.low_k}) must not exceed params.high_k ({self.high_k})")
        if not (isinstance(self.n_scales, int) and self.n_scales >= 1):
            raise ValueError(f"params.n_scales must be an integer >= 1, got {self.n_scales!r}")
        for name in ("min_object_px", "fill_holes_px"):
            value = getattr(self, name)
            if name in DETECTOR_DEFAULTS and value is None:
                continue
            if not (isinstance(value, int) and value >= 0):
                raise ValueError(f"params.{name} must be an integer >= 0, got {value!r}")
        value = self.min_trace_contrast
        if value is not None and not (isinstance(value, (int, float)) and value <= 1):
            raise ValueError(f"params.min_trace_contrast must be a number <= 1 (-inf: no filter), "
                             f"got {value!r}")
        value = self.face_contrast_share
        if value is not None and (isinstance(value, bool) or not (isinstance(value, (int, float))
                                                                  and value >= 0)):
            raise ValueError(f"params.face_contrast_share must be a number >= 0 (inf: the fixed "
                             f"floor min_trace_contrast), got {value!r}")
        levels = self.learned_levels
        if not (isinstance(levels, (tuple, list)) and all(
                isinstance(f, int) and not isinstance(f, bool) and f >= 2 for f in levels)
                and len(set(levels)) == len(levels)):
            raise ValueError(f"params.learned_levels must be a list of distinct integers >= 2 "
                             f"(factors coarser than the working grid; [] for none), got {levels!r}")
        object.__setattr__(self, "learned_levels", tuple(sorted(levels)))
        from .enhance import FLATTEN_METHODS

        if self.flatten_method not in FLATTEN_METHODS:
            raise ValueError(f"params.flatten_method must be one of {', '.join(FLATTEN_METHODS)}, "
                             f"got {self.flatten_method!r}")

    def resolved(self, name: str):
        """The value of a setting of :data:`DETECTOR_DEFAULTS`, or the detector's default when it is
        None (``None`` there: no filter).

        Examples
        --------
        >>> ExtractParams(detector="learned").resolved("min_trace_length_px")
        70.0
        >>> ExtractParams(detector="ridge").resolved("min_trace_contrast") is None
        True
        """
        if self.detector == AUTO:
            raise ValueError(f"{name}: the auto detector has no settings of its own; resolve it "
                             f"on ExtractParams.for_detector('learned') or ('ridge')")
        value = getattr(self, name)
        return DETECTOR_DEFAULTS[name][self.detector] if value is None else value

    def for_detector(self, detector: str) -> ExtractParams:
        """These settings with ``detector`` (one of :data:`DETECTORS`): what ``"auto"`` runs.

        Examples
        --------
        >>> ExtractParams().for_detector("ridge").detector
        'ridge'
        """
        if detector not in DETECTORS:
            raise ValueError(f"detector must be one of {', '.join(DETECTORS)}, got {detector!r}")
        return replace(self, detector=detector,
                       pixel_model=self.pixel_model if detector == "learned" else None)

    @property
    def trace_length_floor_px(self) -> float:
        """``min_trace_length_px``, or the detector's default when it is None."""
        return float(self.resolved("min_trace_length_px"))

    def on_grid(self, scale: float) -> ExtractParams:
        """These settings for a working grid ``scale`` times finer per side than the reference one:
        the lengths of :data:`PIXEL_LENGTHS` times ``scale``, the areas of :data:`PIXEL_AREAS` times
        ``scale²`` (rounded), detector defaults resolved first. ``scale`` 1 returns ``self``.

        Examples
        --------
        >>> p = ExtractParams(max_megapixels=16.0, detector="ridge").on_grid(2.0)
        >>> p.link_gap_px, p.min_object_px, p.min_trace_length_px, p.min_sigma_px
        (100.0, 160, 40.0, 1.0)
        """
        if not (np.isfinite(scale) and scale > 0):
            raise ValueError(f"grid scale must be a finite number > 0, got {scale!r}")
        if scale == 1.0:
            return self
        if self.detector == AUTO:
            raise ValueError("the auto detector's settings go on a grid per detector: "
                             "for_detector(name).on_grid(scale)")
        changes: dict[str, Any] = {}
        for name in PIXEL_LENGTHS:
            value = self.resolved(name) if name in DETECTOR_DEFAULTS else getattr(self, name)
            changes[name] = float(value) * scale
        for name in PIXEL_AREAS:
            value = self.resolved(name) if name in DETECTOR_DEFAULTS else getattr(self, name)
            changes[name] = int(round(value * scale * scale))
        return replace(self, **changes)


def grid_scale(work_megapixels: float) -> float:
    r"""How much finer than the reference grid a working grid is, per side:
    :math:`s = \max(1, \sqrt{\text{MP}_{work} / \text{MP}_{ref}})` with
    :data:`REFERENCE_MEGAPIXELS` as MP_ref. Pixel lengths on the working grid are multiplied by s
    (:meth:`ExtractParams.on_grid`). Grids at or below the reference (every grid at the default
    ``max_megapixels``) keep the settings as they are.

    Examples
    --------
    >>> grid_scale(2.0), grid_scale(16.0)
    (1.0, 2.0)
    """
    return max(1.0, float(np.sqrt(work_megapixels / REFERENCE_MEGAPIXELS)))


def joint_width_on_grid(joint_width_px: float | None, joint_width_m: float | None, *,
                        work_factor: float, m_per_px: float | None, scale: float) -> tuple[float, str]:
    """Expected joint width on the working grid, pixels, and where it came from.

    Parameters
    ----------
    joint_width_px, joint_width_m : float or None
        The width in input pixels, or in metres on the face (needs ``m_per_px``); at most one.
        Neither: :data:`DEFAULT_JOINT_WIDTH_PX` working pixels times ``scale``.
    work_factor : float
        Working grid / input grid, per side.
    m_per_px : float or None
        Metres per input pixel; None when the image has no scale.
    scale : float
        :func:`grid_scale` of the working grid.

    Returns
    -------
    (float, str)
        The width and its source: "joint_width_px", "joint_width_m" or "default".
    """
    if joint_width_px is not None and joint_width_m is not None:
        raise ValueError("give either joint_width_px or joint_width_m, not both")
    if joint_width_m is not None:
        if m_per_px is None:
            raise ValueError("joint_width_m needs a scale: give m_per_px or control_points too (or "
                             "joint_width_px in pixels)")
        return joint_width_m / m_per_px * work_factor, "joint_width_m"
    if joint_width_px is not None:
        return joint_width_px * work_factor, "joint_width_px"
    return DEFAULT_JOINT_WIDTH_PX * scale, "default"


def _check_width(value: float | None, name: str, unit: str) -> None:
    """A given joint width must be a finite number > 0."""
    if value is not None and not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite width > 0 ({unit}), got {value!r}")


@dataclass(frozen=True)
class ScaleInfo:
    """How the result is scaled.

    Attributes
    ----------
    m_per_px : float
        Metres per *input* pixel (1.0 when running in pixels).
    units : {"m", "px"}
        Unit of every coordinate and length in the result.
    source : {"m_per_px", "control_points", "none"}
        Where the scale came from.
    work_factor : float
        Working grid / input grid (1.0 = full resolution; 0.41 = down-sampled to 41 % per side).
    work_shape_px : (rows, cols)
        Shape of the grid the chain ran on.
    processing : str
        The processing mode in words ("full resolution" or "down-sampled ...").
    grid_scale : float
        :func:`grid_scale` of the working grid: the factor the pixel-valued settings were
        multiplied by (1 at or below :data:`REFERENCE_MEGAPIXELS`).
    """

    m_per_px: float
    units: str
    source: str
    work_factor: float
    work_shape_px: tuple[int, int]
    processing: str
    grid_scale: float = 1.0


@dataclass(frozen=True, eq=False)
class Extraction:
    """Result of :func:`extract`.

    Attributes
    ----------
    traces : TraceMap
        Traces in the face frame (u right, v up, origin at the image's bottom-left corner), in
        ``scale.units``, with attributes ``id``, ``length_m``, ``angle_deg`` (0–180° counter-
        clockwise from +u) and ``confidence`` (the detector's mean response along the trace on the
        grid it was found on (the working grid, or a coarser one, ``learned_levels``), 0–1: the mean probability of the learned detector; the mean normalised ridge
        response of the ridge detector, not a probability) and ``contrast`` (1 - the mean of the
        flattened image along the trace / its median over the image: how much darker than the face
        the trace is; see ``ExtractParams.min_trace_contrast``), and the window (image rectangle,
        or the ROI clipped to it).
    scale : ScaleInfo
    params : ExtractParams
        The settings given (before :meth:`ExtractParams.on_grid`; ``scale.grid_scale`` says by how
        much the pixel lengths were multiplied).
    joint_width_px : float
        Expected joint width used, input pixels.
    joint_width_source : str
        Where it came from: "default", "joint_width_px" or "joint_width_m", the last two followed
        by ", capped" when the learned detector used its default width, narrower than the one
        given (see :func:`extract`); then ", grid coarsened fx" when the learned traces came from
        a grid coarsened f times (its width in input pixels is f times as wide).
    face_orientation : (dip_deg, dip_direction_deg) or None
        The face plane, for placing the traces in 3D later.
    timings_s : mapping of str to float
        Wall time per step, seconds, in chain order; the steps of the chains run on the second
        thread (the ridge chain of "auto", the coarser grids) are added in, so their sum can
        exceed the wall time.
    warnings : tuple of str
    debug : mapping of str to ndarray
        With ``debug=True``: ``flattened``, ``ridge_response`` (``joint_probability`` with the
        learned detector, both with "auto"), ``binary``, ``skeleton`` and ``pruned`` (of the
        detector whose traces were kept) on the working grid (a coarser grid's maps enlarged to
        it, nearest pixel), and ``face_mask`` when one was used; else empty.
    face_mask : mapping
        How candidates were limited: ``used`` (bool), ``source`` ("face mask", "roi" or "none"),
        ``mode`` (``params.face_mask``), ``masked_fraction`` (share of the working grid outside
        the mask or ROI, 0 without), ``excluded_fraction`` per cue (face mask only) and ``window``
        ("image", "roi" or "face outline").
    detector_model : mapping or None
        When the learned detector ran (detector "learned" or "auto"), the model used
        (:func:`rockmass.imaging.learned.model_record`: file, shipped or not, sha256, what it was
        trained on); None with the ridge detector.
    detector_choice : mapping or None
        With ``detector = "auto"``: the detector whose traces were kept (``kept``), the
        :func:`detector_agreement` measured (``agreement``), the ``auto_agreement`` it was compared
        with, and how many traces each detector found (``traces``); None otherwise.
    face_contrast : mapping or None
        When the learned detector's traces were kept: how it saw the face's contrast
        (docs/imaging.md §3.1): ``spread``, the relative spread 1.4826 MAD / median of the
        flattened face, ``stretch``, the factor its input was stretched by (1: not;
        ``ExtractParams.min_face_spread``), ``model_stretch``, the factor the pixel model's
        training would have stretched it by
        (:attr:`rockmass.imaging.learned.PixelModel.input_stretch`; None when the model file does
        not record it), ``face_contrast``, the face's own contrast
        1 - q5 / median of the flattened face (:func:`rockmass.imaging.vectorize.face_levels`),
        and ``contrast_floor``, the traces' contrast floor used (``min_trace_contrast``, or lower
        by ``face_contrast_share``); None with the ridge detector's traces.
    learned_levels : mapping or None
        When the learned detector ran on coarser grids too (``ExtractParams.learned_levels``,
        docs/imaging.md §3.4): the grids tried (``levels``, 1 the working grid, f coarsened f
        times), the length-weighted mean joint score of each one's traces (``joint_score``),
        their trace counts (``traces``) and total lengths (``length``, in the traces' units) and
        the grid whose traces the learned detector gives (``kept``); None otherwise.
    """

    traces: Any
    scale: ScaleInfo
    params: ExtractParams
    joint_width_px: float
    face_orientation: tuple[float, float] | None
    timings_s: Mapping[str, float]
    warnings: tuple[str, ...]
    debug: Mapping[str, np.ndarray] = field(default_factory=dict)
    face_mask: Mapping[str, Any] = field(default_factory=dict)
    joint_width_source: str = "joint_width_px"
    detector_model: Mapping[str, Any] | None = None
    detector_choice: Mapping[str, Any] | None = None
    face_contrast: Mapping[str, Any] | None = None
    learned_levels: Mapping[str, Any] | None = None

    def summary(self) -> dict:
        """A JSON-ready dict of the scale, parameters, timings and warnings (no arrays)."""
        return {"n_traces": self.traces.n_traces, "units": self.scale.units,
                "scale": asdict(self.scale), "params": infinities_as_text(asdict(self.params)),
                "joint_width_px": self.joint_width_px,
                "joint_width_source": self.joint_width_source,
                "face_orientation": self.face_orientation,
                "face_mask": dict(self.face_mask),
                "detector_model": None if self.detector_model is None else dict(self.detector_model),
                "detector_choice": None if self.detector_choice is None
                else {**self.detector_choice, "traces": dict(self.detector_choice["traces"])},
                "face_contrast": None if self.face_contrast is None
                else infinities_as_text(self.face_contrast),
                "learned_levels": None if self.learned_levels is None else dict(self.learned_levels),
                "timings_s": dict(self.timings_s), "warnings": list(self.warnings)}


def infinities_as_text(record: Mapping[str, Any]) -> dict:
    """A flat record (``asdict`` of :class:`ExtractParams`, a config's ``[imaging.params]``,
    ``Extraction.face_contrast``) with its infinities as the strings "inf" / "-inf": JSON has no
    infinity, and ``float()`` reads these back (``min_trace_contrast = -inf`` turns the contrast
    filter off, and the contrast floor is then ``-inf``).

    Examples
    --------
    >>> infinities_as_text({"min_trace_contrast": float("-inf"), "prob_low": 0.8, "detector": "auto"})
    {'min_trace_contrast': '-inf', 'prob_low': 0.8, 'detector': 'auto'}
    """
    return {name: str(value) if isinstance(value, float) and np.isinf(value) else value
            for name, value in record.items()}


def scale_from_control_points(control_points, shape_px: tuple[int, int] | None = None) -> float:
    """Metres per pixel from two pixel positions and the real distance between them.

    Parameters
    ----------
    control_points : mapping or sequence
        ``{"rc_px": [(r1, c1), (r2, c2)], "distance_m": d}`` or ``((r1, c1), (r2, c2), d)``: two
        points in input-image pixels (row, col) and their distance on the face in metres.
    shape_px : (int, int), optional
        (rows, cols) of the image: then both points must lie on it (a point off the photo is a
        typo or a point of another photo).

    Returns
    -------
    float
        :math:`d / \\lVert p_2 - p_1 \\rVert`.

    Raises
    ------
    ValueError
        Zero, negative or non-finite distance, coincident or non-finite points, or a malformed
        argument (the message names the field, e.g. ``control_points.distance_m``).

    Examples
    --------
    >>> scale_from_control_points({"rc_px": [(0, 0), (30, 40)], "distance_m": 1.0})
    0.02
    """
    if isinstance(control_points, Mapping):
        unknown = set(control_points) - {"rc_px", "distance_m"}
        if unknown or "rc_px" not in control_points or "distance_m" not in control_points:
            raise ValueError("control_points must have the keys 'rc_px' (two (row, col) pixel "
                             f"positions) and 'distance_m', got {sorted(map(str, control_points))}")
        points, distance = control_points["rc_px"], control_points["distance_m"]
    else:
        try:
            p1, p2, distance = control_points
        except (TypeError, ValueError) as exc:
            raise ValueError("control_points must be ((r1, c1), (r2, c2), distance_m) or a mapping "
                             "with 'rc_px' and 'distance_m'") from exc
        points = (p1, p2)
    try:
        rc = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError("control_points.rc_px must be two (row, col) pixel positions") from exc
    if rc.shape != (2, 2):
        raise ValueError(f"control_points.rc_px must be two (row, col) pixel positions, got shape {rc.shape}")
    if not np.isfinite(rc).all():
        raise ValueError("control_points.rc_px has non-finite coordinates")
    try:
        d = float(distance)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"control_points.distance_m must be a number, got {distance!r}") from exc
    if not (np.isfinite(d) and d > 0):
        raise ValueError(f"control_points.distance_m must be a finite distance > 0 (metres), got {distance!r}")
    if shape_px is not None:
        h, w = shape_px
        off = [i for i in range(2) if not (-0.5 <= rc[i, 0] <= h - 0.5 and -0.5 <= rc[i, 1] <= w - 0.5)]
        if off:
            raise ValueError(f"control_points.rc_px: point {off[0] + 1} (row {rc[off[0], 0]:g}, col "
                             f"{rc[off[0], 1]:g}) lies outside the {h} x {w} pixel image (rows "
                             f"0..{h - 1}, cols 0..{w - 1})")
    pixels = float(np.hypot(*(rc[1] - rc[0])))
    if pixels == 0:
        raise ValueError("control_points.rc_px: the two points coincide; pick two points apart")
    return d / pixels


def _check_orientation(dip, dip_direction):
    if dip is None and dip_direction is None:
        return None
    if dip is None or dip_direction is None:
        raise ValueError("face_dip_deg and face_dip_direction_deg must be given together")
    dip, dip_direction = float(dip), float(dip_direction)
    if not (np.isfinite(dip) and 0 <= dip <= 90):
        raise ValueError(f"face_dip_deg must be in 0-90 degrees, got {dip!r}")
    if not (np.isfinite(dip_direction) and 0 <= dip_direction <= 360):
        raise ValueError(f"face_dip_direction_deg must be in 0-360 degrees, got {dip_direction!r}")
    return (dip, dip_direction % 360.0)


# the steps of :func:`extract`, in order: its timings and its ``progress`` callback use these names
STEPS = ("read", "grey", "downsample", "roi", "face_mask", "flatten", "ridges", "segment", "skeleton",
         "graph", "prune", "crossings", "bridge", "chain", "link", "vectorize")


class _Clock:
    """Time per step (summed when a step runs again, as the detection steps do for "auto");
    calls ``progress(step)`` as each step first ends."""

    def __init__(self, progress: Callable[[str], None] | None = None):
        self.timings: dict[str, float] = {}
        self.progress = progress
        self._reported: set[str] = set()
        self._t = time.perf_counter()

    def lap(self, name: str, *, report: bool = True) -> None:
        """End the running step ``name``; ``report=False``: not yet its end for the progress bar
        (it runs again later, as "vectorize" does after the side tasks)."""
        now = time.perf_counter()
        self.timings[name] = self.timings.get(name, 0.0) + now - self._t
        self._t = now
        if self.progress is not None and report and name not in self._reported:
            self._reported.add(name)
            self.progress(name)

    def skip(self) -> None:
        """Restart the running lap without recording it (time spent waiting for another thread)."""
        self._t = time.perf_counter()

    def add(self, other: _Clock) -> None:
        """Add the step times of a chain timed apart (the ridge chain of "auto", run beside)."""
        for name, seconds in other.timings.items():
            self.timings[name] = self.timings.get(name, 0.0) + seconds


def _render(graph, shape) -> np.ndarray:
    """Binary image of a skeleton graph's branch pixels (for the debug output)."""
    out = np.zeros(shape, dtype=bool)
    rc = np.round(graph.branch_rc_px).astype(np.int64)
    if rc.size:
        out[rc[:, 0], rc[:, 1]] = True
    return out


def _with_joint_score(traces, detector: str, *, m_per_px: float, joint_width_px: float):
    """The traces with a ``joint_score`` attribute (eq. (7.1), :mod:`rockmass.imaging.trace_score`)."""
    import dataclasses

    from . import trace_score

    if not trace_score.scoring():
        return traces
    features = trace_score.trace_features(traces, m_per_px=m_per_px, joint_width_px=joint_width_px)
    score = trace_score.joint_score(features, detector)
    return dataclasses.replace(traces, attributes={**traces.attributes, "joint_score": score})


def _read_grey(image_or_path, control_points, clock: _Clock):
    """The photo (file or array) and its grey image, checked: at least :data:`MIN_SIDE_PX` a
    side, not blank, control points on it. Returns (raw, grey, name for messages)."""
    from . import enhance

    if isinstance(image_or_path, (str, Path)):
        raw = enhance.read_photo(image_or_path)
        name = str(image_or_path)
    else:
        raw = image_or_path
        name = "image"
    clock.lap("read")
    grey = enhance.to_grey(raw, name=name)
    h, w = grey.shape
    if h < MIN_SIDE_PX or w < MIN_SIDE_PX:
        raise ValueError(f"{name} is {h} x {w} pixels; at least {MIN_SIDE_PX} x {MIN_SIDE_PX} are "
                         "needed to find joints")
    if control_points is not None:  # the points must lie on this photo
        scale_from_control_points(control_points, shape_px=(h, w))
    lo, hi = float(grey.min()), float(grey.max())
    if hi - lo < 0.5 / 255:
        raise ValueError(f"{name} is blank: every pixel has grey level {lo:.3f} (all black or all "
                         "white?); there are no joints to find")
    clock.lap("grey")
    return raw, grey, name


def working_grid(grey, max_megapixels: float, notes: list) -> tuple:
    """The grey image area-averaged down to at most ``max_megapixels`` (the working grid; a note
    says so in ``notes``), or as it is. Returns (grey on the working grid, its shape, the mode in
    words). :mod:`rockmass.imaging.train_pixel_model` puts a user's photographs on the same grid."""
    import cv2

    h, w = grey.shape
    megapixels = h * w / 1e6
    if megapixels <= max_megapixels:
        return grey, (h, w), "full resolution"
    factor = float(np.sqrt(max_megapixels / megapixels))
    work_shape = (max(int(round(h * factor)), MIN_SIDE_PX), max(int(round(w * factor)), MIN_SIDE_PX))
    grey = cv2.resize(grey, (work_shape[1], work_shape[0]), interpolation=cv2.INTER_AREA)
    processing = (f"down-sampled from {h} x {w} ({megapixels:.1f} MP) to {work_shape[0]} x "
                  f"{work_shape[1]} ({work_shape[0] * work_shape[1] / 1e6:.1f} MP, factor "
                  f"{factor:.3f}; max_megapixels = {max_megapixels:g})")
    notes.append(processing)
    return grey, work_shape, processing


def _largest_polygon(area):
    """The largest polygon of a shapely (Multi)Polygon."""
    import shapely

    return area if area.geom_type == "Polygon" else max(shapely.get_parts(area), key=lambda g: g.area)


def _candidate_area(raw, roi, face_mask: str, shape_px, work_shape, scale: float, units: str,
                    name: str, clock: _Clock) -> tuple:
    """Where joint pixels may lie on the working grid, and the sampling window on the face.

    A ROI (input pixels or metres) gives both; else the automatic face mask of mode ``face_mask``
    (:mod:`.face_mask`), whose outline becomes the window when its cues leave out more than the
    border band; "off" gives neither. Returns (mask or None, window (k, 2) in face units, the
    ``Extraction.face_mask`` record, the mask's border band on the working grid in pixels)."""
    import shapely

    from . import grid_levels, segment

    h, _w = shape_px
    mask = None
    window = image_window_uv_m(shape_px, scale)
    if roi is not None:
        rc_in = segment.roi_vertices_rc(roi, shape_px, m_per_px=scale if units == "m" else None)
        rc_work = grid_levels.to_grid([rc_in], shape_px, work_shape)[0]
        mask = segment.roi_mask({"rc_px": rc_work}, work_shape)
        area = shapely.Polygon(rc_to_uv(rc_in, h, scale)).intersection(shapely.Polygon(window))
        window = np.asarray(_largest_polygon(area).exterior.coords)
    clock.lap("roi")
    face_info: dict[str, Any] = {"used": False, "source": "none", "mode": face_mask,
                                 "masked_fraction": 0.0, "window": "image"}
    band_px = 0.0  # width of the face mask's border band on the working grid
    if mask is not None:
        face_info.update(used=True, source="roi", masked_fraction=float(1.0 - mask.mean()),
                         window="roi")
    elif face_mask != "off":
        from .face_mask import face_mask_cues, face_outline_rc

        cues = face_mask_cues(raw, shape_px=work_shape, mode=face_mask, name=name)
        mask = cues.mask
        band_px = cues.border_px * work_shape[0] / cues.cues["border"].shape[0]
        face_info.update(used=True, source="face mask", masked_fraction=float(1.0 - mask.mean()),
                         excluded_fraction=dict(cues.summary()["excluded_fraction"]))
        outline = face_outline_rc(cues, shape_px)
        if outline is not None:
            area = _largest_polygon(shapely.Polygon(rc_to_uv(outline, h, scale)).buffer(0)
                                    .intersection(shapely.Polygon(window)))
            if not area.is_empty and area.area > 0:
                window = np.asarray(area.exterior.coords)
                face_info["window"] = "face outline"
    clock.lap("face_mask")
    return mask, window, face_info, band_px


def _joint_pixels(grey, params: ExtractParams, width_work: float, mask, clock: _Clock,
                  flat_face=None) -> tuple:
    """Flatten the working grey image, find the joint response (ridge filter or learned
    probability) and threshold it (hysteresis, inside ``mask``; holes filled). Returns (flattened
    image, response, binary mask of joint pixels, and for the learned detector the relative
    spread and contrast of the flattened face and the factor its input was stretched by, else
    None). Within :func:`rockmass.imaging.reuse.shared_work` the learned detector's flattened face
    and probability map are computed once per model, image and mask (no back-end setting changes
    them). ``flat_face``: the learned detector's flattened face when another model's run on the
    same grid made it already (:func:`rockmass.imaging.learned.flattened` of ``grey``)."""
    from . import enhance, learned, ridges, segment
    from .reuse import array_digest, reused

    stretch = None
    if params.detector == "learned":
        model = learned.load_model(params.pixel_model)
        computed = []

        def probability_map():
            computed.append(True)
            flat, levels, model_image, gain = _learned_input(grey, params, mask, flat_face)
            clock.lap("flatten")
            probability = learned.joint_probability(model_image, model)
            clock.lap("ridges")
            # the model is kept with its map, so that its id stays its own while the block lasts
            return model, flat, levels, gain, probability

        (_, flat, levels, gain, response), _ = reused(
            lambda: ("probability map", id(model), array_digest(grey), array_digest(mask),
                     params.background_sigma_px, params.min_face_spread), probability_map)
        if not computed:  # reused: the steps took no time in this run
            clock.lap("flatten")
            clock.lap("ridges")
        # kept in a block, flat and response are read here and by _detect, which copies what it
        # hands on: one map per photo, not one per pair of hysteresis levels
        trained = model.input_stretch
        stretch = {"spread": levels.spread, "stretch": gain, "face_contrast": levels.contrast,
                   "model_stretch": None if trained is None
                   else learned.stretch_gain(levels.spread, *trained)}
        binary = segment.hysteresis_mask(response, low=params.prob_low, high=params.prob_high,
                                         min_size_px=params.min_object_px, mask=mask)
    else:
        flat = enhance.flatten_illumination(
            grey, line_width_px=max(2.0 * width_work, 2.0), sigma_px=params.background_sigma_px,
            method=params.flatten_method, clahe=params.clahe, clahe_clip_limit=params.clahe_clip_limit)
        clock.lap("flatten")
        sigmas = ridges.ridge_sigmas(width_work, params.n_scales, spread=params.scale_spread,
                                     min_sigma_px=params.min_sigma_px)
        response = ridges.ridge_response(flat, sigmas, black_ridges=params.line_polarity == "dark")
        clock.lap("ridges")
        binary = segment.segment_ridges(response, low_k=params.low_k, high_k=params.high_k,
                                        min_size_px=params.min_object_px, mask=mask)
    binary = segment.fill_holes(binary, params.resolved("fill_holes_px"))
    clock.lap("segment")
    return flat, response, binary, stretch


def _learned_input(grey, params: ExtractParams, mask, flat=None) -> tuple:
    """(flattened face, its levels, the pixel model's input, the factor it was stretched by) of
    the learned detector (docs/imaging.md §3.1): the face stretched when flatter than
    ``min_face_spread``, the unstretched one kept for the traces' contrasts; ``flat``, when given,
    is the flattened face already made."""
    from . import learned, vectorize

    if flat is None:
        flat = learned.flattened(grey, background_sigma_px=params.background_sigma_px)
    levels = vectorize.face_levels(flat, mask=mask)  # one sample: the stretch and the floor
    model_image, gain, _ = learned.stretch_flat_face(flat, min_spread=params.min_face_spread,
                                                     levels=levels)
    return flat, levels, model_image, gain


#: The steps of :func:`_chains_before_floor`, as its clock names them.
_CHAIN_STEPS = ("skeleton", "graph", "prune", "crossings", "bridge", "chain")


def _chains_before_floor(binary, params: ExtractParams, work_shape, width_work: float,
                         band_px: float, clock: _Clock) -> tuple:
    """Joint pixels -> pixel polylines on the working grid: skeleton, graph, spur pruning, X
    crossings, gap bridging, chaining, linking, ends carried to the border. Returns (chains,
    skeleton image, pruned graph)."""
    from . import link, skeleton_graph

    skeleton = skeleton_graph.skeletonize(binary)
    clock.lap("skeleton")
    graph = skeleton_graph.build_graph(skeleton)
    clock.lap("graph")
    tangent = dict(skip_px=params.tangent_skip_px, reach_px=params.tangent_reach_px)
    pruned = skeleton_graph.prune_spurs(graph, params.spur_length_px)
    clock.lap("prune")
    repaired = skeleton_graph.repair_crossings(pruned, max_link_px=params.crossing_link_px,
                                               max_turn_deg=params.max_turn_deg, **tangent)
    clock.lap("crossings")
    bridged = skeleton_graph.bridge_gaps(repaired, max_distance_px=params.bridge_distance_px,
                                         max_angle_deg=params.bridge_angle_deg, **tangent)
    clock.lap("bridge")
    chains = skeleton_graph.chain_traces(bridged, max_turn_deg=params.max_turn_deg, **tangent)
    clock.lap("chain")
    chains = link.link_traces(chains, max_gap_px=params.link_gap_px,
                              max_turn_deg=params.link_turn_deg, max_offset_px=params.link_offset_px,
                              max_overlap_px=max(width_work, 1.0), skip_px=params.link_skip_px,
                              reach_px=params.link_reach_px)
    if params.border_extend_px > 0:  # across the face mask's border band too: it hid that stretch
        chains = link.extend_to_border(chains, work_shape,
                                       max_distance_px=params.border_extend_px + band_px,
                                       skip_px=params.link_skip_px, reach_px=params.link_reach_px)
    return chains, skeleton, pruned


class _Found(NamedTuple):
    """One detector's traces on its grid (the working grid, or a coarser one for the learned
    detector), with what the debug output shows."""

    chains: list
    contrast: np.ndarray
    band_px: np.ndarray
    confidence: np.ndarray
    flat: np.ndarray
    response: np.ndarray
    binary: np.ndarray
    skeleton: np.ndarray
    pruned: Any
    face_contrast: Mapping[str, Any] | None


def contrast_floor(params: ExtractParams, face_contrast: float | None) -> float | None:
    """The traces' contrast floor on a face of contrast ``face_contrast``
    (:func:`vectorize.face_levels`): ``min_trace_contrast``, lowered to ``face_contrast_share``
    times the face's contrast when that is lower; None: no floor.

    Examples
    --------
    >>> learned = ExtractParams(detector="learned")
    >>> contrast_floor(learned, 0.5), round(contrast_floor(learned, 0.1), 3)
    (0.25, 0.08)
    """
    floor, share = params.resolved("min_trace_contrast"), params.resolved("face_contrast_share")
    if floor is None or share is None or not np.isfinite(share) or face_contrast is None:
        return floor
    return float(min(floor, share * face_contrast))


def _low_contrast_notes(record, params: ExtractParams) -> list[str]:
    """Warnings for a face the learned detector saw as of low contrast: its input stretched
    (and by another factor than the pixel model's training would have, or by a model that does
    not record its training's), or its contrast floor lowered below half the fixed one
    (``record`` as in ``Extraction.face_contrast``)."""
    if record is None:
        return []
    notes = []
    if record["stretch"] > 1.0:
        notes.append(f"flat face: the learned detector's input was stretched {record['stretch']:.3g} "
                     f"times to the spread min_face_spread = {params.min_face_spread:g} "
                     f"(docs/imaging.md §3.1)")
    trained = record["model_stretch"]
    if trained is None and record["stretch"] > 1.0:
        notes.append("the pixel model file does not record the stretch its training faces went "
                     "through (trained before rockmass recorded it): it may not have learned from "
                     "stretched faces like this one")
    elif trained is not None and not np.isclose(trained, record["stretch"]):
        notes.append(f"this face's input was stretched {record['stretch']:.3g} times "
                     f"(min_face_spread = {params.min_face_spread:g}), the pixel model's training "
                     f"faces would have been {trained:.3g} times: its input differs from what it "
                     f"learned; give the min_face_spread it was trained with (detector_model."
                     f"input_stretch in the summary)")
    fixed, floor = params.resolved("min_trace_contrast"), record["contrast_floor"]
    if fixed is not None and floor is not None and floor < 0.5 * fixed:
        notes.append(f"low-contrast face (its darkest 5 % only {record['face_contrast']:.3g} below "
                     f"its median): the learned detector's contrast floor was lowered from {fixed:g} "
                     f"to {floor:.3g} (face_contrast_share); if its traces miss faint joints, "
                     f"compare --detector ridge")
    return notes


def _detect(grey, params: ExtractParams, width_work: float, mask, band_px: float, work_shape,
            clock: _Clock, flat_face=None) -> _Found:
    """The chain of one detector (``params`` on the grid, not "auto"), from the working grey image
    to filtered traces: joint pixels, traces (:func:`_chains_before_floor`), then the length floor
    and the contrast and width filters. Within :func:`rockmass.imaging.reuse.shared_work`
    everything before the length floor is computed once per image, mask and other settings (the
    floor changes nothing before it; the traces' attributes are those of each trace alone).
    ``flat_face``: the learned detector's flattened face of ``grey``, when made already."""
    from . import link, vectorize
    from .reuse import array_digest, reused

    computed = []

    def before_floor():
        computed.append(True)
        flat, response, binary, stretch = _joint_pixels(grey, params, width_work, mask, clock,
                                                        flat_face)
        chains, skeleton, pruned = _chains_before_floor(binary, params, work_shape, width_work,
                                                        band_px, clock)
        attributes = (vectorize.trace_contrast(chains, flat, mask=mask),
                      vectorize.band_width_px(chains, binary), vectorize.mean_along(chains, response))
        return flat, response, binary, stretch, chains, skeleton, pruned, attributes

    (flat, response, binary, stretch, chains, skeleton, pruned, (contrast, band, confidence)), kept \
        = reused(lambda: ("traces before the floor", array_digest(grey), array_digest(mask),
                          repr(replace(params, min_trace_length_px=None)), tuple(work_shape),
                          float(width_work), float(band_px)), before_floor)
    if not computed:  # reused: the steps took no time in this run
        for step in ("flatten", "ridges", "segment", *_CHAIN_STEPS):
            clock.lap(step)
    keep = np.array([link.polyline_length_px(c) >= params.trace_length_floor_px for c in chains],
                    dtype=bool)
    face = None if stretch is None else stretch["face_contrast"]
    if face is None and params.resolved("face_contrast_share") is not None:  # a share for ridge
        face = vectorize.face_levels(flat, mask=mask).contrast
    floor = contrast_floor(params, face)
    if floor is not None:
        keep &= contrast >= floor
    if params.resolved("min_trace_width") is not None:
        keep &= band >= params.resolved("min_trace_width") * width_work
    clock.lap("link")
    chains = [c for c, k in zip(chains, keep) if k]
    if kept:  # the block keeps them as computed for the next setting
        chains = [c.copy() for c in chains]
        flat, response, binary, skeleton = flat.copy(), response.copy(), binary.copy(), skeleton.copy()
    record = None if stretch is None else MappingProxyType({**stretch, "contrast_floor": floor})
    return _Found(chains, contrast[keep], band[keep], confidence[keep], flat, response, binary,
                  skeleton, pruned, record)


def detector_agreement(ridge_chains, learned_chains, shape_px, *,
                       radius_px: float = AGREEMENT_RADIUS_PX) -> float:
    r"""Share of the ridge filter's trace length that the learned detector found too.

    The ridge filter (§3) marks every thin dark line, the learned detector (§3.1) only those that
    look like joints on real rock. On a clean photo, whose dark lines are joints, they agree but
    for the faint lines the learned detector leaves out; on rough rock the ridge filter draws
    several times the joints' length in texture, grain and block edges, which the learned
    detector does not follow. The share

    .. math:: A = \frac{\#\{x \in R : d(x, L) \le r\}}{\#R},

    with R the ridge traces' pixels and L the learned traces' (both drawn 1 px wide on the
    working grid) and d the Euclidean distance, tells the two apart (docs/imaging.md §3.3).

    Parameters
    ----------
    ridge_chains, learned_chains : sequence of (n, 2) arrays
        Traces as (row, col) pixel polylines on one grid.
    shape_px : (rows, cols)
    radius_px : float, default AGREEMENT_RADIUS_PX

    Returns
    -------
    float
        A in [0, 1]; 0 when the ridge filter found nothing.

    Examples
    --------
    >>> line = [np.array([[10.0, 5.0], [10.0, 95.0]])]
    >>> detector_agreement(line, line, (40, 100))
    1.0
    >>> detector_agreement(line, [np.array([[30.0, 5.0], [30.0, 95.0]])], (40, 100))
    0.0
    """
    from .metrics import pixels_within, render_chains

    # the ridge pixels play the truth of the raster scores (8.5)-(8.6): A is their "recall"
    confirmed, ridge = pixels_within(render_chains(ridge_chains, shape_px),
                                     render_chains(learned_chains, shape_px), radius_px)
    return confirmed / ridge if ridge else 0.0


def _ridge_or_learned(detected, work_shape, scale_of_grid: float, params: ExtractParams) -> dict:
    """"auto"'s choice between the ridge filter's traces and the pixel model's, by their
    agreement (:func:`detector_agreement`, docs/imaging.md §3.3): the record of
    ``Extraction.detector_choice`` before the network (``kept``, ``agreement``, ``auto_agreement``).
    ``detected`` maps "ridge" and "learned" to (run, traces), the learned run on its kept grid."""
    from . import grid_levels

    learned_run, ridge_run = detected["learned"][0], detected["ridge"][0]
    learned_chains = grid_levels.to_grid(learned_run.chains, learned_run.flat.shape, work_shape)
    agreement = detector_agreement(ridge_run.chains, learned_chains, work_shape,
                                   radius_px=AGREEMENT_RADIUS_PX * scale_of_grid)
    return {"kept": "ridge" if agreement > params.auto_agreement else "learned",
            "agreement": agreement, "auto_agreement": params.auto_agreement}


def network_length_ratio(network_traces, learned_traces) -> float:
    r"""Total trace length of the convolutional network's chain over the pixel model's.

    The two learned chains (§3.1, §3.6) both mark joint centre lines and both leave texture out,
    but the pixel model, made for the major open joints real labels mark, loses thin and faint
    joints on textured rock, where the network, trained on joints drawn over many textures, keeps
    them. Where it finds clearly more joint length,

    .. math:: \rho = \frac{\sum \ell_{\mathrm{network}}}{\sum \ell_{\mathrm{pixel\ model}}}
              \ge \rho_{\min}

    (``auto_network_ratio``, :data:`AUTO_NETWORK_RATIO` by default), "auto" keeps the network's
    traces (docs/imaging.md §3.6).

    Returns
    -------
    float
        The ratio; ``inf`` when the pixel model found nothing and the network something, 0 when
        the network found nothing.

    Examples
    --------
    >>> from rockmass.dfn import TraceMap
    >>> short = TraceMap.from_polylines([np.array([[0.0, 0.0], [1.0, 0.0]])])
    >>> long = TraceMap.from_polylines([np.array([[0.0, 0.0], [3.0, 0.0]])])
    >>> network_length_ratio(long, short), network_length_ratio(short, long) < 1
    (3.0, True)
    """
    network = float(network_traces.lengths_m().sum()) if network_traces.n_traces else 0.0
    pixel_model = float(learned_traces.lengths_m().sum()) if learned_traces.n_traces else 0.0
    if pixel_model > 0:
        return network / pixel_model
    return float("inf") if network > 0 else 0.0


def extract(image_or_path, *, m_per_px: float | None = None, control_points=None,
            joint_width_px: float | None = None, joint_width_m: float | None = None, roi=None,
            face_dip_deg: float | None = None, face_dip_direction_deg: float | None = None,
            params: ExtractParams | None = None,
            debug: bool = False, progress: Callable[[str], None] | None = None) -> Extraction:
    """Joint traces from a face photograph.

    Parameters
    ----------
    image_or_path : str, path-like, or (H, W), (H, W, 3), (H, W, 4) array_like
        A JPEG / PNG / TIFF file (EXIF orientation honoured) or an image array (grey or RGB(A),
        uint8, uint16 or float in [0, 1]); never modified.
    m_per_px : float, optional
        Scale, metres per input pixel, finite and > 0.
    control_points : mapping or sequence, optional
        Instead of ``m_per_px``: two pixel positions and their distance in metres (see
        :func:`scale_from_control_points`). With neither, the result is in pixels, with a warning.
    joint_width_px : float, optional
        Expected joint width in input pixels, > 0; sets the ridge filter scales (σ ≈ w / 2). The
        learned detector uses it for its width filter, linking and joint scores up to the
        default width of the working grid, and caps a wider one with a warning: its probability
        bands do not widen with the joints (docs/imaging.md §3.1).
    joint_width_m : float, optional
        Instead of ``joint_width_px``: the width in metres on the face (needs a scale). With
        neither, :data:`DEFAULT_JOINT_WIDTH_PX` pixels of the working grid (times
        :func:`grid_scale` when ``max_megapixels`` is raised above :data:`REFERENCE_MEGAPIXELS`),
        which keeps the chain's view of a joint the same at any photo size.
    roi : (k, 2) array_like or mapping, optional
        Region of interest polygon (see :func:`rockmass.imaging.segment.roi_mask`): a bare array or
        ``{"rc_px": ...}`` in input pixels (row, col), ``{"uv_m": ...}`` in metres on the face frame.
        Traces are found only inside; it becomes the sampling window. It replaces the automatic
        face mask (``params.face_mask``).
    face_dip_deg, face_dip_direction_deg : float, optional
        Orientation of the face plane (0–90°, 0–360°), recorded for placing traces in 3D.
    params : ExtractParams, optional
        Chain settings; default ``ExtractParams()``.
    debug : bool, default False
        Keep the intermediate images in ``Extraction.debug``.
    progress : callable, optional
        ``progress(step)`` after each step of the chain, with the names of :data:`STEPS` in order
        (the ``rockmass extract`` progress bar).

    Returns
    -------
    Extraction

    Raises
    ------
    FileNotFoundError, OSError
        Missing, empty, truncated or unreadable image file.
    ValueError
        An image smaller than 16 x 16 pixels, a blank image (all one grey level, e.g. all black or
        all white), a bad scale or control points, a ROI outside the image, both ``m_per_px`` and
        ``control_points``, or a bad parameter (each message names the field).
    TypeError
        ``params`` of the wrong type, or a non-numeric image.

    Examples
    --------
    >>> from rockmass.imaging import synthetic_face
    >>> face = synthetic_face("easy", seed=7, shape_px=(300, 450), m_per_px=0.02)
    >>> result = extract(face.image, m_per_px=0.02)
    >>> result.scale.units, result.traces.n_traces > 0
    ('m', True)
    """
    from . import grid_levels, learned, trace_score, vectorize

    params = ExtractParams() if params is None else params
    if not isinstance(params, ExtractParams):
        raise TypeError(f"params must be an ExtractParams, got {type(params).__name__}")
    _check_width(joint_width_px, "joint_width_px", "pixels")
    _check_width(joint_width_m, "joint_width_m", "metres")
    orientation = _check_orientation(face_dip_deg, face_dip_direction_deg)
    notes: list[str] = []
    if m_per_px is not None and control_points is not None:
        raise ValueError("give either m_per_px or control_points, not both")
    if m_per_px is not None:
        scale, units, source = check_scale(m_per_px), "m", "m_per_px"
    elif control_points is not None:
        scale, units, source = scale_from_control_points(control_points), "m", "control_points"
    else:
        scale, units, source = 1.0, "px", "none"
        notes.append("no scale given (m_per_px or control_points): coordinates and lengths are in "
                     "pixels, labelled 'px'; set m_per_px or give two control points for metres")

    clock = _Clock(progress)
    raw, grey, name = _read_grey(image_or_path, control_points, clock)
    h, w = grey.shape
    grey, work_shape, processing = working_grid(grey, params.max_megapixels, notes)
    row_factor, col_factor = work_shape[0] / h, work_shape[1] / w
    factor = float(np.sqrt(row_factor * col_factor))
    given_params, scale_of_grid = params, grid_scale(work_shape[0] * work_shape[1] / 1e6)
    width_work, width_source = joint_width_on_grid(
        joint_width_px, joint_width_m, work_factor=factor, m_per_px=scale if units == "m" else None,
        scale=scale_of_grid)
    if width_work / factor >= min(h, w):  # else OpenCV's kernels cannot be sized (TypeError)
        given = (f"joint_width_px = {joint_width_px:g} px" if joint_width_m is None
                 else f"joint_width_m = {joint_width_m:g} m ({width_work / factor:.4g} px)")
        raise ValueError(f"{given} is not narrower than the {h} x {w} pixel image; give the "
                         "width of one joint (default 3 px of the working grid)")
    learned_width = DEFAULT_JOINT_WIDTH_PX * scale_of_grid  # the width its bands keep
    capped_note = (f"the joint width given ({width_work / factor:.4g} px, {width_work:.4g} px of the "
                   f"working grid) is wider than the learned detector uses: its probability bands "
                   f"do not widen with the joints (docs/imaging.md §3.1), so its width filter, "
                   f"linking and joint scores use {learned_width:g} px of the grid it reads (the "
                   f"working grid or a coarser one, §3.4); "
                   f"--detector ridge sets its filter scales from the width given")
    if scale_of_grid > 1.0:
        notes.append(f"working grid {work_shape[0] * work_shape[1] / 1e6:.1f} MP, above the "
                     f"{REFERENCE_MEGAPIXELS:g} MP the pixel settings are given for: pixel lengths "
                     f"x {scale_of_grid:.3f}")
    clock.lap("downsample")

    mask, window, face_info, band_px = _candidate_area(
        raw, roi, params.face_mask, (h, w), work_shape, scale, units, name, clock)
    def learned_width_on(level):  # the learned detector's joint width, pixels of its grid
        # a given width describes the working grid's joints; a coarser grid uses the detector's
        # own, so that the grids' joint scores are compared at one width
        return min(width_work, learned_width) if level == 1 else learned_width

    uses_learned = params.detector in (AUTO, "learned")
    uses_network = (params.detector == AUTO and params.pixel_model is None
                    and np.isfinite(params.auto_network_ratio))
    levels = (grid_levels.usable_levels(params.learned_levels, work_shape)
              if uses_learned and trace_score.scoring() else ())

    def detect(detector, image, detector_clock, level=1, model=None, flat_face=None):  # run, traces
        width = learned_width_on(level) if detector == "learned" else width_work
        level_mask, shape = mask, work_shape
        if level > 1:  # a coarser grid (§3.4)
            image, level_mask, shape = grid_levels.coarsen(image, mask, level)
        grid_params = given_params.for_detector(detector).on_grid(scale_of_grid)
        if model is not None:  # the learned chain with another model: "auto"'s network (§3.6)
            grid_params = replace(grid_params, pixel_model=model)
        run = _detect(image, grid_params, width, level_mask, band_px / level, shape, detector_clock,
                      flat_face)
        # the traces in input pixels or metres
        grid_factor = float(np.sqrt(shape[0] / h * shape[1] / w))
        traces = vectorize.to_trace_map(
            grid_levels.to_grid(run.chains, shape, (h, w)), height_px=h, m_per_px=scale,
            window_uv_m=window, tolerance_px=grid_params.simplify_tolerance_px / grid_factor,
            frame="face", attributes={"confidence": run.confidence,
                                      "contrast": run.contrast,
                                      "band_width_px": run.band_px / grid_factor})
        traces = _with_joint_score(traces, detector, m_per_px=scale,
                                   joint_width_px=width / grid_factor)
        detector_clock.lap("vectorize", report=False)  # the step ends once a detector is kept
        return run, traces

    # the ridge chain of "auto" and the coarser grids run beside the working grid's learned
    # chain, on the other core, each with its traces (the ridge filter's are made whether "auto"
    # keeps them or not: the other core would wait for the main chain meanwhile)
    from concurrent.futures import ThreadPoolExecutor

    side_clocks = []

    def timed(task, *args, **kwargs):  # a side task's clock starts with the task, not queued
        side_clocks.append(_Clock())
        return task(*args, side_clocks[-1], **kwargs)  # one worker: one task after another

    grid_of, level_records = {}, {}  # the grid each learned chain's traces come from (§3.4)

    def keep_grid(chain, runs):  # the (run, traces) of the grid a learned chain keeps (§3.4)
        grid_of[chain], level_records[chain] = grid_levels.kept_grid(
            {level: traces for level, (_, traces) in runs.items()})
        return runs[grid_of[chain]]

    choice = None
    with ThreadPoolExecutor(max_workers=1) as pool:
        try:
            ridge = pool.submit(timed, detect, "ridge", grey) if params.detector == AUTO else None
            # the coarser grids of the learned chain
            pending = {level: pool.submit(timed, detect, "learned", grey, level=level)
                       for level in levels}
            main_detector = "learned" if uses_learned else params.detector
            detected = {main_detector: detect(main_detector, grey, clock)}  # (run, traces)
            if ridge is not None:
                detected["ridge"] = ridge.result()
            if uses_learned:
                runs = {1: detected["learned"], **{f: job.result() for f, job in pending.items()}}
                detected["learned"] = keep_grid("learned", runs)
            if params.detector == AUTO:
                choice = _ridge_or_learned(detected, work_shape, scale_of_grid, params)
            if uses_network and choice["kept"] == "learned":
                # the network's traces can replace only the pixel model's (§3.6): run when kept,
                # on every grid, the coarser ones on the other core, each reading the face the
                # pixel model's run on that grid flattened
                flat_of = {level: run.flat for level, (run, _) in runs.items()}
                pending = {level: pool.submit(timed, detect, "learned", grey, level=level,
                                              model=AUTO_NETWORK, flat_face=flat_of[level])
                           for level in levels}
                runs = {1: detect("learned", grey, clock, model=AUTO_NETWORK, flat_face=flat_of[1]),
                        **{f: job.result() for f, job in pending.items()}}
                detected[AUTO_NETWORK] = keep_grid(AUTO_NETWORK, runs)
        except BaseException:  # an error or Ctrl-C: the side tasks not begun are dropped
            pool.shutdown(wait=True, cancel_futures=True)
            raise
    clock.skip()  # the wait for the side tasks is no step's time
    for side_clock in side_clocks:
        clock.add(side_clock)
    del grey
    found = {detector: run for detector, (run, _) in detected.items()}
    maps = {detector: traces for detector, (_, traces) in detected.items()}
    if choice is not None:
        choice["traces"] = {d: len(found[d].chains) for d in found}
        if uses_network:
            choice["auto_network_ratio"] = params.auto_network_ratio
        if AUTO_NETWORK in maps:
            ratio = network_length_ratio(maps[AUTO_NETWORK], maps["learned"])
            choice["network_length_ratio"] = ratio
            if ratio >= params.auto_network_ratio:
                choice["kept"] = AUTO_NETWORK
    kept = params.detector if choice is None else choice["kept"]
    chain_of_kept = "learned" if kept == AUTO_NETWORK else kept  # the network's is the learned chain
    level = grid_of.get(kept, 1)
    if chain_of_kept == "learned":
        width_used = learned_width_on(level) * level
        if width_work > learned_width:
            notes.append(capped_note)
            width_source = f"{width_source}, capped"
        if level > 1:
            notes.append(f"the learned detector's traces come from the working grid coarsened "
                         f"{level} times, where they are the most joint-like (joints wide in "
                         f"pixels; learned_levels, docs/imaging.md §3.4)")
            width_source = f"{width_source}, grid coarsened {level}x"
        width_work = width_used
    params = given_params.for_detector(chain_of_kept).on_grid(scale_of_grid)
    chains, contrast, band, _, flat, response, binary, skeleton, pruned, face_contrast = found[kept]
    notes += _low_contrast_notes(face_contrast, params)
    model_of_kept = AUTO_NETWORK if kept == AUTO_NETWORK else given_params.pixel_model
    if chain_of_kept == "learned":
        from .site_back_end import unused_settings_note

        note = unused_settings_note(learned.load_model(model_of_kept).info,
                                    given_params.for_detector("learned"))
        notes += [] if note is None else [note]
    traces = maps[kept]
    clock.lap("vectorize")

    debug_images = {}
    if debug:
        debug_images = {"flattened": flat, "binary": binary, "skeleton": skeleton,
                        "pruned": _render(pruned, flat.shape)}
        debug_images = {key: grid_levels.resized(image, work_shape)  # a coarser grid's too
                        for key, image in debug_images.items()}
        for detector, run in found.items():  # "auto": every response, the rest of the kept one
            debug_images[_RESPONSE_NAMES[detector]] = grid_levels.resized(run.response, work_shape)
        if face_info["source"] == "face mask":
            debug_images["face_mask"] = mask
    for note in notes:
        if note.startswith("no scale"):
            warnings.warn(note, UserWarning, stacklevel=2)
    return Extraction(
        traces=traces,
        scale=ScaleInfo(m_per_px=scale, units=units, source=source, work_factor=factor,
                        work_shape_px=tuple(int(v) for v in work_shape), processing=processing,
                        grid_scale=scale_of_grid),
        params=given_params, joint_width_px=float(width_work / factor),
        joint_width_source=width_source, face_orientation=orientation,
        timings_s=MappingProxyType(dict(clock.timings)), warnings=tuple(notes),
        debug=MappingProxyType(debug_images), face_mask=MappingProxyType(face_info),
        detector_model=None if chain_of_kept != "learned" and "learned" not in found
        else MappingProxyType(learned.model_record(model_of_kept if chain_of_kept == "learned"
                                                   else given_params.pixel_model)),
        detector_choice=None if choice is None else MappingProxyType(choice),
        face_contrast=face_contrast,
        learned_levels=None if level_records.get(kept, level_records.get("learned")) is None
        else MappingProxyType(level_records.get(kept, level_records.get("learned"))))
