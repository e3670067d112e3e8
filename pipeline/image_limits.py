"""A pixel limit checked from an image file's header, before anything decodes it (issue 18).

Decoding allocates the whole picture (and the filters several float copies of it): a 875 KB PNG of
30 000 x 30 000 pixels asked for gigabytes before any check ran. :func:`check_image_pixels` reads
the width and height from the file's header (Pillow's lazy open, its own bomb limit off for that
call) and refuses an image above the limit with exit code 2, naming the file, its size and the
limit, and how to raise it.

The limit is :data:`DEFAULT_MAX_PIXELS` (100 megapixels, a 12 000 x 8 000 photograph fits), or the
``--max-pixels`` option of the command, or the environment variable :data:`MAX_PIXELS_ENV`.
A file whose header Pillow cannot read is left to the decoder (which reports a broken file
itself).
"""

from __future__ import annotations

import os
from pathlib import Path

from .budgets import positive_count, positive_count_arg
from .errors import InputError

__all__ = ["DEFAULT_MAX_PIXELS", "MAX_PIXELS_ENV", "image_size", "max_pixels", "check_image_pixels",
           "pixel_limit_arg"]

DEFAULT_MAX_PIXELS = 100_000_000
MAX_PIXELS_ENV = "ROCKMASS_MAX_PIXELS"


def image_size(path: str | os.PathLike) -> tuple[int, int] | None:
    """(width, height) in pixels from the file's header, without decoding it; None for a file
    Pillow does not recognise or whose header it cannot read.

    Pillow's :func:`PIL.Image.open` is lazy: it parses the header and leaves the pixels to
    ``load()``. Its own decompression-bomb check, which would refuse a large header before the
    caller's limit is applied, is switched off for that call (the caller judges the size).

    Examples
    --------
    >>> import tempfile, pathlib, struct, zlib
    >>> def chunk(kind, data):
    ...     return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.png"
    >>> ihdr = struct.pack(">IIBBBBB", 30000, 20000, 8, 0, 0, 0, 0)
    >>> _ = p.write_bytes(b"\\x89PNG\\r\\n\\x1a\\n" + chunk(b"IHDR", ihdr)
    ...                   + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b""))
    >>> image_size(p)
    (30000, 20000)
    """
    from PIL import Image

    before, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
    try:
        with Image.open(path) as img:
            return img.size
    except (OSError, SyntaxError, ValueError):  # UnidentifiedImageError is an OSError
        return None
    finally:
        Image.MAX_IMAGE_PIXELS = before


def pixel_limit_arg(text: str) -> int:
    """``argparse`` type of ``--max-pixels``: a positive number of pixels."""
    return positive_count_arg(text, "pixels")


def max_pixels(option: int | None = None) -> int:
    """The pixel limit in force: ``option`` (``--max-pixels``) if given, else the environment
    variable :data:`MAX_PIXELS_ENV`, else :data:`DEFAULT_MAX_PIXELS`.

    Raises
    ------
    InputError
        If the environment variable is not a positive integer (naming it).
    """
    if option is not None:
        return int(option)
    text = os.environ.get(MAX_PIXELS_ENV)
    if text is None or not text.strip():
        return DEFAULT_MAX_PIXELS
    value = positive_count(text)
    if value is None:
        raise InputError(f"{MAX_PIXELS_ENV} must be a positive number of pixels, got {text!r}")
    return value


def _size_text(n_bytes: int) -> str:
    """``n_bytes`` in GiB from 1 GiB up, else in MiB.

    >>> _size_text(3 * 2**30), _size_text(5 * 2**20)
    ('3.0 GiB', '5.0 MiB')
    """
    return f"{n_bytes / 2**30:.1f} GiB" if n_bytes >= 2**30 else f"{n_bytes / 2**20:.1f} MiB"


def check_image_pixels(path: str | os.PathLike, limit: int | None = None,
                       option: str | None = "--max-pixels") -> tuple[int, int] | None:
    """Refuse an image above the pixel limit from its header, before it is decoded.

    Parameters
    ----------
    path : str or path-like
        The image file.
    limit : int, optional
        The command's ``--max-pixels``; default: :func:`max_pixels` (environment, then 100 MP).
    option : str or None, default "--max-pixels"
        The option that raises the limit, named in the message (None: the command has none, the
        environment variable raises it).

    Returns
    -------
    (int, int) or None
        The image's (width, height), or None when the header was not read (the decoder decides).

    Raises
    ------
    InputError
        If width x height exceeds the limit: names the file, its size and the limit, and how to
        raise it (``option`` or :data:`MAX_PIXELS_ENV`).
    """
    size = image_size(path)
    if size is None:
        return None
    width, height = size
    allowed = max_pixels(limit)
    if width * height > allowed:
        raise InputError(
            f"{Path(path)}: the image is {width} x {height} pixels ({width * height / 1e6:.1f} MP), "
            f"above the limit of {allowed / 1e6:g} MP read before decoding (decoding it would need "
            f"at least {_size_text(width * height * 4)}); raise the limit with "
            f"{f'{option} N or ' if option else ''}the environment variable {MAX_PIXELS_ENV}=N, or "
            "downsample the image")
    return size
