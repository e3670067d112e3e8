"""Random rock textures with no joints in them, to draw training joints on (docs/imaging.md §3.6).

A detector trained on one generator's rock learns that rock (§8.4: the shipped pixel model finds
fewer than half of the joints drawn on real rock photographs that it finds on its own texture).
Drawing the training joints on many different textures instead, none of them the test's, makes the
texture a nuisance the model must ignore rather than a cue (domain randomisation, Tobin et al.
2017). Two kinds:

- :func:`procedural_rock`: fractal noise of random spectral slope (power spectrum ∝ 1/f^β,
  β in 1.6-3.2: from gritty to cloudy), pixel noise, flat facets of slightly different grey (a
  Voronoi mosaic: blocks of rock lit at different angles), curved dark *crack clutter* (short
  random walks, never joints: they bend at every step), an illumination ramp and a slight blur;
- :func:`photo_rock`: a random crop of scikit-image's CC0 photographs of gravel and bricks
  (``skimage.data.gravel``, ``skimage.data.brick``; from CC0Textures, licensed CC0), zoomed,
  turned and with its contrast lowered: real grain and real shadows.

Neither draws a straight line on purpose: on these textures, what is long, straight and dark is a
drawn joint.
"""

from __future__ import annotations

import numpy as np

__all__ = ["power_law_noise", "crack_clutter", "facets", "procedural_rock", "photo_rock",
           "random_rock", "PHOTO_TEXTURES"]

#: scikit-image's CC0 photographs used by :func:`photo_rock` (its ``grass`` is left out: blades of
#: grass are long straight dark lines, i.e. joints to a detector).
PHOTO_TEXTURES = ("gravel", "brick")


def power_law_noise(rng: np.random.Generator, shape, beta: float) -> np.ndarray:
    """Gaussian noise whose power spectrum falls as 1 / f^beta, zero mean, unit standard
    deviation (float32): beta = 0 is white noise, 2 Brownian, 3 cloud-like.

    Examples
    --------
    >>> n = power_law_noise(np.random.default_rng(0), (64, 80), 2.0)
    >>> n.shape, round(float(n.mean()), 6), round(float(n.std()), 3)
    ((64, 80), 0.0, 1.0)
    """
    h, w = shape
    f = np.hypot(np.fft.fftfreq(h)[:, None], np.fft.rfftfreq(w)[None, :])
    f[0, 0] = 1.0
    spectrum = (rng.standard_normal(f.shape) + 1j * rng.standard_normal(f.shape)) / f ** (beta / 2)
    spectrum[0, 0] = 0.0
    noise = np.fft.irfft2(spectrum, s=(h, w))
    noise -= noise.mean()
    return (noise / max(float(noise.std()), 1e-12)).astype(np.float32)


def crack_clutter(rng: np.random.Generator, shape, n: int, *, width_px=(1, 3), length_px=(10, 80),
                  curl: float = 0.5, darkness=(0.1, 0.4)) -> np.ndarray:
    """Darkness (share of the grey level taken, float32 in [0, 1)) of ``n`` short curved cracks:
    random walks of 3 px steps whose direction turns by N(0, ``curl``) radians at every step."""
    import cv2

    h, w = shape
    out = np.zeros(shape, np.float32)
    layer = np.zeros(shape, np.float32)
    for _ in range(n):
        x, y, angle = rng.uniform(0, w), rng.uniform(0, h), rng.uniform(0, 2 * np.pi)
        points = [(x, y)]
        for _ in range(int(rng.uniform(*length_px) / 3.0)):
            angle += rng.normal(0.0, curl)
            x, y = x + 3.0 * np.cos(angle), y + 3.0 * np.sin(angle)
            points.append((x, y))
        layer[:] = 0.0
        cv2.polylines(layer, [np.round(np.array(points) * 4).astype(np.int32)], False, 1.0,
                      int(rng.integers(width_px[0], width_px[1] + 1)), cv2.LINE_AA, shift=2)
        np.maximum(out, layer * rng.uniform(*darkness), out=out)
    return out


def facets(rng: np.random.Generator, shape, n: int, amplitude: float) -> np.ndarray:
    """A mosaic of ``n`` flat facets (the Voronoi cells of random points), each its own grey offset
    N(0, ``amplitude``), edges softened by a blur of 0.7-2 px (float32)."""
    import cv2
    from scipy.spatial import cKDTree

    h, w = shape
    centres = np.column_stack([rng.uniform(0, w, n), rng.uniform(0, h, n)])
    yy, xx = np.mgrid[0:h, 0:w]
    _, cell = cKDTree(centres).query(np.column_stack([xx.ravel(), yy.ravel()]))
    levels = rng.normal(0.0, amplitude, n).astype(np.float32)
    return cv2.GaussianBlur(levels[cell].reshape(shape), (0, 0), rng.uniform(0.7, 2.0))


def procedural_rock(rng: np.random.Generator, shape=(400, 400)) -> np.ndarray:
    """A grey uint8 rock texture of random character (module notes)."""
    import cv2

    h, w = shape
    grey = np.full(shape, rng.uniform(90, 180), np.float32)
    grey += rng.uniform(8, 35) * power_law_noise(rng, shape, rng.uniform(1.6, 3.2))
    grey += rng.uniform(2, 12) * rng.standard_normal(shape).astype(np.float32)
    grey += facets(rng, shape, int(rng.integers(5, 40)), rng.uniform(0, 20))
    grey *= 1.0 - crack_clutter(rng, shape, int(rng.integers(0, 60)), curl=rng.uniform(0.2, 0.8))
    yy, xx = np.mgrid[0:h, 0:w] / max(shape)
    angle = rng.uniform(0, 2 * np.pi)
    grey *= 1.0 + rng.uniform(0, 0.5) * (np.cos(angle) * (xx - 0.5) + np.sin(angle) * (yy - 0.5))
    grey = cv2.GaussianBlur(grey, (0, 0), rng.uniform(0.3, 1.2))
    return np.clip(grey, 0, 255).astype(np.uint8)


def photo_rock(rng: np.random.Generator, shape=(400, 400)) -> np.ndarray:
    """A random crop (at most ``shape``) of one of :data:`PHOTO_TEXTURES`, zoomed 0.8-2.5 times,
    turned by a multiple of 90 degrees and its contrast about the mean scaled by 0.2-0.8 (uint8)."""
    import cv2
    import skimage.data

    image = getattr(skimage.data, str(rng.choice(PHOTO_TEXTURES)))().astype(np.float32)
    zoom = rng.uniform(0.8, 2.5)
    image = np.rot90(cv2.resize(image, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_CUBIC),
                     int(rng.integers(4)))
    h, w = image.shape
    rows, cols = min(shape[0], h), min(shape[1], w)
    top, left = rng.integers(0, h - rows + 1), rng.integers(0, w - cols + 1)
    crop = image[top:top + rows, left:left + cols]
    mean = crop.mean()
    return np.clip(mean + rng.uniform(0.2, 0.8) * (crop - mean), 0, 255).astype(np.uint8)


def random_rock(rng: np.random.Generator, shape=(400, 400), photo_share: float = 0.25) -> np.ndarray:
    """:func:`photo_rock` with probability ``photo_share``, else :func:`procedural_rock`.

    Examples
    --------
    >>> rock = random_rock(np.random.default_rng(1), (48, 64))
    >>> rock.dtype, rock.shape[0] <= 48 and rock.shape[1] <= 64
    (dtype('uint8'), True)
    """
    return photo_rock(rng, shape) if rng.uniform() < photo_share else procedural_rock(rng, shape)
