"""Field-like synthetic face photographs: what real faces show and the plain generator does not.

The faces of :mod:`rockmass.imaging.synthetic` are thin dark lines on noise; the chain's defaults are
tuned to them and score F1 0.97 there but 0.33 on real labelled photographs (issue 22). The
failures measured on real faces name what is missing, and :func:`field_face` draws it
(docs/imaging.md §9.1):

- **major joints** that are rough (a random walk across the face, not a gentle wiggle), often span
  the photograph, and are seen as a *dark core* of 2-12 px, often with a **shadow band** on one
  side (an overhang) and a **step edge** — the blocks either side lit differently, each shaded away
  from the joint. The label is the core's centre line, as a geologist traces it; optionally
  (``FieldStyle.crevice_share``, :data:`CREVICE_STYLE`) a share of them is a **wide open crevice**,
  a dark band up to 30 px across whose label is still its centre line, not its two edges;
- **distractors that are not labelled**: minor cracks (short, thin, faint), rubble (small dark and
  bright blobs with sharp rims), **bright plates and highlights** (polygons with sharp edges, soft
  specular spots), thin bright veins, dark blotches (lichen, wet patches);
- **oriented texture** (bedding streaks: noise smoothed along one direction), rock grain, uneven
  light with soft shadows, defocus blur, sensor noise and JPEG compression;
- **blast half-casts**, not labelled: the straight, parallel half-barrels of drill holes left on a
  drill-and-blast face, grooves shaded by the rock's light (a dark-bright line pair);
- **shotcrete** over parts of the face: smooth, uniformly grey, lobed edge; the joints under it are
  hidden, so the truth is cut there.

Everything is drawn from one seed (:class:`numpy.random.SeedSequence`), so the same seed gives the
same image and truth on any machine. Half-casts, shotcrete and wide crevices have streams of their
own, so turning them off gives the faces drawn before they were added (and turning the crevices on
widens some joints of the same faces, everything else unchanged). The result is a
:class:`~rockmass.imaging.synthetic.SyntheticFace` with ``difficulty = "field"``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from .frame import check_scale, rc_to_uv
from .synthetic import SyntheticFace, _lighting, _rock_texture, _smooth_noise

__all__ = ["FieldStyle", "TUNNEL_STYLE", "CREVICE_STYLE", "field_face", "centre_line_mask",
           "half_cast_axes", "minor_crack_mask", "shotcrete_mask", "shotcrete_area"]


@dataclass(frozen=True)
class FieldStyle:
    """Ranges the field-like faces are drawn from (grey levels 0–255, lengths in pixels).

    Each ``(lo, hi)`` is a uniform range a face (or a joint) draws its value from; counts are per
    400 x 400 px and scale with the image area, except the half-cast families (per face). The
    half-casts and shotcrete are sized in metres and drawn at the face's ``m_per_px``.

    ``feature_scale`` k draws the face as a camera with k times the pixels across would see it:
    every size in pixels (joint widths and paths, shadows, clutter, blur, the shortest truth
    piece) is multiplied by k, every count per 400 x 400 px divided by k², and the fields drawn
    as noise (the rock, the shotcrete, the sensor noise) are drawn on the grid of the face of
    k = 1 and enlarged. A face of k times the shape at ``m_per_px / k`` is then the face of
    k = 1 from the same seed at k times the pixels: the same joints in metres, and averaged
    down k times nearly the same image (docs/imaging.md §9.1). The default, 1, draws the faces
    drawn before it existed.
    """

    major_joints: tuple[int, int] = (1, 5)
    core_width_px: tuple[float, float] = (2.0, 12.0)
    core_depth: tuple[float, float] = (0.25, 0.75)  # relative darkening of the core
    shadow_share: float = 0.5  # share of joints with a one-sided shadow band
    shadow_width_px: tuple[float, float] = (4.0, 24.0)
    shadow_depth: tuple[float, float] = (0.15, 0.45)
    step_share: float = 0.6  # share of spanning joints with a step edge (blocks lit differently)
    step_contrast: tuple[float, float] = (15.0, 60.0)
    minor_cracks: tuple[int, int] = (10, 60)
    crevice_fields: tuple[int, int] = (0, 2)  # fields of curvy texture loops
    rubble: tuple[int, int] = (0, 40)
    plates: tuple[int, int] = (0, 4)
    veins: tuple[int, int] = (0, 2)
    texture: tuple[float, float] = (10.0, 28.0)
    relief: tuple[float, float] = (0.05, 0.35)  # typical surface slope of the rock's lumps
    oriented_texture: tuple[float, float] = (0.0, 12.0)
    lighting: tuple[float, float] = (0.1, 0.5)
    shadows: tuple[int, int] = (0, 3)
    noise: tuple[float, float] = (1.5, 6.0)
    blur_px: tuple[float, float] = (0.4, 2.0)
    jpeg_quality: tuple[int, int] = (55, 95)
    # blast half-casts (not labelled): families per face (not scaled with the area), holes per
    # family. Off by default, as shotcrete: the default faces (and the shipped model trained on
    # them, and the benchmarks' figures) stay those drawn before; TUNNEL_STYLE turns both on
    half_cast_families: tuple[int, int] = (0, 0)
    half_casts_per_family: tuple[int, int] = (3, 8)
    half_cast_diameter_m: tuple[float, float] = (0.045, 0.051)
    half_cast_spacing_m: tuple[float, float] = (0.3, 0.8)
    half_cast_length_m: tuple[float, float] = (0.8, 4.0)
    half_cast_fan_share: float = 0.3  # share of families drilled as a fan, not parallel
    half_cast_crack_share: float = 0.3  # share of half-casts with a thin crack along the axis
    # shotcrete: share of faces with any, and the covered fraction of the image
    shotcrete_share: float = 0.0
    shotcrete_cover: tuple[float, float] = (0.0, 0.35)
    # wide open crevices: share of the major joints whose core is drawn wide and dark instead
    # (labelled at the centre line all the same). Off by default, as the half-casts
    crevice_share: float = 0.0
    crevice_width_px: tuple[float, float] = (12.0, 30.0)
    crevice_depth: tuple[float, float] = (0.6, 0.9)
    crevice_blur: tuple[float, float] = (0.05, 0.2)  # edge softness, times the crevice's width
    # pixels per feature: sizes in pixels times this, counts per 400 x 400 px over its square
    feature_scale: float = 1.0


#: A drill-and-blast tunnel face: the field-like faces with blast half-casts (0-2 families) and
#: shotcrete on 40 % of the faces (up to 35 % of the image).
TUNNEL_STYLE = FieldStyle(half_cast_families=(0, 2), shotcrete_share=0.4)

#: Field-like faces where a quarter of the major joints are wide open crevices (a dark core of
#: 12-30 px): the model is to mark such a band's centre line, not its two edges.
CREVICE_STYLE = FieldStyle(crevice_share=0.25)


def _rough_path(rng, start, angle, length_px, step_px=6.0, roughness=0.35, scale=1.0):
    """A rough polyline (rc pixels): a walk of ``step_px`` steps whose heading wanders around
    ``angle`` (radians) by an Ornstein–Uhlenbeck turn, ``roughness`` radians at most per step.
    ``length_px`` and ``step_px`` are pixels of the reference face (feature scale 1); the walk is
    drawn ``scale`` times larger, with the same number of steps and draws."""
    n = max(int(length_px / step_px), 2)
    step_px = scale * step_px
    heading, pts = 0.0, [np.asarray(start, dtype=np.float64)]
    for _ in range(n):
        heading = 0.8 * heading + rng.normal(0.0, roughness / 2)
        a = angle + np.clip(heading, -roughness * 2, roughness * 2)
        pts.append(pts[-1] + step_px * np.array([np.sin(a), np.cos(a)]))
    return np.array(pts)


def _draw(canvas, rc, value, width):
    """Draw a polyline (rc pixels) into a float32 canvas, anti-aliased, 4-bit sub-pixel."""
    import cv2

    xy = np.round(rc[:, ::-1] * 16).astype(np.int32)
    cv2.polylines(canvas, [xy], False, float(value), thickness=max(int(round(width)), 1),
                  lineType=cv2.LINE_AA, shift=4)


def _offset(rc, distance):
    """The polyline shifted sideways by ``distance`` pixels (along the local left normal)."""
    d = np.gradient(rc, axis=0)
    d /= np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
    return rc + distance * np.column_stack([-d[:, 1], d[:, 0]])


def _side_mask(rc, shape):
    """Pixels on the left of a polyline that crosses the image (bool), from the connected pieces
    of the image minus the drawn line; None when the line does not cut the image in two."""
    import cv2

    line = np.zeros(shape, dtype=np.float32)
    _draw(line, rc, 1.0, 2)
    n, labels = cv2.connectedComponents((line < 0.5).astype(np.uint8), connectivity=4)
    if n != 3:
        return None
    probe = np.round(_offset(rc, 4.0)).astype(int)
    inside = (probe[:, 0] >= 0) & (probe[:, 0] < shape[0]) & (probe[:, 1] >= 0) & (probe[:, 1] < shape[1])
    hits = labels[probe[inside, 0], probe[inside, 1]]
    hits = hits[hits > 0]
    if hits.size == 0:
        return None
    return labels == np.bincount(hits).argmax()


def _oriented_texture(rng, shape, amplitude):
    """Bedding-like streaks: noise smoothed far more along a random direction than across it."""
    import cv2

    if amplitude <= 0:
        return np.zeros(shape, dtype=np.float32)
    h, w = shape
    side = int(np.ceil(np.hypot(h, w))) + 2
    noise = rng.standard_normal((side, side)).astype(np.float32)
    streaks = cv2.GaussianBlur(noise, (0, 0), sigmaX=rng.uniform(10, 40), sigmaY=rng.uniform(1.5, 5.0))
    turn = cv2.getRotationMatrix2D((side / 2, side / 2), float(rng.uniform(0, 180)), 1.0)
    streaks = cv2.warpAffine(streaks, turn, (side, side), flags=cv2.INTER_LINEAR)
    r0, c0 = (side - h) // 2, (side - w) // 2
    out = streaks[r0:r0 + h, c0:c0 + w]
    return amplitude * out / max(float(out.std()), 1e-12)


def _light_direction(rng):
    """A unit light vector (row, col, toward-camera components), 30-70° from the viewing
    direction at a random azimuth: a headlamp or flash held beside the camera."""
    azimuth, tilt = rng.uniform(0, 2 * np.pi), np.radians(rng.uniform(30, 70))
    return np.array([np.sin(tilt) * np.sin(azimuth), np.sin(tilt) * np.cos(azimuth), np.cos(tilt)])


def _lambert(g_r, g_c, light):
    """Lambert shading of a surface of slopes (g_r, g_c) lit by ``light``, 1 where it is flat."""
    shade = (-g_r * light[0] - g_c * light[1] + light[2]) / np.sqrt(1 + g_r * g_r + g_c * g_c)
    return (np.maximum(shade, 0.05) / light[2]).astype(np.float32)


def _shaded_relief(rng, shape, relief):
    r"""Lambert shading of a rough surface: lumps, ledges and crevices lit from one side.

    The height is multi-scale smooth noise, :math:`z = \sum_k r\,\sigma_k a_k n_{\sigma_k}` (a_k
    decreasing weights, n unit-variance smoothed noise), so slopes are of order r at every scale;
    the shading is :math:`\max(\hat n \cdot \hat l, 0) / \hat l_z` for the surface normal
    :math:`\hat n \propto (-\partial_c z, -\partial_r z, 1)` and a light 30-70° from the viewing
    direction, so a flat patch keeps its brightness. Returns the shading and the light (None when
    ``relief`` is 0: a flat face, nothing drawn).
    """
    if relief <= 0:
        return np.ones(shape, dtype=np.float32), None
    height = np.zeros(shape, dtype=np.float32)
    for sigma, weight in ((1.5, 0.25), (4.0, 0.5), (12.0, 0.8), (36.0, 1.0)):
        height += relief * sigma * weight * _smooth_noise(rng, shape, sigma)
    g_r, g_c = np.gradient(height)
    light = _light_direction(rng)
    return _lambert(g_r, g_c, light), light


def _feature_scale(style) -> float:
    """``style.feature_scale``, checked: finite and > 0."""
    k = float(style.feature_scale)
    if not (np.isfinite(k) and k > 0):
        raise ValueError(f"FieldStyle.feature_scale must be finite and > 0, got {style.feature_scale!r}")
    return k


def _area_factor(shape, style) -> float:
    """The area of the reference face (feature scale 1) an image of ``shape`` enlarges, in units
    of 400 x 400 px: what the counts per 400 x 400 px are multiplied by."""
    h, w = _reference_shape(shape, _feature_scale(style))
    return h * w / 160_000.0


def _extent(shape, style) -> tuple[float, float]:
    """The reference face's rows and columns times the feature scale: the extent, in pixels of
    ``shape``, that positions are drawn over (``shape`` itself at scale 1), so that a position
    drawn from the same number lies at the same place on the face at every scale."""
    k = _feature_scale(style)
    h, w = _reference_shape(shape, k)
    return k * h, k * w


def _count(rng, bounds, area_factor):
    """A count drawn from ``bounds`` (per 400 x 400 px), scaled to the image area."""
    return int(round(rng.integers(bounds[0], bounds[1] + 1) * area_factor))


def _minor_cracks(rng, shape, style, area_factor):
    """The unlabelled minor cracks: (rc path, width px, relative darkening) each, short (8-90 px),
    rough, 1-3 px wide and faint (0.08-0.5), sizes times ``style.feature_scale``. The first draws
    of the clutter stream."""
    h, w = _extent(shape, style)
    k = _feature_scale(style)
    cracks = []
    for _ in range(_count(rng, style.minor_cracks, area_factor)):
        start = rng.uniform(0, 1, 2) * (h, w)
        path = _rough_path(rng, start, rng.uniform(0, 2 * np.pi), rng.uniform(8, 90), step_px=3.0,
                           roughness=0.6, scale=k)
        width = k * rng.choice([1, 1, 2, 3])
        cracks.append((path, width, rng.uniform(0.08, 0.5)))
    return cracks


def _major_joints(rng, shape, style, area_factor):
    """Polylines (rc pixels) of the major joints: two sets, most spanning the image."""
    k = _feature_scale(style)
    h, w = _extent(shape, style)
    diag = float(np.hypot(*_reference_shape(shape, k)))  # pixels of the reference face
    n = max(_count(rng, style.major_joints, area_factor), 1)
    centre_shift = 0.5 * (k - 1.0)
    set_angles = rng.uniform(0, np.pi) + np.array([0.0, rng.uniform(np.pi / 4, np.pi / 2)])
    paths = []
    for _ in range(n):
        angle = set_angles[int(rng.random() < 0.35)] + rng.normal(0, np.radians(8))
        # drawn on the pixel-edge frame: the same place in metres at every feature scale
        centre = np.array([rng.uniform(0.1, 0.9) * h, rng.uniform(0.1, 0.9) * w]) + centre_shift
        spans = rng.random() < 0.7
        half = diag if spans else rng.uniform(0.2, 0.45) * diag
        back = _rough_path(rng, centre, angle + np.pi, half, roughness=rng.uniform(0.1, 0.4), scale=k)
        ahead = _rough_path(rng, centre, angle, half, roughness=rng.uniform(0.1, 0.4), scale=k)
        paths.append(np.vstack([back[::-1], ahead[1:]]))
    return paths


def _clip_to_image(paths_rc, shape, hidden=None, min_length_px=10.0):
    """Pieces of the polylines inside the image rectangle (pixel-centre extent) and outside the
    ``hidden`` area (a shapely geometry in rc pixels, e.g. shotcrete), as rc arrays, those shorter
    than ``min_length_px`` left out."""
    import shapely

    h, w = shape
    frame = shapely.box(-0.5, -0.5, h - 0.5, w - 0.5)
    if hidden is not None and not hidden.is_empty:
        frame = frame.difference(hidden)
    pieces = []
    for rc in paths_rc:
        clipped = shapely.LineString(rc).intersection(frame)
        for part in shapely.get_parts(clipped):
            if part.geom_type == "LineString" and part.length >= min_length_px:
                pieces.append(np.asarray(part.coords))
    return pieces


def _half_cast_layout(rng, shape, style, m_per_px):
    """Axes of the blast half-casts: a list of families, each a list of holes ``(p0, p1, radius_px,
    crack)`` with ends p0, p1 in rc pixels and ``crack`` the darkening of an axial crack (0: none).

    Drill-and-blast rounds are drilled with parallel holes (a fan on some contours); what survives
    the blast on the rock is the half of each hole's barrel. Face-drilling bits are 45-51 mm across;
    contour holes are spaced about 10-15 diameters apart in smooth blasting (0.5-0.8 m) and closer in
    presplitting (0.3-0.5 m), as tunnelling drill-and-blast handbooks give them; a visible
    half-cast is at most the round length (3-5 m), usually less where the barrel broke away.
    All sizes are drawn in metres and converted with ``m_per_px``.
    """
    h, w = shape
    families = []
    for _ in range(int(rng.integers(style.half_cast_families[0], style.half_cast_families[1] + 1))):
        n = max(int(rng.integers(style.half_casts_per_family[0], style.half_casts_per_family[1] + 1)), 1)
        angle = rng.uniform(0, np.pi)
        fan = np.radians(rng.uniform(1.0, 4.0)) if rng.random() < style.half_cast_fan_share else 0.0
        spacing = rng.uniform(*style.half_cast_spacing_m) / m_per_px
        length = rng.uniform(*style.half_cast_length_m) / m_per_px
        radius = rng.uniform(*style.half_cast_diameter_m) / 2 / m_per_px
        centre = rng.uniform(0, 1, 2) * (h, w)
        axis = np.array([np.sin(angle), np.cos(angle)])
        normal = np.array([-axis[1], axis[0]])
        holes = []
        for k in range(n):
            offset = k - (n - 1) / 2
            mid = (centre + offset * spacing * rng.uniform(0.9, 1.1) * normal
                   + rng.uniform(-0.15, 0.15) * length * axis)
            a = angle + offset * fan
            direction = np.array([np.sin(a), np.cos(a)])
            half = 0.5 * length * rng.uniform(0.6, 1.0)
            crack = rng.uniform(0.2, 0.5) if rng.random() < style.half_cast_crack_share else 0.0
            holes.append((mid - half * direction, mid + half * direction, radius, crack))
        families.append(holes)
    return families


def _half_cast_shade(shape, families, light, crack_width_px=1.0):
    """Multiplicative shading (1 off the grooves) of half-cylindrical grooves along the given axes.

    Across a groove of radius R the surface is :math:`z = -\\sqrt{R^2 - d^2}` (d the distance from the
    axis), Lambert-shaded with the face's light: the wall facing the light is bright, the other
    dark, and the part of the groove the rim hides from the light (the ray leaves through the wall,
    not the opening) is in shadow at an ambient 0.45 — the dark-bright line pair of a half-cast.
    The shading's departure from 1 is doubled (fresh blasted rock in a groove glints, and its
    walls are steeper than a flat face ever is), and the bottom is slightly darker (less sky seen).
    An axial crack is a thin dark line, ``crack_width_px`` wide, along the groove's bottom.
    """
    h, w = shape
    shade = np.ones(shape, dtype=np.float32)
    for p0, p1, radius, crack in (hole for family in families for hole in family):
        lo = np.floor(np.minimum(p0, p1) - radius - 2).astype(int)
        hi = np.ceil(np.maximum(p0, p1) + radius + 2).astype(int)
        r0, c0, r1, c1 = max(lo[0], 0), max(lo[1], 0), min(hi[0], h), min(hi[1], w)
        if r0 >= r1 or c0 >= c1:
            continue
        rr, cc = np.mgrid[r0:r1, c0:c1].astype(np.float64)
        length = float(np.hypot(*(p1 - p0)))
        axis = (p1 - p0) / max(length, 1e-9)
        normal = np.array([-axis[1], axis[0]])
        t = (rr - p0[0]) * axis[0] + (cc - p0[1]) * axis[1]
        d = (rr - p0[0]) * normal[0] + (cc - p0[1]) * normal[1]
        inside = (np.abs(d) < radius) & (t >= 0) & (t <= length)
        if not inside.any():
            continue
        d = np.clip(d[inside], -0.97 * radius, 0.97 * radius)
        depth = np.sqrt(radius * radius - d * d)
        slope = d / depth  # dz/dd, across the groove
        l_n = light[0] * normal[0] + light[1] * normal[1]
        lit = np.abs(d + l_n * depth / light[2]) <= radius  # the light ray leaves by the opening
        local = _lambert(slope * normal[0], slope * normal[1], light)
        local = np.where(lit, np.clip(1.0 + 2.0 * (local - 1.0), 0.45, 2.2), 0.45)
        local *= 1.0 - 0.1 * depth / radius
        window = shade[r0:r1, c0:c1]
        window[inside] *= local.astype(np.float32)
        if crack > 0:
            line = np.zeros(shape, dtype=np.float32)
            _draw(line, np.array([p0, p1]), 1.0, crack_width_px)
            shade *= 1.0 - crack * line
    return shade


def _shotcrete_cover(rng, shape, style, m_per_px):
    """Where shotcrete covers the face: ``(score, level)`` with the cover ``score > level``, or None.

    Sprayed concrete in a heading is applied to the crown and walls right behind the face and
    overspray reaches the face's rim, or it seals loose patches of the face as blobs; either way
    the edge is lobed, following how the nozzle was swept. Drawn here as a closeness to one image
    edge (the top most often, as the crown) or to 1-3 blob centres, plus smooth noise of a 0.15-0.5 m
    scale for the lobes, thresholded at the quantile that covers the drawn fraction exactly. The
    score is drawn on the reference grid of ``style.feature_scale`` and enlarged to ``shape``.
    """
    if rng.random() >= style.shotcrete_share:
        return None
    fraction = rng.uniform(*style.shotcrete_cover)
    if fraction < 0.005:
        return None
    k = _feature_scale(style)
    ref_shape, ref_m_per_px = _reference_shape(shape, k), m_per_px * k
    h, w = ref_shape
    diag = float(np.hypot(h, w))
    rr, cc = np.mgrid[0:h, 0:w].astype(np.float32)
    if rng.random() < 0.6:  # along the face's rim: top (crown) twice as likely as another edge
        edge = int(rng.choice(4, p=[0.4, 0.2, 0.2, 0.2]))
        bias = -(rr, h - 1 - rr, cc, w - 1 - cc)[edge] / diag
    else:
        centres = rng.uniform(0, 1, (int(rng.integers(1, 4)), 2)) * (h, w)
        bias = -np.min([np.hypot(rr - r, cc - c) for r, c in centres], axis=0) / diag
    sigma = float(np.clip(rng.uniform(0.15, 0.5) / ref_m_per_px, 3.0, 0.3 * max(h, w)))
    score = _enlarged(bias + rng.uniform(0.05, 0.15) * _smooth_noise(rng, ref_shape, sigma), shape)
    return score, float(np.quantile(score, 1.0 - fraction))


def _cover_polygon(score, level):
    """The area ``score > level`` as a shapely geometry in rc pixels (sub-pixel iso-line)."""
    import shapely
    from skimage.measure import find_contours

    padded = np.pad(score, 1, constant_values=float(score.min()) - 1.0)
    area = shapely.Polygon()
    for ring in find_contours(padded, level):
        if len(ring) >= 4:
            area = area.symmetric_difference(shapely.make_valid(shapely.Polygon(ring - 1.0)))
    return area


def _shotcrete_surface(rng, shape, m_per_px, light):
    """Grey levels of a shotcrete skin: one uniform tone (lighter than most rock), gentle bumps of
    2-15 cm Lambert-shaded with the face's light, and a faint fine grain — sprayed concrete
    smooths the rock's roughness out and shows neither joints nor grain."""
    tone = rng.uniform(140.0, 200.0)
    slope = rng.uniform(0.03, 0.12)
    height = np.zeros(shape, dtype=np.float32)
    for sigma_m, weight in ((0.02, 0.4), (0.06, 0.7), (0.15, 1.0)):
        sigma = max(sigma_m / m_per_px, 1.0)
        height += slope * sigma * weight * _smooth_noise(rng, shape, sigma)
    g_r, g_c = np.gradient(height)
    grain = rng.uniform(1.0, 3.0) * _smooth_noise(rng, shape, 0.8)
    return tone * _lambert(g_r, g_c, light) + grain


def _rock(rng, shape, style):
    """The bare rock of a field face on a grid of ``shape`` (float32 grey levels) and the light
    that shades it (None for a flat face): grain and blotches, shaded relief, bedding streaks, dark
    patches (lichen, wet rock) and fields of crevice loops (the zero level of a smooth field:
    grain boundaries, the texture loops a line filter mistakes for joints). Every draw of the
    face's rock stream."""
    h, w = shape
    image = _rock_texture(rng, (h, w), rng.uniform(*style.texture))
    relief, light = _shaded_relief(rng, (h, w), rng.uniform(*style.relief))
    image *= relief
    image += _oriented_texture(rng, (h, w), rng.uniform(*style.oriented_texture))
    blotch = np.clip(_smooth_noise(rng, (h, w), rng.uniform(6, 20)) - 1.2, 0, None)
    image -= rng.uniform(0, 40) * np.clip(blotch, 0, 1)
    for _ in range(int(rng.integers(style.crevice_fields[0], style.crevice_fields[1] + 1))):
        level = _smooth_noise(rng, (h, w), rng.uniform(5, 18))
        grad = np.hypot(*np.gradient(level)) + 1e-6
        loops = np.exp(-0.5 * (level / (grad * rng.uniform(0.6, 1.6))) ** 2)
        patchy = np.clip(_smooth_noise(rng, (h, w), 20.0) + 0.5, 0, 1)  # only in places
        image *= 1.0 - rng.uniform(0.1, 0.45) * loops * patchy
    return image, light


def _reference_shape(shape, feature_scale: float) -> tuple[int, int]:
    """The grid of the face at feature scale 1 that a face of ``shape`` at ``feature_scale``
    enlarges (``shape`` itself at 1)."""
    return tuple(max(int(round(n / feature_scale)), 2) for n in shape)


def _enlarged(field, shape):
    """A float32 field drawn on the reference grid resized to ``shape`` (bicubic; area averaging
    for a feature scale under 1); the field itself when it is already of that shape."""
    import cv2

    if field.shape == tuple(shape):
        return field
    shrink = shape[0] * shape[1] < field.shape[0] * field.shape[1]
    return cv2.resize(field, (shape[1], shape[0]),
                      interpolation=cv2.INTER_AREA if shrink else cv2.INTER_CUBIC)


def _streams(seed):
    """The face's random streams: network, rock, joints, clutter, camera, half-casts, shotcrete,
    crevices.

    Children of one :class:`numpy.random.SeedSequence`; spawning more children leaves the first
    ones unchanged, so the elements added later (half-casts, shotcrete, crevices) do not alter the
    others.
    """
    return [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(8)]


class _Crevice(NamedTuple):
    """A major joint drawn as a wide open crevice: core width (px), relative darkening, and the
    Gaussian blur of its edges (px)."""

    width_px: float
    depth: float
    blur_px: float


def _crevice(rng, style) -> _Crevice | None:
    """The crevice a major joint is drawn as, or None for an ordinary joint (a share
    ``style.crevice_share`` are crevices). Nothing is drawn from ``rng`` when the share is 0, so the
    default faces stay those drawn before.

    An open crevice seen face-on is a band in shadow: darker than most joint cores, its edges the
    rims of the two blocks, fairly sharp; a pixel classifier sees its two edges as two thin dark
    lines unless taught that the label lies between them.
    """
    if style.crevice_share <= 0 or rng.random() >= style.crevice_share:
        return None
    k = _feature_scale(style)
    width = k * rng.uniform(*style.crevice_width_px)
    return _Crevice(width, rng.uniform(*style.crevice_depth),
                    max(width * rng.uniform(*style.crevice_blur), k * 0.6))


def field_face(*, seed: int = 0, shape_px=(400, 400), m_per_px: float = 0.005,
               style: FieldStyle | None = None) -> SyntheticFace:
    """Render a field-like synthetic face photograph and the centre lines of its major joints.

    Parameters
    ----------
    seed : int, default 0
        Root seed: the same seed, shape and style give the same image and truth.
    shape_px : (rows, cols), default (400, 400)
        Image size, at least 32 x 32. Feature sizes are in pixels (times ``style.feature_scale``);
        counts scale with the area (over the feature scale squared).
    m_per_px : float, default 0.005
        Scale of the truth.
    style : FieldStyle, optional
        The ranges drawn from (default :class:`FieldStyle`).

    Returns
    -------
    SyntheticFace
        ``image`` (H, W) uint8 grey, JPEG-spoiled; ``truth`` the major joints' centre lines (a
        TraceMap in metres on the face frame, attribute ``width_px`` = core width rounded), cut
        where shotcrete hides them (:func:`shotcrete_area`); ``difficulty = "field"``. The window
        stays the image rectangle.

    Examples
    --------
    >>> face = field_face(seed=3, shape_px=(120, 160))
    >>> face.image.shape, face.image.dtype.name, face.truth.n_traces > 0
    ((120, 160), 'uint8', True)
    """
    import cv2

    from ..dfn import TraceMap

    style = style or FieldStyle()
    m_per_px = check_scale(m_per_px)
    h, w = (int(v) for v in shape_px)
    if h < 32 or w < 32:
        raise ValueError(f"shape_px must be at least 32 x 32 pixels, got {shape_px}")
    k = _feature_scale(style)
    area, extent = _area_factor((h, w), style), _extent((h, w), style)
    (net_rng, rock_rng, joint_rng, clutter_rng, camera_rng, cast_rng, spray_rng,
     crevice_rng) = _streams(seed)

    # the rock, drawn on the reference grid (k = 1) and enlarged: the same rock at any scale
    image, light = _rock(rock_rng, _reference_shape((h, w), k), style)
    image = _enlarged(image, (h, w))

    # blast half-casts: straight grooves of the drill holes, shaded with the rock's light
    light = light if light is not None else np.array([0.5, 0.5, np.sqrt(0.5)])
    casts = _half_cast_layout(cast_rng, (h, w), style, m_per_px)
    if casts:
        image *= _half_cast_shade((h, w), casts, light, crack_width_px=k)

    paths = _major_joints(net_rng, (h, w), style, area)
    darkness = np.zeros((h, w), dtype=np.float32)
    widths = []
    for rc in paths:
        width = k * joint_rng.uniform(*style.core_width_px)
        crevice = _crevice(crevice_rng, style)  # the joint stream's draws stay the same either way
        if crevice is not None:
            width = crevice.width_px
        widths.append(width)
        if joint_rng.random() < style.step_share:  # blocks lit differently, shaded away from it
            side = _side_mask(rc, (h, w))
            if side is not None:
                line = np.ones((h, w), dtype=np.float32)
                _draw(line, rc, 0.0, 1)
                dist = cv2.distanceTransform((line > 0.5).astype(np.uint8), cv2.DIST_L2, 3)
                fade = np.exp(-dist / (k * joint_rng.uniform(15, 120)))
                step = joint_rng.uniform(*style.step_contrast) * joint_rng.choice([-1.0, 1.0])
                image += np.where(side, step, -0.3 * step) * fade
        if joint_rng.random() < style.shadow_share:  # one-sided shadow band beside the core
            band = np.zeros((h, w), dtype=np.float32)
            shadow_w = k * joint_rng.uniform(*style.shadow_width_px)
            sign = joint_rng.choice([-1.0, 1.0])
            _draw(band, _offset(rc, sign * (width + shadow_w) / 2), 1.0, shadow_w)
            band = cv2.GaussianBlur(band, (0, 0), max(shadow_w / 4, k))
            darkness = np.maximum(darkness, joint_rng.uniform(*style.shadow_depth) * band)
        core = np.zeros((h, w), dtype=np.float32)
        _draw(core, rc, 1.0, width)
        core = cv2.GaussianBlur(core, (0, 0),
                                max(width / 5, k * 0.6) if crevice is None else crevice.blur_px)
        depth = joint_rng.uniform(*style.core_depth)
        if crevice is not None:
            depth = crevice.depth
        if joint_rng.random() < 0.4:  # a faint stretch (rock bridge, dirt) along the joint
            t = joint_rng.uniform(0.1, 0.9)
            centre = rc[int(t * (len(rc) - 1))]
            cv2.circle(core, (int(centre[1]), int(centre[0])), int(k * joint_rng.uniform(5, 25)), 0.3,
                       -1)
        darkness = np.maximum(darkness, depth * np.clip(core, 0, 1))

    # clutter, not labelled: minor cracks, rubble, bright plates, highlights, veins
    for crack, width, depth in _minor_cracks(clutter_rng, (h, w), style, area):
        mark = np.zeros((h, w), dtype=np.float32)
        _draw(mark, crack, 1.0, width)
        mark = cv2.GaussianBlur(mark, (0, 0), k * 0.7)
        darkness = np.maximum(darkness, depth * mark)
    for _ in range(_count(clutter_rng, style.rubble, area)):
        centre = (int(clutter_rng.uniform(0, extent[1])), int(clutter_rng.uniform(0, extent[0])))
        axes = (int(k * clutter_rng.uniform(2, 14)), int(k * clutter_rng.uniform(2, 10)))
        tone = clutter_rng.uniform(-50, 40)
        blob = np.zeros((h, w), dtype=np.float32)
        cv2.ellipse(blob, centre, axes, float(clutter_rng.uniform(0, 180)), 0, 360, 1.0, -1)
        image += tone * cv2.GaussianBlur(blob, (0, 0), k * 0.7)
    for _ in range(_count(clutter_rng, style.plates, area)):
        centre = clutter_rng.uniform(0, 1, 2) * extent[::-1]
        n_vert = int(clutter_rng.integers(4, 8))
        angles = np.sort(clutter_rng.uniform(0, 2 * np.pi, n_vert))
        radius = k * clutter_rng.uniform(15, 90) * clutter_rng.uniform(0.6, 1.0, n_vert)
        poly = np.column_stack([centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles)])
        plate = np.zeros((h, w), dtype=np.float32)
        cv2.fillPoly(plate, [np.round(poly).astype(np.int32)], 1.0, lineType=cv2.LINE_AA)
        image += clutter_rng.uniform(15, 70) * cv2.GaussianBlur(plate, (0, 0),
                                                                k * clutter_rng.uniform(0.6, 2.0))
    for _ in range(int(clutter_rng.integers(0, 3))):  # soft specular highlights
        spot = np.zeros((h, w), dtype=np.float32)
        cv2.circle(spot, (int(clutter_rng.uniform(0, extent[1])), int(clutter_rng.uniform(0, extent[0]))),
                   int(k * clutter_rng.uniform(5, 40)), 1.0, -1)
        image += clutter_rng.uniform(20, 60) * cv2.GaussianBlur(spot, (0, 0),
                                                                k * clutter_rng.uniform(3, 12))
    for _ in range(_count(clutter_rng, style.veins, area)):
        vein = np.zeros((h, w), dtype=np.float32)
        _draw(vein, _rough_path(clutter_rng, clutter_rng.uniform(0, 1, 2) * extent,
                                clutter_rng.uniform(0, 2 * np.pi), clutter_rng.uniform(40, 300),
                                roughness=0.2, scale=k), 1.0, k * clutter_rng.uniform(1, 4))
        image += clutter_rng.uniform(15, 50) * cv2.GaussianBlur(vein, (0, 0), k * 0.8)

    # shotcrete: a smooth grey skin over parts of the face, hiding everything under it
    cover = _shotcrete_cover(spray_rng, (h, w), style, m_per_px)
    hidden = None
    if cover is not None:
        alpha = cv2.GaussianBlur((cover[0] > cover[1]).astype(np.float32), (0, 0), k)
        skin = _shotcrete_surface(spray_rng, _reference_shape((h, w), k), m_per_px * k, light)
        image = image * (1.0 - alpha) + _enlarged(skin, (h, w)) * alpha
        darkness *= 1.0 - alpha
        hidden = _cover_polygon(*cover)

    # camera: uneven light, darkening by joints, defocus, noise, JPEG
    image *= _lighting(camera_rng, (h, w), camera_rng.uniform(*style.lighting),
                       int(camera_rng.integers(style.shadows[0], style.shadows[1] + 1)))
    image *= 1.0 - np.clip(darkness, 0.0, 0.95)
    image = cv2.GaussianBlur(image, (0, 0), k * camera_rng.uniform(*style.blur_px))
    amplitude = camera_rng.uniform(*style.noise)  # sensor noise, drawn on the reference grid
    noise = camera_rng.standard_normal(_reference_shape((h, w), k)).astype(np.float32)
    image += amplitude * _enlarged(noise, (h, w))
    image = np.clip(np.round(image), 0, 255).astype(np.uint8)
    quality = int(camera_rng.integers(style.jpeg_quality[0], style.jpeg_quality[1] + 1))
    ok, encoded = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])
    image = cv2.imdecode(encoded, cv2.IMREAD_GRAYSCALE)

    pieces, piece_widths = [], []
    for rc, width in zip(paths, widths):
        for part in _clip_to_image([rc], (h, w), hidden, min_length_px=k * 10.0):
            pieces.append(rc_to_uv(part, h, m_per_px))
            piece_widths.append(int(round(width)))
    window = np.array([[0.0, 0.0], [w * m_per_px, 0.0], [w * m_per_px, h * m_per_px],
                       [0.0, h * m_per_px]])
    truth = TraceMap.from_polylines(pieces, attributes={"width_px": np.asarray(piece_widths, np.int64)},
                                    window=window, frame="face")
    return SyntheticFace(image=image, truth=truth, m_per_px=m_per_px, difficulty="field",
                         seed=int(seed), style=replace(style))


def centre_line_mask(face: SyntheticFace) -> np.ndarray:
    """The truth's centre lines drawn as 1-px lines on the image grid (bool), for training and
    scoring at pixel level."""
    from .metrics import render_traces

    return render_traces(face.truth, face.image.shape, face.m_per_px)


def half_cast_axes(face: SyntheticFace) -> list[np.ndarray]:
    """The axes of a field face's blast half-casts, one ``(n_holes, 2, 2)`` array of rc-pixel ends
    per family (redrawn from the face's seed and style: the half-casts have their own stream)."""
    rng = _streams(face.seed)[5]
    families = _half_cast_layout(rng, face.image.shape, face.style, face.m_per_px)
    return [np.array([[p0, p1] for p0, p1, _, _ in holes]) for holes in families]


def minor_crack_mask(face: SyntheticFace, *, margin_px: float | None = None) -> np.ndarray:
    """Pixels of a field face within ``margin_px`` (default 2 px times the style's feature scale)
    of a minor crack's drawn stroke (bool), redrawn from the face's seed and style. Minor cracks
    are not labelled; training can leave these pixels out of its negatives, so that a thin dark
    line is not taught to be "not a joint" (its length, which tells a minor crack from a joint, is
    judged per trace, not per pixel)."""
    import cv2

    h, w = face.image.shape
    area = _area_factor((h, w), face.style)
    if margin_px is None:
        margin_px = 2.0 * _feature_scale(face.style)
    mark = np.zeros((h, w), dtype=np.float32)
    for crack, width, _ in _minor_cracks(_streams(face.seed)[3], (h, w), face.style, area):
        _draw(mark, crack, 1.0, width)
    if margin_px > 0:
        mark = cv2.dilate(mark, cv2.getStructuringElement(
            cv2.MORPH_ELLIPSE, (2 * int(margin_px) + 1, 2 * int(margin_px) + 1)))
    return mark > 0


def shotcrete_mask(face: SyntheticFace) -> np.ndarray:
    """Pixels of a field face under shotcrete (bool; all False when it has none), redrawn from the
    face's seed and style."""
    cover = _shotcrete_cover(_streams(face.seed)[6], face.image.shape, face.style, face.m_per_px)
    return np.zeros(face.image.shape, bool) if cover is None else cover[0] > cover[1]


def shotcrete_area(face: SyntheticFace):
    """The area of a field face under shotcrete as a shapely geometry in face-frame metres (the
    truth's frame; empty when it has none). No truth trace runs inside it."""
    import shapely

    h = face.image.shape[0]
    cover = _shotcrete_cover(_streams(face.seed)[6], face.image.shape, face.style, face.m_per_px)
    if cover is None:
        return shapely.Polygon()
    return shapely.transform(_cover_polygon(*cover), lambda rc: rc_to_uv(rc, h, face.m_per_px))
