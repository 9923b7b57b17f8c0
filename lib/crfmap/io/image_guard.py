"""Checks on a map image made from its header, before any pixel is decoded.

A 20000 x 20000 PNG of a few kilobytes would otherwise take 8 GB and most of a minute to decode before anything
could object. :func:`check_map_image` reads only the header: the image must be a regular file (a FIFO would block
the reader) no larger than :func:`crfmap.checks.max_cells` pixels (raise it with ``crfmap --max-cells N`` or
``$CRFMAP_MAX_CELLS``; above 178 million pixels Pillow's own bomb limit still applies). A float image (TIFF mode
``F``) must hold finite values: NaN has no occupancy.
"""
from __future__ import annotations

import warnings

import numpy as np
from PIL import Image, UnidentifiedImageError

from crfmap.checks import check_cells, check_input_file
from crfmap.errors import InputError


def check_map_image(image_path, context=""):
    """InputError naming ``image_path`` if it is not a regular file, too large, or a float image with NaN/Inf.

    Unreadable or unidentified images pass: the loader reports those in its own words.

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
