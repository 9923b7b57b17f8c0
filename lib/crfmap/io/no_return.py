"""Which readings of a laser log are no-return codes, not hits, when neither the log (``PARAM
robot_front_laser_max``) nor the user (``--max-range``) names the maximum range: one rule, with its reasons.

A CARMEN log writes "no return" as a reading at or beyond the maximum range, whose exact value varies within and
across logs (81.83-81.91 m in SICK logs, 50.00 m in ACES, 51.05 and 51.10 m in one log)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

NO_RETURN_TOLERANCE = 0.005  # [m] readings this close below the maximum range count as at it (logs print cm)
SICK_NO_RETURN = 80.0  # [m] a SICK LMS 2xx measures at most 80 m; readings beyond are its no-return codes
SPIKE_MIN_COUNT = 10  # readings exactly at the file's maximum before it may be a no-return code ...
SPIKE_RATIO = 3.0  # ... and this many times more than in the SPIKE_BAND below it
SPIKE_BAND = 0.5  # [m]
CODE_GAP = 0.06  # [m] codes of one log lie within a few cm of each other (51.05 and 51.10; 51.14-51.16) ...
CODE_SPREAD = 0.25  # [m] ... and within this of the top (81.83-81.91 in one SICK log)
CODE_STRAYS = 3  # readings above the codes set aside as strays (one 51.25 above codes at 51.14-51.16)
MIN_CODE_RANGE = 4.0  # [m] no scanning laser of these logs stops short of this (Hokuyo URG: 4-5.6 m; SICK 8-80 m)


@dataclass(frozen=True)
class MaxRangeGuess:
    """``max_range`` [m]: readings at or beyond it are codes (None: all hits); ``reason`` in words; ``warning``: one
    line naming ``--max-range`` when readings look like codes the rule did not take (or None)."""

    max_range: float | None
    reason: str
    warning: str | None = None


def _code_cluster(finite):
    """(lowest value, count) of the readings at the top of ``finite`` (strays set aside) that lie together as codes
    do: no gap over :data:`CODE_GAP`, within :data:`CODE_SPREAD` (a real wall's readings spread further)."""
    top_k = np.sort(np.partition(finite, max(finite.size - 1 - CODE_STRAYS, 0))[-(CODE_STRAYS + 1):])
    top = float(top_k[0])  # the (CODE_STRAYS + 1)-th largest reading
    near = np.unique(finite[(finite >= top - CODE_SPREAD) & (finite <= top)])[::-1]
    low = top
    for value in near[1:]:
        if low - value > CODE_GAP:
            break
        low = float(value)
    return low, int(np.count_nonzero(finite >= low - NO_RETURN_TOLERANCE))


def no_return_rule(ranges) -> MaxRangeGuess:
    """The maximum range [m] a log's readings imply, with its reason.

    Readings beyond :data:`SICK_NO_RETURN` are codes. Else the pile at the top (:func:`_code_cluster`) is codes if
    it is many (:data:`SPIKE_MIN_COUNT`), :data:`SPIKE_RATIO` times denser than the :data:`SPIKE_BAND` below, and at
    least :data:`MIN_CODE_RANGE` away; the maximum range is its lowest value (strays above it are no-returns too).
    Such a pile below :data:`MIN_CODE_RANGE`, or only as dense as below it, is kept as hits with a warning.

    >>> r = np.r_[np.linspace(1, 49.9, 500), np.full(40, 50.0)]
    >>> no_return_rule(r).max_range, no_return_rule(np.linspace(1, 12, 500)).max_range
    (50.0, None)
    >>> no_return_rule(np.r_[r, 81.87, 81.91]).max_range
    80.0
    >>> codes = np.r_[np.linspace(1, 30, 500), np.full(20, 51.05), np.full(20, 51.10), 51.25]
    >>> no_return_rule(codes).max_range
    51.05
    """
    finite = np.asarray(ranges, dtype=np.float64).ravel()
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        return MaxRangeGuess(None, "no finite readings")
    if finite.max() >= SICK_NO_RETURN:
        return MaxRangeGuess(SICK_NO_RETURN, f"readings beyond {SICK_NO_RETURN:g} m, a SICK LMS's limit, are codes")
    low, n_code = _code_cluster(finite)
    n_below = int(np.count_nonzero((finite >= low - SPIKE_BAND) & (finite < low - NO_RETURN_TOLERANCE)))
    top = float(finite.max())
    at = f"{low:g} m" if top - low < NO_RETURN_TOLERANCE else f"{low:g}-{top:g} m"
    pile = f"{n_code} readings at {at} against {n_below} in the {SPIKE_BAND:g} m below"
    if n_code >= SPIKE_MIN_COUNT and n_code >= SPIKE_RATIO * n_below:
        if low >= MIN_CODE_RANGE:
            return MaxRangeGuess(low, f"no-return codes: {pile}")
        return MaxRangeGuess(None, f"kept as hits: {pile}, but below {MIN_CODE_RANGE:g} m",
                             f"{pile} look like no-return codes, kept as hits (below {MIN_CODE_RANGE:g} m); "
                             f"pass --max-range {low:g} if they are")
    if n_code >= SPIKE_MIN_COUNT and n_code >= n_below:
        return MaxRangeGuess(None, f"kept as hits: {pile}",
                             f"{pile} may be no-return codes, kept as hits; pass --max-range {low:g} if they are")
    return MaxRangeGuess(None, "none found (every reading is a hit)")

