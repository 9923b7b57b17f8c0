"""Reproducing the thesis: saving figures and tables, running the notebooks, rendering the paper.

Public API (imported on first use, so ``import crfmap.repro`` stays cheap):

- :mod:`crfmap.repro.report`: ``save_figure``, ``save_table``, ``save_numbers``, ``load_numbers``, ``markdown_table``
- :mod:`crfmap.repro.paper`: ``build_paper``, ``render``
- :mod:`crfmap.repro.reproduce`: ``execute``, ``notebooks``, ``data_needed``
"""
from __future__ import annotations

import importlib

_API = {
    "save_figure": "report",
    "save_table": "report",
    "save_numbers": "report",
    "load_numbers": "report",
    "markdown_table": "report",
    "build_paper": "paper",
    "render": "paper",
    "execute": "reproduce",
    "notebooks": "reproduce",
    "data_needed": "reproduce",
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
