"""Synthetic face photographs with known joint traces, for tests, benchmarks and users' checks.

A trace network of 2–3 joint sets (von Mises scatter of the trace angle, lognormal lengths, gentle
wiggle, crossings, and T-terminations where a share of a younger set's traces stop at older traces)
is drawn as dark lines of 1–6 px width on a rock-like texture, then spoiled as a camera and a tunnel
face spoil it: uneven lighting, soft shadows, gaps where a trace is hidden (dirt, rock bridges),
sensor noise, blur and JPEG compression. The ground truth is the undamaged network as a
:class:`rockmass.dfn.TraceMap` in metres on the face frame (gaps are not in the truth: a good
extractor bridges them).

Difficulty levels set the spoiling (:data:`DIFFICULTIES`); "easy" is a clean, high-contrast face,
"moderate" the level the extraction targets are set at, "hard" shows where a method breaks.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .frame import check_scale, uv_to_rc

__all__ = ["JointSetSpec", "FaceStyle", "DIFFICULTIES", "DEFAULT_SETS", "SyntheticFace",
           "synthetic_network", "synthetic_face", "joints_on_photo", "in_flat_light", "save_synthetic_face"]


@dataclass(frozen=True)
class JointSetSpec:
    """One joint set of a synthetic 2D network.

    Attributes
    ----------
    angle_deg : float
        Mean trace angle, counter-clockwise from +u, 0–180.
    kappa : float
        von Mises concentration of the doubled angle 2θ (larger = tighter set).
    mean_length_m : float
        Mean trace length (lognormal).
    length_sigma : float
        Standard deviation of log length.
    intensity_per_m2 : float
        Trace centres per square metre (P20 before clipping and abutment).
    abut_fraction : float
        Share of this set's traces that stop at the first older trace they meet (T-terminations).
    """

    angle_deg: float
    kappa: float
    mean_length_m: float
    length_sigma: float
    intensity_per_m2: float
    abut_fraction: float = 0.0


DEFAULT_SETS = (JointSetSpec(25.0, 40.0, 2.6, 0.5, 0.55, 0.0),
                JointSetSpec(115.0, 25.0, 1.8, 0.45, 0.75, 0.5),
                JointSetSpec(160.0, 60.0, 3.2, 0.4, 0.3, 0.2))


@dataclass(frozen=True)
class FaceStyle:
    """How a synthetic face is rendered and spoiled (grey levels are 0–255)."""

    width_px: tuple[int, int] = (2, 4)  # range of line widths, inclusive
    contrast: float = 80.0  # how much darker a trace is than the rock
    texture: float = 12.0  # amplitude of the rock texture
    lighting: float = 0.15  # relative amplitude of the lighting gradient
    shadows: int = 0  # number of soft shadows
    gap_fraction: float = 0.0  # share of traces with a hidden stretch
    noise: float = 3.0  # sensor noise standard deviation
    blur_px: float = 0.5  # Gaussian blur sigma
    jpeg_quality: int = 95


DIFFICULTIES = {
    "easy": FaceStyle(),
    "moderate": FaceStyle(width_px=(1, 6), contrast=55.0, texture=18.0, lighting=0.3, shadows=2,
                          gap_fraction=0.15, noise=6.0, blur_px=0.8, jpeg_quality=85),
    "hard": FaceStyle(width_px=(1, 4), contrast=30.0, texture=28.0, lighting=0.45, shadows=4,
                      gap_fraction=0.35, noise=10.0, blur_px=1.2, jpeg_quality=60),
}


@dataclass(frozen=True)
class SyntheticFace:
    """A rendered face and its ground truth.

    Attributes
    ----------
    image : (H, W) uint8
        The photograph (grey, after JPEG compression).
    truth : TraceMap
        Trace centre lines in metres on the face frame, with ``set`` (1-based) and ``width_px``
        attributes; the window is the image rectangle.
    m_per_px : float
        Scale.
    difficulty : str
    seed : int
    style : FaceStyle
    """

    image: np.ndarray
    truth: object
    m_per_px: float
    difficulty: str
    seed: int
    style: FaceStyle = field(repr=False)


def _wiggly_polyline(p0, p1, rng, n_inner=3, amplitude=0.04):
    """A polyline from p0 to p1 with small perpendicular wiggle at evenly spaced inner vertices."""
    t = np.linspace(0.0, 1.0, n_inner + 2)[:, None]
    pts = p0 + t * (p1 - p0)
    d = p1 - p0
    length = max(float(np.hypot(*d)), 1e-12)
    normal = np.array([-d[1], d[0]]) / length
    offsets = rng.normal(0.0, amplitude * length / 4, size=(n_inner + 2, 1))
    offsets[[0, -1]] = 0.0
    return pts + offsets * normal


def synthetic_network(window_uv_m, sets=DEFAULT_SETS, *, rng: np.random.Generator,
                      min_length_m: float = 0.05):
    """A 2D trace network in a window polygon: older sets first, younger ones abutting.

    Parameters
    ----------
    window_uv_m : (k, 2) array_like
        The face outline (metres); traces are clipped to it.
    sets : sequence of JointSetSpec
        In order of age (the first is the oldest).
    rng : numpy.random.Generator
        All randomness; the same generator state gives the same network.
    min_length_m : float, default 0.05
        Clipped pieces shorter than this are dropped.

    Returns
    -------
    polylines : list of (k, 2) float64 arrays
    set_ids : (n,) int64
        1-based index into ``sets``.

    Notes
    -----
    The number of traces of a set is Poisson(intensity × area of the window's bounding box padded
    by one mean length), centres uniform in that padded box, angles θ = mean + ½·VM(0, κ) (von Mises
    on 2θ), lengths lognormal with the given mean. An abutting trace is cut at its first crossing
    with the traces drawn before it.
    """
    import shapely
    import shapely.ops

    window = np.asarray(window_uv_m, dtype=np.float64)
    face = shapely.Polygon(window)
    lo, hi = window.min(axis=0), window.max(axis=0)
    existing, polylines, set_ids = [], [], []
    for set_id, spec in enumerate(sets, start=1):
        pad = spec.mean_length_m
        box_lo, box_hi = lo - pad, hi + pad
        count = rng.poisson(spec.intensity_per_m2 * float(np.prod(box_hi - box_lo)))
        theta = np.deg2rad(spec.angle_deg) + 0.5 * rng.vonmises(0.0, spec.kappa, size=count)
        sigma = spec.length_sigma
        lengths = rng.lognormal(np.log(spec.mean_length_m) - 0.5 * sigma**2, sigma, size=count)
        centres = rng.uniform(box_lo, box_hi, size=(count, 2))
        abutting = rng.random(count) < spec.abut_fraction
        for c, th, length, stops in zip(centres, theta, lengths, abutting):
            d = 0.5 * length * np.array([np.cos(th), np.sin(th)])
            line = shapely.LineString(_wiggly_polyline(c - d, c + d, rng))
            if stops and existing:
                hits = line.intersection(shapely.union_all(existing))
                if not hits.is_empty:
                    first = min(line.project(p) for p in shapely.get_parts(hits))
                    if first > min_length_m:
                        line = shapely.ops.substring(line, 0.0, first)
            for part in shapely.get_parts(line.intersection(face)):
                if part.geom_type == "LineString" and part.length > min_length_m:
                    polylines.append(np.asarray(part.coords))
                    set_ids.append(set_id)
                    existing.append(part)
    return polylines, np.asarray(set_ids, dtype=np.int64)


def _smooth_noise(rng, shape, sigma_px):
    """Gaussian-filtered white noise scaled to unit standard deviation, as float32.

    Wide filters (sigma > 4 px) are applied on a grid coarsened by sigma / 2 and resized up
    (bicubic): the same smooth field at a small fraction of the cost of a wide kernel.
    """
    import cv2

    h, w = shape
    factor = max(sigma_px / 2.0, 1.0) if sigma_px > 4.0 else 1.0
    small = (max(int(np.ceil(h / factor)), 2), max(int(np.ceil(w / factor)), 2))
    noise = rng.standard_normal(small).astype(np.float32)
    smooth = cv2.GaussianBlur(noise, (0, 0), sigma_px / factor)
    if factor > 1.0:
        smooth = cv2.resize(smooth, (w, h), interpolation=cv2.INTER_CUBIC)
    return smooth / max(float(smooth.std()), 1e-12)


def _rock_texture(rng, shape, amplitude):
    """Multi-scale noise (grains to blotches) around a mid-grey, as float32."""
    h, w = shape
    base = np.full(shape, 150.0, dtype=np.float32)
    for sigma, weight in ((1.0, 0.35), (4.0, 0.35), (16.0, 0.2), (max(h, w) / 8, 0.3)):
        base += amplitude * weight * _smooth_noise(rng, shape, sigma)
    return base


def _lighting(rng, shape, amount, n_shadows):
    """Multiplicative illumination: a tilted gradient, a soft vignette and soft shadow blobs."""
    import cv2

    h, w = shape
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    angle = rng.uniform(0, 2 * np.pi)
    ramp = (np.cos(angle) * (xx / w - 0.5) + np.sin(angle) * (yy / h - 0.5))
    r2 = ((xx / w - 0.5) ** 2 + (yy / h - 0.5) ** 2)
    gain = 1.0 + amount * ramp - 0.5 * amount * r2
    shadow = np.zeros(shape, dtype=np.float32)
    for _ in range(n_shadows):
        centre = (int(rng.uniform(0, w)), int(rng.uniform(0, h)))
        axes = (int(rng.uniform(0.08, 0.25) * w), int(rng.uniform(0.08, 0.25) * h))
        cv2.ellipse(shadow, centre, axes, float(rng.uniform(0, 180)), 0, 360, 1.0, -1)
    if n_shadows:
        shadow = cv2.GaussianBlur(shadow, (0, 0), 0.03 * max(h, w))
        gain *= 1.0 - 0.45 * np.clip(shadow, 0.0, 1.0)
    return gain


def _joint_darkness(polylines, shape, m_per_px, style, rng):
    """Where the joints darken the face: 0-1 per pixel (anti-aliased lines of ``style.width_px``,
    a share ``style.gap_fraction`` of them with a hidden stretch), and each joint's width (px)."""
    import cv2

    h, w = shape
    darkness = np.zeros((h, w), dtype=np.float32)
    widths = rng.integers(style.width_px[0], style.width_px[1] + 1, size=len(polylines))
    gaps = rng.random(len(polylines)) < style.gap_fraction
    for poly, width, gap in zip(polylines, widths, gaps):
        rc = uv_to_rc(poly, h, m_per_px)
        xy = np.round(rc[:, ::-1] * 16).astype(np.int32)  # cv2 wants (x=col, y=row), 4-bit subpixel
        cv2.polylines(darkness, [xy], False, 1.0, thickness=int(width), lineType=cv2.LINE_AA, shift=4)
        if gap:  # hide a stretch of 5-15 % of the trace around a random point
            t = rng.uniform(0.2, 0.8)
            length = np.hypot(*np.diff(poly, axis=0).T).sum()
            centre = poly[0] + t * (poly[-1] - poly[0])
            radius_px = 0.5 * rng.uniform(0.05, 0.15) * length / m_per_px
            c_rc = uv_to_rc(centre[None, :], h, m_per_px)[0]
            cv2.circle(darkness, (int(c_rc[1]), int(c_rc[0])), max(int(radius_px), 2), 0.0, -1)
    return darkness, widths


def synthetic_face(difficulty: str = "moderate", *, seed: int = 0, shape_px=(1000, 1500),
                   m_per_px: float = 0.008, sets=DEFAULT_SETS, style: FaceStyle | None = None,
                   traces=None) -> SyntheticFace:
    """Render a synthetic face photograph and its ground-truth traces.

    Parameters
    ----------
    difficulty : {"easy", "moderate", "hard"}, default "moderate"
        Picks a :class:`FaceStyle` from :data:`DIFFICULTIES`.
    seed : int, default 0
        Root seed: the same seed and settings give the same image and truth on any machine.
    shape_px : (rows, cols), default (1000, 1500)
        Image size.
    m_per_px : float, default 0.008
        Scale; the default face is 12 m x 8 m.
    sets : sequence of JointSetSpec, default DEFAULT_SETS
    style : FaceStyle, optional
        Overrides the difficulty's style.
    traces : TraceMap, optional
        The traces to draw, in metres on the face frame (u right, v up from the image's bottom-left
        corner), e.g. a 3D network's section (:func:`rockmass.dfn.sample_plane`); its ``set``
        attribute is kept (default 1). Default: a network drawn from ``sets``
        (:func:`synthetic_network`). The rendering is that of the seed either way.

    Returns
    -------
    SyntheticFace
    """
    import cv2

    style, m_per_px = _checked_style(difficulty, style), check_scale(m_per_px)
    h, w = (int(v) for v in shape_px)
    if h < 16 or w < 16:
        raise ValueError(f"shape_px must be at least 16 x 16 pixels, got {shape_px}")
    network = _Network.draw(seed, (h, w), m_per_px, sets, traces)
    rock = _rock_texture(network.render_rng, (h, w), style.texture)
    darkness, widths = _joint_darkness(network.polylines, (h, w), m_per_px, style, network.render_rng)
    image = rock * _lighting(network.render_rng, (h, w), style.lighting, style.shadows)
    image -= style.contrast * np.clip(darkness, 0.0, 1.0) * (image / 150.0)
    image += style.noise * network.render_rng.standard_normal((h, w)).astype(np.float32)
    if style.blur_px > 0:
        image = cv2.GaussianBlur(image, (0, 0), style.blur_px)
    return SyntheticFace(image=_as_jpeg(image, style.jpeg_quality), truth=network.truth(widths),
                         m_per_px=m_per_px, difficulty=difficulty, seed=int(seed), style=replace(style))


def _checked_style(difficulty: str, style: FaceStyle | None) -> FaceStyle:
    """``style``, or the style of a known ``difficulty``."""
    if difficulty not in DIFFICULTIES:
        raise ValueError(f"difficulty must be one of {', '.join(DIFFICULTIES)}, got {difficulty!r}")
    return style or DIFFICULTIES[difficulty]


@dataclass
class _Network:
    """The joints of a face of ``seed`` (drawn from ``sets``, or given) in the image rectangle, and
    the random stream that renders them (the second child of the seed's ``SeedSequence``)."""

    window: np.ndarray
    polylines: list
    set_ids: np.ndarray
    render_rng: np.random.Generator

    @classmethod
    def draw(cls, seed, shape, m_per_px, sets, traces=None) -> _Network:
        h, w = shape
        network_rng, render_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
        window = np.array([[0.0, 0.0], [w * m_per_px, 0.0], [w * m_per_px, h * m_per_px],
                           [0.0, h * m_per_px]])
        if traces is None:
            polylines, set_ids = synthetic_network(window, sets, rng=network_rng)
        else:
            polylines = [np.asarray(traces.polyline(i), dtype=np.float64) for i in range(traces.n_traces)]
            set_ids = np.asarray(traces.attributes.get("set", np.ones(traces.n_traces)), dtype=np.int64)
        return cls(window, polylines, set_ids, render_rng)

    def truth(self, widths):
        """The drawn centre lines as a trace map (metres, the face frame), with set and width."""
        from ..dfn import TraceMap

        return TraceMap.from_polylines(
            self.polylines, attributes={"set": self.set_ids, "width_px": widths.astype(np.int64)},
            window=self.window, frame="face")


def _as_jpeg(image, quality: int) -> np.ndarray:
    """A float grey image rounded to 8 bits and passed through JPEG at ``quality`` (uint8)."""
    import cv2

    image = np.clip(np.round(image), 0, 255).astype(np.uint8)
    ok, encoded = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    return cv2.imdecode(encoded, cv2.IMREAD_GRAYSCALE)


def joints_on_photo(photo, difficulty: str = "moderate", *, seed: int = 0, m_per_px: float = 0.008,
                    sets=DEFAULT_SETS, style: FaceStyle | None = None) -> SyntheticFace:
    r"""Joints of known position drawn on a real photograph: the rock is real, the truth exact.

    The faces of :func:`synthetic_face` put the joints on a rock texture the same module draws, so a
    detector tuned on them may have learnt the texture. Here the network of :func:`synthetic_network`
    (window: the photo's rectangle at ``m_per_px``) is drawn onto a photograph of rock as
    :func:`synthetic_face` draws it onto its own rock: anti-aliased lines of the style's widths,
    some with a hidden stretch (the same joints, widths and hidden stretches as the synthetic face of
    the same seed, size and style), each darkening the photo by the same share of its local grey
    level,

    .. math:: I' = I\,(1 - c\,d / 150),

    with :math:`c` the style's ``contrast`` (grey levels at the synthetic rock's mid-grey, 150) and
    :math:`d \in [0, 1]` the line's coverage of the pixel, blurred by the style's ``blur_px``. The
    photo keeps its own light, noise and sharpness (the style's lighting, shadows, noise and texture
    are not applied); the result passes through JPEG at the style's quality. Fractures the photo
    already shows are not in the truth: score with them masked out (the benchmark
    ``benchmarks/bench_texture_faces.py`` does).

    Parameters
    ----------
    photo : (H, W) or (H, W, 3) uint8 array_like
        The rock, grey or RGB (converted to grey as :func:`rockmass.imaging.enhance.to_grey`).
    difficulty, seed, m_per_px, sets, style
        As :func:`synthetic_face`; ``seed`` draws the network and the rendering.

    Returns
    -------
    SyntheticFace
        ``image`` the photo's shape, grey uint8; ``truth`` the drawn centre lines in metres.

    Examples
    --------
    >>> rock = np.full((64, 96), 120, dtype=np.uint8)
    >>> face = joints_on_photo(rock, seed=3, m_per_px=0.05)
    >>> face.image.shape, float(face.image.mean()) < 119.5, face.truth.n_traces > 0
    ((64, 96), True, True)
    """
    import cv2

    from .enhance import to_grey

    style, m_per_px = _checked_style(difficulty, style), check_scale(m_per_px)
    photo = np.asarray(photo)
    if photo.dtype != np.uint8 or photo.ndim not in (2, 3) or min(photo.shape[:2]) < 16:
        raise ValueError("photo must be a grey or RGB uint8 image of at least 16 x 16 pixels, got "
                         f"{photo.dtype} of shape {photo.shape}")
    grey = 255.0 * to_grey(photo, name="photo")
    shape = grey.shape
    network = _Network.draw(seed, shape, m_per_px, sets)
    _rock_texture(network.render_rng, shape, style.texture)  # drawn, not used: the same stream below
    darkness, widths = _joint_darkness(network.polylines, shape, m_per_px, style, network.render_rng)
    if style.blur_px > 0:
        darkness = cv2.GaussianBlur(darkness, (0, 0), style.blur_px)
    image = grey * (1.0 - style.contrast / 150.0 * np.clip(darkness, 0.0, 1.0))
    return SyntheticFace(image=_as_jpeg(image, style.jpeg_quality), truth=network.truth(widths),
                         m_per_px=m_per_px, difficulty=difficulty, seed=int(seed), style=replace(style))

def in_flat_light(face: SyntheticFace, factor: float) -> SyntheticFace:
    r"""The same face photographed in flatter light: every grey level pulled towards the image's
    median, :math:`I' = \operatorname{med}(I) + f\,(I - \operatorname{med}(I))`, rounded to
    8 bits. The joints stay where they were, each darker than the face by ``factor`` times as
    much; the truth is unchanged.

    Examples
    --------
    >>> face = synthetic_face("easy", seed=1, shape_px=(40, 60), m_per_px=0.05)
    >>> dim = in_flat_light(face, 0.5)
    >>> int(np.ptp(dim.image)) <= int(np.ptp(face.image)) // 2 + 1, dim.truth is face.truth
    (True, True)
    """
    if not (isinstance(factor, (int, float)) and np.isfinite(factor) and 0 < factor <= 1):
        raise ValueError(f"factor must be in (0, 1], got {factor!r}")
    grey = face.image.astype(np.float64)
    median = np.median(grey)
    image = np.clip(np.round(median + factor * (grey - median)), 0, 255).astype(np.uint8)
    return replace(face, image=image)


def save_synthetic_face(face: SyntheticFace, directory) -> dict[str, Path]:
    """Write ``face.png`` (lossless copy of the JPEG-spoiled image), ``truth.geojson`` and
    ``meta.json`` (scale, difficulty, seed, style) into ``directory``; return the paths."""
    import dataclasses
    import json

    import cv2

    from ..dfn import write_traces
    from ..dfn.atomic import atomic_path

    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"image": folder / "face.png", "truth": folder / "truth.geojson",
             "meta": folder / "meta.json"}
    with atomic_path(paths["image"]) as tmp:
        if not cv2.imwrite(str(tmp), face.image):
            raise OSError(f"{paths['image']}: could not write the image")
    write_traces(face.truth, paths["truth"])
    meta = {"m_per_px": face.m_per_px, "difficulty": face.difficulty, "seed": face.seed,
            "shape_px": list(face.image.shape), "style": dataclasses.asdict(face.style)}
    with atomic_path(paths["meta"]) as tmp:
        tmp.write_text(json.dumps(meta, indent=2))
    return paths
