"""Benchmarks that print numbers: the suite behind ``crfmap bench``, the NumPy baseline, external libraries, online mapping.

Public API (imported on first use, so ``import crfmap.bench`` stays cheap):

- :mod:`crfmap.bench.suite`: ``run``, ``format_record``, ``to_json``
- :mod:`crfmap.bench.goals`: issue 13's rows (end to end vs kernel, cold / warm start, explorer redraw,
  reproduce time, convergence from each start), run by ``run(goals=True)``
"""
from __future__ import annotations

from crfmap.lazy import attach

_API = {
    "run": "suite",
    "format_record": "suite",
    "to_json": "suite",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
