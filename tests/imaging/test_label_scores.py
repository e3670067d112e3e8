"""Scores against hand-traced labels (rockmass.imaging.label_scores): the review image's colours
and the scores of a photo, from masks whose matches are known."""

import math

import numpy as np

from rockmass.imaging.label_scores import REVIEW_COLOURS, PhotoScore, review_image


def test_review_image_colours_each_pixel_by_whether_it_matches():
    image = np.full((40, 60), 200, np.uint8)
    label = np.zeros((40, 60), bool)
    label[10, 5:55] = True                  # a labelled joint
    drawn = np.zeros((40, 60), bool)
    drawn[12, 5:30] = True                  # drawn 2 px off the left half: matched
    drawn[30, 5:55] = True                  # a false trace, 20 px from the label
    rgb = review_image(image, drawn, label, tolerance_px=5.0, line_px=1)

    def colour(name):
        return np.all(rgb == REVIEW_COLOURS[name], axis=2)

    assert colour("matched")[12, 5:30].all() and colour("false")[30, 5:55].all()
    # the label's right half has no drawn pixel within 5 px: missed; its left half is not
    assert colour("missed")[10, 36:55].all() and not colour("missed")[10, 5:28].any()
    untouched = ~(drawn | label)
    assert np.all(rgb[untouched] == rgb[0, 0]) and rgb[0, 0, 0] == rgb[0, 0, 1] == rgb[0, 0, 2]


def test_a_photo_with_nothing_drawn_scores_zero_and_its_precision_is_undefined():
    score = PhotoScore("a.jpg", "a.png", (0, 0, 0, 50), 0, 2, "learned", 0.1)
    assert score.f1 == 0.0 and score.recall == 0.0 and math.isnan(score.precision)
    assert score.length_error_pct == -100.0 and score.count_error_pct == -100.0
    full = PhotoScore("b.jpg", "b.png", (45, 60, 40, 50), 3, 0, "ridge", 0.1)
    assert full.precision == 0.75 and full.recall == 0.8
    assert math.isclose(full.f1, 2 * 0.75 * 0.8 / 1.55) and math.isnan(full.count_error_pct)
