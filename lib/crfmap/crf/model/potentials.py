"""The CRF's two 2x2 potential tables, in the thesis's layout, and how they are checked.

Layout (thesis Tables 4, 5, 7): rows are the state of the cell C that a message arrives at
(C1 = occupied, C0 = empty), columns the state of the neighbour N it comes from (N1, N0)::

            N1   N0
    C1  [[ oo,  oe ],
    C0   [ eo,  ee ]]

- ``hidden``: cell-cell potential of the hidden lattice (default [[10, 1], [1, 10]]).
- ``link``: observation-cell potential (default identity); the observed node holds the grid's P(occupied) and sends
  one message through it.

A table matters only up to scale. Any finite non-negative table with no all-zero row is accepted.

Pairing (how a hidden table applies to an undirected lattice edge):

- ``"receiver"`` (the thesis, eq. 9): every message uses the table with rows = receiving cell: sum-product on the
  pairwise CRF for a symmetric table; for a non-symmetric one (the thesis's learned tables) the thesis's
  directed-influence model, which has no joint distribution to compare against.
- ``"oriented"``: a proper pairwise CRF whose edge potential is ``psi(x_a, x_b) = hidden[x_a, x_b]`` with ``a`` the
  west (lower x) or south (lower y) cell of the edge. Same as ``"receiver"`` for symmetric tables."""
from __future__ import annotations

import numpy as np
from numba import njit

from crfmap.crf.threads import over_rows
from crfmap.errors import InputError

DEFAULT_HIDDEN = np.array([[10.0, 1.0], [1.0, 10.0]])
DEFAULT_LINK = np.array([[1.0, 0.0], [0.0, 1.0]])
PAIRINGS = ("receiver", "oriented")

# Message directions as the kernels store them: a message sent east arrives "from the west", in slot 0; and so on
TO_EAST, TO_WEST, TO_NORTH, TO_SOUTH = 0, 1, 2, 3


def check_table(table, name="potential") -> np.ndarray:
    """A potential (a nested list, an array, or a string "oo,oe,eo,ee") as a (2, 2) float64 array, or InputError.

    >>> check_table("10,1,1,10").tolist()
    [[10.0, 1.0], [1.0, 10.0]]
    """
    if isinstance(table, str):
        parts = [p.strip() for p in table.replace(";", ",").split(",") if p.strip()]
        if len(parts) != 4:
            raise InputError(name, f"expected 4 comma-separated numbers oo,oe,eo,ee, got {table!r}")
        try:
            table = [float(p) for p in parts]
        except ValueError:
            raise InputError(name, f"expected 4 numbers oo,oe,eo,ee, got {table!r}") from None
    try:
        arr = np.array(table, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(name, f"expected a 2x2 table of numbers, got {table!r}") from None
    if arr.size == 4:
        arr = arr.reshape(2, 2)
    if arr.shape != (2, 2):
        raise InputError(name, f"expected a 2x2 table, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(name, f"entries must be finite, got {arr.tolist()}")
    if np.any(arr < 0):
        raise InputError(name, f"entries must be non-negative, got {arr.tolist()}")
    for row, label in zip(arr, ("C1 (occupied)", "C0 (empty)")):
        if not np.any(row > 0):
            raise InputError(name, f"row {label} is all zero: that state could never occur")
    return arr


TABLE_HEADROOM = 16  # a table entry times the messages it meets: entries stay this far below the dtype's largest


def check_table_fits(table, dtype, name="potential") -> np.ndarray:
    """``table`` (checked) if every non-zero entry survives ``dtype``: between its smallest normal number and
    its largest over :data:`TABLE_HEADROOM`. A float32 entry of 1e39 is inf there, and the kernels' beliefs NaN.

    >>> check_table_fits([[1e39, 1], [1, 1]], np.float32, "hidden")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: hidden: entries [[1e+39, 1.0], [1.0, 1.0]] do not fit float32 (1.2e-38 .. 2.1e+37); rescale the table or compute in float64
    """
    values = check_table(table, name)
    info = np.finfo(dtype)
    positive = values[values > 0]
    if positive.max() > info.max / TABLE_HEADROOM or positive.min() < info.tiny:
        advice = "; rescale the table" + (" or compute in float64" if info.dtype == np.float32 else "")
        raise InputError(name, f"entries {values.tolist()} do not fit {info.dtype} ({info.tiny:.1e} .. "
                               f"{info.max / TABLE_HEADROOM:.1e}){advice}")
    return values


def check_pairing(pairing) -> str:
    if pairing not in PAIRINGS:
        raise InputError("pairing", f"must be one of {', '.join(PAIRINGS)}, got {pairing!r}")
    return pairing


def directional_tables(hidden, pairing="receiver") -> np.ndarray:
    """The table each message direction (TO_EAST, ...) uses, rows = receiver: shape (4, 2, 2). Under ``"oriented"``
    the edge potential ``hidden[x_west, x_east]`` reads as ``hidden.T`` for messages travelling east or north."""
    t = check_table(hidden, "hidden")
    check_pairing(pairing)
    if pairing == "receiver":
        return np.stack([t, t, t, t])
    return np.stack([t.T, t, t.T, t])


def message_coefficients(tables) -> np.ndarray:
    """Per direction, (oo, oe, oo + eo, oe + ee): with cavity weights A (occupied) and B (empty) at the sender, a
    message is one division, P(receiver occupied) = ``(oo*A + oe*B) / ((oo + eo)*A + (oe + ee)*B)``."""
    tables = np.asarray(tables, dtype=np.float64)
    oo, oe, eo, ee = tables[:, 0, 0], tables[:, 0, 1], tables[:, 1, 0], tables[:, 1, 1]
    return np.stack([oo, oe, oo + eo, oe + ee], axis=1)


def link_unary(observed, link) -> np.ndarray:
    """P(occupied) that each observed node's message ``phi(c) = sum_o link[c, o] * P(o)`` tells its hidden cell
    (before flooring); 0.5 where the link calls the observation impossible under both states.

    >>> link_unary(np.array([[0.8]]), DEFAULT_LINK).tolist()
    [[0.8]]
    """
    link = check_table(link, "link")
    p = np.asarray(observed, dtype=np.float64)
    if p.ndim == 2 and p.size:  # a grid: one pass over rows in bands (NumPy's eight temporaries cost far more)
        out = np.empty(p.shape)
        over_rows(_link_unary_rows, p.shape[0], np.ascontiguousarray(p), link, out)
        return out
    occ = link[0, 0] * p + link[0, 1] * (1.0 - p)
    emp = link[1, 0] * p + link[1, 1] * (1.0 - p)
    total = occ + emp
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(total > 0, occ / np.where(total > 0, total, 1.0), 0.5)
    return u


@njit(cache=True, nogil=True)  # no fastmath: the same operations in the same order, so bit for bit NumPy's
def _link_unary_rows(p, link, out, r0, r1):
    """out[y, x] = :func:`link_unary` of p[y, x] for rows [r0, r1)."""
    for y in range(r0, r1):
        for x in range(p.shape[1]):
            v = p[y, x]
            occ = link[0, 0] * v + link[0, 1] * (1.0 - v)
            emp = link[1, 0] * v + link[1, 1] * (1.0 - v)
            total = occ + emp
            out[y, x] = occ / total if total > 0 else 0.5
