"""A pixel limit checked from an image file's header, before anything decodes it (issue 18).

Decoding allocates the whole picture (and the filters several float copies of it): a 875 KB PNG of
30 000 x 30 000 pixels asked for gigabytes before any check ran. :func:`check_image_pixels` reads
the width and height from the first bytes of a PNG, JPEG, TIFF or BMP file (standard library
only: no image library is imported, and no limit of theirs applies first) and refuses an image
above the limit with exit code 2, naming the file, its size and the limit, and how to raise it.

The limit is :data:`DEFAULT_MAX_PIXELS` (100 megapixels, a 12 000 x 8 000 photograph fits), or the
``--max-pixels`` option of the command, or the environment variable :data:`MAX_PIXELS_ENV`.
A format this module does not parse, or a header it cannot read, is left to the decoder (which
reports a broken file itself).
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import BinaryIO

from .errors import InputError

__all__ = ["DEFAULT_MAX_PIXELS", "MAX_PIXELS_ENV", "image_size", "max_pixels", "check_image_pixels",
           "pixel_limit_arg"]

DEFAULT_MAX_PIXELS = 100_000_000
MAX_PIXELS_ENV = "ROCKMASS_MAX_PIXELS"

_PNG = b"\x89PNG\r\n\x1a\n"
#: JPEG start-of-frame markers (baseline, progressive, lossless, ...; not DHT C4, JPG C8, DAC CC).
_SOF = {0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF}
_MAX_JPEG_SEGMENTS = 4096  # a header is a few dozen segments: stop walking a hostile file


def _png_size(head: bytes) -> tuple[int, int] | None:
    """Width and height of the IHDR chunk, which must come first."""
    if len(head) >= 24 and head[12:16] == b"IHDR":
        return struct.unpack(">II", head[16:24])
    return None


def _bmp_size(head: bytes) -> tuple[int, int] | None:
    """Width and height of a BITMAPINFOHEADER (height negative for top-down rows)."""
    if len(head) >= 26:
        width, height = struct.unpack("<ii", head[18:26])
        return abs(width), abs(height)
    return None


def _jpeg_size(handle: BinaryIO) -> tuple[int, int] | None:
    """Width and height of the first start-of-frame segment, walking the segments from SOI."""
    handle.seek(2)
    for _ in range(_MAX_JPEG_SEGMENTS):
        byte = handle.read(1)
        while byte == b"\xff":  # fill bytes before a marker
            byte = handle.read(1)
        if not byte:
            return None
        marker = byte[0]
        if marker == 0xD8 or 0xD0 <= marker <= 0xD7 or marker == 0x01:  # no length
            continue
        length_bytes = handle.read(2)
        if len(length_bytes) < 2:
            return None
        (length,) = struct.unpack(">H", length_bytes)
        if marker in _SOF:
            body = handle.read(5)
            if len(body) < 5:
                return None
            height, width = struct.unpack(">HH", body[1:5])
            return width, height
        if marker == 0xDA or length < 2:  # image data before a frame header: not a JPEG we know
            return None
        handle.seek(length - 2, os.SEEK_CUR)
        # a marker byte must follow; anything else is not a segment boundary
        if handle.read(1) != b"\xff":
            return None
        handle.seek(-1, os.SEEK_CUR)
    return None


def _tiff_size(handle: BinaryIO, head: bytes) -> tuple[int, int] | None:
    """ImageWidth (256) and ImageLength (257) of the first IFD (classic and BigTIFF)."""
    order = "<" if head[:2] == b"II" else ">"
    (version,) = struct.unpack(order + "H", head[2:4])
    if version == 42:
        (offset,) = struct.unpack(order + "I", head[4:8])
        count_fmt, entry_fmt, entry_size, value_at = "H", "HHI", 12, 8
    elif version == 43:
        (offset,) = struct.unpack(order + "Q", head[8:16])
        count_fmt, entry_fmt, entry_size, value_at = "Q", "HHQ", 20, 12
    else:
        return None
    handle.seek(offset)
    raw = handle.read(struct.calcsize(order + count_fmt))
    if not raw:
        return None
    (count,) = struct.unpack(order + count_fmt, raw)
    found: dict[int, int] = {}
    for _ in range(min(count, 4096)):
        entry = handle.read(entry_size)
        if len(entry) < entry_size:
            break
        tag, kind, _n = struct.unpack(order + entry_fmt, entry[:value_at])
        if tag in (256, 257) and kind in (3, 4, 16):  # SHORT, LONG, LONG8: the value is inline
            fmt = {3: "H", 4: "I", 16: "Q"}[kind]
            (found[tag],) = struct.unpack(order + fmt, entry[value_at:value_at + struct.calcsize(fmt)])
    if 256 in found and 257 in found:
        return found[256], found[257]
    return None


def image_size(path: str | os.PathLike) -> tuple[int, int] | None:
    """(width, height) in pixels from the header of a PNG, JPEG, TIFF or BMP file, without
    decoding it; None for another format or a header that cannot be read.

    Examples
    --------
    >>> import tempfile, pathlib, struct, zlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.png"
    >>> ihdr = struct.pack(">IIBBBBB", 30000, 20000, 8, 0, 0, 0, 0)
    >>> _ = p.write_bytes(b"\\x89PNG\\r\\n\\x1a\\n" + struct.pack(">I", 13) + b"IHDR" + ihdr)
    >>> image_size(p)
    (30000, 20000)
    """
    try:
        with open(path, "rb") as handle:
            head = handle.read(32)
            if head.startswith(_PNG):
                return _png_size(head)
            if head.startswith(b"\xff\xd8"):
                return _jpeg_size(handle)
            if head[:4] in (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+"):
                return _tiff_size(handle, head)
            if head.startswith(b"BM"):
                return _bmp_size(head)
    except (OSError, struct.error, ValueError):
        return None
    return None


def _positive_pixels(text: str) -> int | None:
    """``text`` as a positive whole number of pixels (``1e8`` accepted), or None."""
    try:
        value = float(text)
    except ValueError:
        return None
    return int(value) if value >= 1 and value == int(value) else None


def pixel_limit_arg(text: str) -> int:
    """``argparse`` type of ``--max-pixels``: a positive number of pixels."""
    import argparse

    value = _positive_pixels(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"must be a positive number of pixels, got {text!r}")
    return value


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
    value = _positive_pixels(text)
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
