"""Labelled test photographs drawn on a smooth random rock texture (tests of pixel models)."""

import cv2
import numpy as np


def rock_texture(rng, shape, level: float, spread: float) -> np.ndarray:
    """A float32 grey face of mean ``level``: white noise blurred at 2 px, scaled to standard
    deviation ``spread``."""
    rock = cv2.GaussianBlur(rng.normal(0, 1, shape).astype(np.float32), (0, 0), 2.0)
    return level + spread * rock / rock.std()


def draw_joint(image, label, a, b, grey: float) -> None:
    """A straight joint 3 px wide from pixel ``a`` to ``b`` (x, y), ``grey`` on the face and
    255 on the (uint8) label."""
    cv2.line(image, a, b, grey, 3)
    cv2.line(label, a, b, 255, 3)


def as_photo(image) -> np.ndarray:
    """The face as an 8-bit photograph."""
    return (np.clip(image, 0, 1) * 255).astype(np.uint8)
