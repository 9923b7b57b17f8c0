"""Slow, obviously-correct reference versions of the ray caster (crfmap.raycast), for the tests.

``exact_line`` enumerates the line cell by cell along its major axis and rounds the exact
(rational) minor coordinate to the nearest integer; an exact tie (a true line passing a
cell corner, thesis Fig. 15) is rounded towards the start's minor coordinate, which is
what Listing 1's error term does (checked in test_raycast.py).
"""
from __future__ import annotations

from fractions import Fraction


def _round_toward(value: Fraction, toward: int) -> int:
    """Nearest integer to ``value``; at an exact .5 the one nearer ``toward``."""
    lo = value.numerator // value.denominator  # floor
    frac = value - lo
    if frac < Fraction(1, 2):
        return lo
    if frac > Fraction(1, 2):
        return lo + 1
    return lo if abs(lo - toward) <= abs(lo + 1 - toward) else lo + 1


def exact_line(x0, y0, x1, y1):
    """Cells (x, y) of the segment between cell centres, one per step of the major axis, both ends included."""
    dx, dy = x1 - x0, y1 - y0
    n = max(abs(dx), abs(dy))
    if n == 0:
        return [(x0, y0)]
    cells = []
    for i in range(n + 1):
        t = Fraction(i, n)
        if abs(dx) >= abs(dy):
            x = x0 + (i if dx > 0 else -i)
            y = _round_toward(y0 + t * dy, y0)
        else:
            y = y0 + (i if dy > 0 else -i)
            x = _round_toward(x0 + t * dx, x0)
        cells.append((x, y))
    return cells


def is_tie(x0, y0, x1, y1) -> bool:
    """Whether the true segment passes exactly between two cells somewhere (a Fig. 15 ambiguity)."""
    dx, dy = x1 - x0, y1 - y0
    n = max(abs(dx), abs(dy))
    minor = dy if abs(dx) >= abs(dy) else dx
    return n > 0 and any((Fraction(i * minor, n) - Fraction(1, 2)).denominator == 1 for i in range(1, n))


def walk_first_hit(occupied, start, end):
    """First occupied cell after ``start`` on ``exact_line``; None if the walk leaves the grid or ends unblocked."""
    h, w = len(occupied), len(occupied[0])
    for x, y in exact_line(*start, *end)[1:]:
        if not (0 <= x < w and 0 <= y < h):
            return None
        if occupied[y][x]:
            return (x, y)
    return None
