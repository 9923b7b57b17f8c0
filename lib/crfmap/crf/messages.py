"""LBP message arrays in the probability layout of :mod:`crfmap.crf._lbp_kernels`: uniform, checked, floored."""
from __future__ import annotations

import numpy as np

from crfmap.errors import InputError


def initial_messages(shape, dtype=np.float64) -> np.ndarray:
    """Uniform messages (0.5) for a grid of ``shape`` = (H, W).

    >>> initial_messages((1, 2)).shape
    (4, 1, 2)
    """
    return np.full((4,) + tuple(shape), 0.5, dtype=dtype)


def check_messages(messages, shape) -> np.ndarray:
    """Warm-start messages for a grid of ``shape``: shape (4, H, W), finite probabilities (else InputError)."""
    msg = np.asarray(messages)
    if msg.shape != (4,) + tuple(shape):
        raise InputError("messages", f"expected shape {(4,) + tuple(shape)} for this grid, got {msg.shape}")
    if not np.issubdtype(msg.dtype, np.floating):
        msg = msg.astype(np.float64)
    if not np.all(np.isfinite(msg)) or msg.min() < 0 or msg.max() > 1:
        raise InputError("messages", "must be finite probabilities in [0, 1]")
    return msg


def floored(messages, dtype, shape, floor):
    """A copy in [floor, 1 - floor] of ``dtype``, slots with no neighbour behind them uniform."""
    msg = np.clip(messages, floor, 1.0 - floor).astype(dtype, copy=False)
    # slots with no neighbour behind them must stay uniform
    msg[0, :, 0] = msg[1, :, -1] = msg[2, 0, :] = msg[3, -1, :] = 0.5
    return msg
