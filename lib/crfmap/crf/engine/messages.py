"""LBP messages in the probability layout: the floor, uniform, checked and floored arrays, and the beliefs they give.

The layout (the plain kernels' and the fast engine's unpacked messages): ``msg[d, y, x]`` is the message arriving at
cell (y, x) that travelled in direction d (0 east-bound, from the west neighbour; 1 west-bound, from the east; 2
north-bound, from the south; 3 south-bound, from the north), as P(receiver occupied). A slot with no neighbour
behind it stays 0.5."""
from __future__ import annotations

import numpy as np
from numba import njit

from crfmap.crf.threads import over_rows
from crfmap.errors import InputError

# Messages and observations are kept in [MESSAGE_FLOOR, 1 - MESSAGE_FLOOR]: products of five factors stay far above
# float32's smallest normal, hard evidence stays finite, and contradicting hard evidence gives 0.5, not 0/0 = NaN.
MESSAGE_FLOOR = 1e-6


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
    msg[0, :, 0] = msg[1, :, -1] = msg[2, 0, :] = msg[3, -1, :] = 0.5
    return msg


def beliefs_from_messages(unary, msg, out=None) -> np.ndarray:
    """P(occupied) of every hidden cell from its floored observation ``unary`` [y, x] and its messages."""
    out = np.empty(unary.shape, dtype=np.float64) if out is None else out
    over_rows(_beliefs, unary.shape[0], unary, msg, out)
    return out


@njit(nogil=True, cache=True)
def _beliefs(unary, msg, out, r0, r1):
    """P(occupied) of every hidden cell: its observation times its four incoming messages."""
    w = unary.shape[1]
    for y in range(r0, r1):
        for x in range(w):
            u = unary[y, x]
            a = u * msg[0, y, x] * msg[1, y, x] * msg[2, y, x] * msg[3, y, x]
            b = (1.0 - u) * (1.0 - msg[0, y, x]) * (1.0 - msg[1, y, x]) * (1.0 - msg[2, y, x]) * (1.0 - msg[3, y, x])
            out[y, x] = a / (a + b)
