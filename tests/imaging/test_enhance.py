"""Grey conversion, photo reading (EXIF orientation, 16 bit, bad files) and illumination flattening."""

import numpy as np
import pytest

from rockmass.imaging.enhance import flatten_illumination, read_photo, to_grey


def test_rgb_grey_uses_bt601_weights():
    rgb = np.zeros((1, 3, 3), dtype=np.uint8)
    rgb[0, 0, 0] = rgb[0, 1, 1] = rgb[0, 2, 2] = 255
    np.testing.assert_allclose(to_grey(rgb)[0], [0.299, 0.587, 0.114], rtol=1e-6)


def test_rgba_alpha_is_ignored_and_16_bit_scales_to_one():
    rgba = np.full((2, 2, 4), 65535, dtype=np.uint16)
    rgba[..., 3] = 0
    np.testing.assert_allclose(to_grey(rgba), 1.0, rtol=1e-6)


def test_to_grey_rejects_bad_shapes_and_nan():
    with pytest.raises(ValueError, match="image must have shape"):
        to_grey(np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match="non-finite"):
        to_grey(np.array([[np.nan, 1.0]]))


def test_read_photo_applies_exif_orientation(tmp_path):
    from PIL import Image

    array = np.zeros((20, 40), dtype=np.uint8)
    array[:, :5] = 255  # a bright stripe on the left of the stored pixels
    img = Image.fromarray(array)
    exif = img.getexif()
    exif[0x0112] = 6  # "rotate 90 CW to display"
    path = tmp_path / "rotated.jpg"
    img.save(path, exif=exif, quality=95)
    shown = read_photo(path)
    assert shown.shape == (40, 20)
    assert shown[:5].mean() > 200 and shown[-5:].mean() < 50  # the stripe is now at the top


def test_read_photo_keeps_16_bit(tmp_path):
    from PIL import Image

    array = (np.arange(64 * 64, dtype=np.uint16) * 7).reshape(64, 64)
    path = tmp_path / "deep.png"
    Image.fromarray(array).save(path)
    np.testing.assert_array_equal(read_photo(path), array)


@pytest.mark.parametrize("content", [b"", b"not an image at all"])
def test_unreadable_files_raise_oserror_naming_the_file(tmp_path, content):
    path = tmp_path / "bad.jpg"
    path.write_bytes(content)
    with pytest.raises(OSError, match="bad.jpg"):
        read_photo(path)


def test_truncated_jpeg_raises(tmp_path):
    import cv2

    ok, data = cv2.imencode(".jpg", np.random.default_rng(1).integers(0, 255, (200, 200), dtype=np.uint8))
    path = tmp_path / "cut.jpg"
    path.write_bytes(data.tobytes()[: len(data) // 2])
    with pytest.raises(OSError, match="cut.jpg"):
        read_photo(path)


def test_division_flattening_equalises_joint_contrast_under_a_lighting_ramp():
    h, w = 120, 200
    rock = np.full((h, w), 0.6, dtype=np.float32)
    rock[:, 50:53] *= 0.5  # a joint in the dark half
    rock[:, 150:153] *= 0.5  # the same joint in the bright half
    gain = np.linspace(0.3, 1.0, w, dtype=np.float32)[None, :]
    flat = flatten_illumination(rock * gain, line_width_px=3, sigma_px=15)
    contrast_dark = 1 - flat[60, 51] / flat[60, 40]
    contrast_bright = 1 - flat[60, 151] / flat[60, 140]
    assert abs(contrast_dark - 0.5) < 0.05 and abs(contrast_bright - 0.5) < 0.05


def test_flatten_does_not_modify_input_and_rejects_unknown_method():
    grey = np.random.default_rng(2).random((50, 60)).astype(np.float32)
    before = grey.copy()
    flatten_illumination(grey, clahe=True)
    np.testing.assert_array_equal(grey, before)
    with pytest.raises(ValueError, match="method must be one of"):
        flatten_illumination(grey, method="median")
