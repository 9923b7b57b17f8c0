"""Benchmarks that print numbers: the suite behind ``crfmap bench``, the NumPy baseline, external libraries, online mapping.

Public API (imported on first use, so ``import crfmap.bench`` stays cheap):

- :mod:`crfmap.bench.suite`: ``run``, ``format_record``, ``to_json``
- :mod:`crfmap.bench.goals`: issue 13's rows (end to end vs kernel, cold / warm start, explorer redraw,
  reproduce time, convergence from each start), run by ``run(goals=True)``
"""
from __future__ import annotations

import importlib

_API = {
    "run": "suite",
    "format_record": "suite",
    "to_json": "suite",
}
__all__ = sorted(_API)


def __getattr__(name):
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_API))
