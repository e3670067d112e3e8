"""Small block-model inputs whose answers can be worked out by hand."""

import numpy as np

from rockmass.blockgen import JointSet, build, circle


def square(side=1.0, x0=0.0, y0=0.0):
    return np.array([[x0, y0], [x0 + side, y0], [x0 + side, y0 + side], [x0, y0 + side]])


def orthogonal_grid(side=1.0, spacing=0.25, **kw):
    """Two persistent orthogonal sets through the origin: (side/spacing)² square blocks."""
    return build(square(side), [JointSet(0, spacing, origin_xy_m=(0, 0)),
                                JointSet(90, spacing, origin_xy_m=(0, 0))], **kw)


def shake_table(**kw):
    """Seed 002: ±45° sets at 5 cm spacing, a 15.2 cm tunnel in a 122 × 61 cm section."""
    domain = np.array([[0, 0], [1.22, 0], [1.22, 0.61], [0, 0.61]])
    return build(domain, [JointSet(45, 0.05), JointSet(135, 0.05)],
                 excavations=[circle((0.61, 0.305), 0.076)], **kw)
