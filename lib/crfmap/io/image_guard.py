"""Checks on a map image from its header, before any pixel is decoded: a PNG of a few kilobytes can take gigabytes
and a minute to decode. The limit is :func:`crfmap.checks.max_cells` (``crfmap --max-cells N``)."""
from __future__ import annotations

import warnings

import numpy as np
from PIL import Image, UnidentifiedImageError

from crfmap.checks import check_cells, check_input_file
from crfmap.errors import InputError


def check_map_image(image_path, context=""):
    """InputError naming ``image_path`` if it is not a regular file (a FIFO would block the reader), too large, or a
    float image with NaN/Inf. Unreadable images pass: the loader words those.

    >>> check_map_image("/dev/null")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: /dev/null: not a regular file (a device, FIFO or socket), expected map image
    """
    path = check_input_file(image_path, "map image")
    limit = Image.MAX_IMAGE_PIXELS
    try:
        Image.MAX_IMAGE_PIXELS = None  # crfmap's limit below replaces Pillow's for the header
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as img:
                width, height = img.size
                mode = img.mode
                check_cells(f"{path}{context}", width, height, what="image")
                if mode == "F":
                    values = np.asarray(img)
                    if not np.isfinite(values).all():
                        raise InputError(path, f"float image with NaN or infinite pixels{context}")
    except InputError:
        raise
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError):
        return  # not ours to word: the loader says what is wrong with it
    finally:
        Image.MAX_IMAGE_PIXELS = limit
