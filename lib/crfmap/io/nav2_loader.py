"""nav2 map_server's per-pixel rules, for Humble and for Jazzy and later (Kilted, Rolling).

Both read the image with GraphicsMagick built with 16-bit quanta (Q16): every channel is an integer 0..65535 (an
8-bit value v becomes 257 v). From there they differ (``nav2_map_server/src/map_io.cpp``, ``loadMapFromFile``):

Humble (per pixel, double precision)
    ``shade`` = mean of R, G, B quanta (plus ``MaxRGB - opacity`` in trinary mode with alpha) / 65535; ``occ =
    shade`` if ``negate`` else ``1 - shade``. Trinary: ``occupied_thresh < occ`` -> 100, ``occ < free_thresh`` -> 0,
    else -1. Scale: not fully opaque -> -1, values between ``rint((occ - free) / (occupied - free) * 100)``. Raw:
    ``round(shade * 255)`` if in 0..100.
Jazzy and later (Eigen, float32)
    Rec. 601 luma ``(306 R + 601 G + 117 B) >> 10`` on the quanta, exported as 8 bits (``quantum / 257``);
    ``occ = 1 - grey / 255.0f`` unless ``negate``. ``occ >= occupied_thresh`` -> 100, ``occ <= free_thresh`` -> 0
    (free wins), else -1; scale: ``round(...)`` strictly between. Any alpha below 255 -> -1. Raw: the grey if in
    0..100, else -1. Thresholds are compared as float32.

>>> import numpy as np
>>> px = Pixels.from_grey8(np.array([[0, 205, 254]], np.uint8))
>>> occupancy(px, "trinary", 0, 0.65, 0.196, loader="jazzy").tolist()
[[100, -1, 0]]
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from crfmap.errors import InputError

LOADERS = ("humble", "jazzy")  # jazzy: Jazzy, Kilted and Rolling share one loader
DEFAULT_LOADER = "jazzy"
QUANTUM_MAX = 65535  # GraphicsMagick Q16


@dataclass
class Pixels:
    """An image as GraphicsMagick Q16 sees it: R, G, B (and alpha, if the image has one) in 0..65535."""

    red: np.ndarray
    green: np.ndarray
    blue: np.ndarray
    alpha: np.ndarray | None = None  # opacity as MaxRGB - GraphicsMagick's opacity: 65535 = opaque

    @classmethod
    def from_grey8(cls, grey, alpha=None):
        """8-bit grey (and alpha) pixels, as a PGM/PNG holding them loads."""
        g = np.asarray(grey, np.int64) * 257
        a = None if alpha is None else np.asarray(alpha, np.int64) * 257
        return cls(g, g, g, a)


def _from_pil(img, source, context):
    if img.width == 0 or img.height == 0:
        raise InputError(source, f"empty image ({img.width} x {img.height} pixels){context}")
    mode = img.mode
    if mode in ("I", "I;16", "I;16B", "I;16L", "I;16N"):  # 16-bit grey: quanta as they are
        grey = np.asarray(img).astype(np.int64)
        if grey.min() < 0 or grey.max() > QUANTUM_MAX:
            raise InputError(source, f"integer image values outside 0..65535 are not supported{context}")
        return Pixels(grey, grey, grey, None)
    if mode == "1":
        img = img.convert("L")
    elif mode == "P":  # a palette with a transparent entry reads as an image with alpha (matte)
        img = img.convert("RGBA" if "transparency" in img.info else "RGB")
    elif mode == "L" and "transparency" in img.info:
        img = img.convert("LA")
    elif mode not in ("L", "LA", "RGB", "RGBA"):
        img = img.convert("RGBA" if "A" in img.getbands() else "RGB")
    px = np.asarray(img).astype(np.int64) * 257  # 8 bits -> 16-bit quanta, exactly
    if img.mode == "L":
        return Pixels(px, px, px, None)
    if img.mode == "LA":
        return Pixels(px[..., 0], px[..., 0], px[..., 0], px[..., 1])
    return Pixels(px[..., 0], px[..., 1], px[..., 2], px[..., 3] if img.mode == "RGBA" else None)


def read_pixels(image_path, context="", check_header=None) -> Pixels:
    """The pixels of an image file as nav2's GraphicsMagick reads them; clear errors name the file."""
    source = Path(image_path)
    if not source.exists():
        raise InputError(source, f"image file not found{context}")
    if source.is_dir():
        raise InputError(source, f"is a folder, expected an image file{context}")
    if source.stat().st_size == 0:
        raise InputError(source, f"empty image file (0 bytes){context}")
    try:
        if check_header is not None:
            check_header(source, source, context)
        with Image.open(source) as img:
            img.load()
            return _from_pil(img, source, context)
    except InputError:
        raise
    except UnidentifiedImageError:
        raise InputError(source, f"not an image Pillow can read{context}") from None
    except Image.DecompressionBombError as exc:
        raise InputError(source, f"image too large for Pillow's safety limit ({exc}){context}") from None
    except (OSError, SyntaxError, ValueError) as exc:  # Pillow's "image file is truncated", bad data
        raise InputError(source, f"unreadable image ({exc}){context}") from None


def _humble(px, mode, negate, occupied_thresh, free_thresh):
    colour = (px.red + px.green + px.blue).astype(np.float64)
    if mode == "trinary" and px.alpha is not None:
        shade = (colour + px.alpha) / 4.0 / QUANTUM_MAX
    else:
        shade = colour / 3.0 / QUANTUM_MAX
    if mode == "raw":
        percent = np.floor(shade * 255.0 + 0.5)  # std::round, for non-negative values
        return np.where((percent >= 0) & (percent <= 100), percent, -1).astype(np.int8)
    occ = shade if negate else 1.0 - shade
    out = np.full(occ.shape, -1, dtype=np.int8)
    if mode == "scale":
        ratio = (occ - free_thresh) / (occupied_thresh - free_thresh)
        out[...] = np.rint(np.clip(ratio, 0.0, 1.0) * 100.0).astype(np.int8)
    out[occ < free_thresh] = 0
    out[occupied_thresh < occ] = 100
    if mode == "scale" and px.alpha is not None:
        out[px.alpha != QUANTUM_MAX] = -1
    return out


def grey8_jazzy(px) -> np.ndarray:
    """GraphicsMagick's Rec. 601 grey of each pixel, exported as 8 bits (what Jazzy+ thresholds)."""
    luma = (306 * px.red + 601 * px.green + 117 * px.blue) >> 10
    return (luma // 257).astype(np.uint8)


def _jazzy(px, mode, negate, occupied_thresh, free_thresh):
    grey = grey8_jazzy(px)
    if mode == "raw":  # nav2 casts uint8 to int8: 128..255 wrap negative, then out of [0, 100] -> -1
        return np.where(grey <= 100, grey, -1).astype(np.int8)
    f32 = np.float32
    normalized = grey.astype(f32) / f32(255.0)
    if not negate:
        normalized = f32(1.0) - normalized
    occ_t, free_t = f32(occupied_thresh), f32(free_thresh)  # Eigen compares in the array's float
    out = np.full(grey.shape, -1, dtype=np.int8)
    out[normalized >= occ_t] = 100
    out[normalized <= free_t] = 0
    if mode == "scale":
        between = (normalized > free_t) & (normalized < occ_t)
        span = f32(float(occupied_thresh) - float(free_thresh))  # the difference is taken in double
        scaled = (normalized - free_t) / span * f32(100.0)
        rounded = np.sign(scaled) * np.floor(np.abs(scaled) + f32(0.5))  # std::round: half away from 0
        out[between] = rounded[between].astype(np.int8)
    if px.alpha is not None:
        out[(px.alpha // 257) < 255] = -1
    return out


def occupancy(px: Pixels, mode, negate, occupied_thresh, free_thresh, loader=DEFAULT_LOADER) -> np.ndarray:
    """int8 OccupancyGrid values of ``px`` (image row order: top row first) under ``loader``'s rules."""
    if loader not in LOADERS:
        raise InputError("loader", f"unknown nav2 loader {loader!r} (expected one of {', '.join(LOADERS)})")
    rule = _humble if loader == "humble" else _jazzy
    return rule(px, mode, negate, occupied_thresh, free_thresh)


__all__ = ["LOADERS", "DEFAULT_LOADER", "Pixels", "read_pixels", "occupancy", "grey8_jazzy"]
