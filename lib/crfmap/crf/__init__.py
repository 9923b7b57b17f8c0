"""The CRF and its inference, in three layers a reader can take one at a time.

- :mod:`crfmap.crf.model`: what the CRF is: ``potentials`` (the two 2x2 tables and their checks), ``evidence`` (cells
  made certain by hard evidence), ``gating`` (what a cell's own evidence lets nav2 read).
- :mod:`crfmap.crf.inference`: how it is solved: ``lbp.infer`` (checks its input, picks a kernel, returns an
  ``LBPResult``), ``schedules`` (and the plain kernels that run them), ``regions``, ``multiscale``, ``compiling``. The
  references the tests compare with (brute force, a textbook LBP) are the study's (``crfstudy.references``).
- :mod:`crfmap.crf.engine`: the fast checkerboard engine (its modules: its docstring).
- :mod:`crfmap.crf.presets`: named configurations, model and solver together, the one source of settings for every
  path; above the three layers, since a preset runs inference.
- :mod:`crfmap.crf.threads`: row bands of ``nogil`` kernels on Python threads, used by all three layers.

From :func:`infer` to the kernel that updates a message: ``infer -> engine.solve.solve -> PackedBlock.run -> _pass``
(fast), ``infer -> run_schedule -> kernel`` (plain).

Public API (imported on first use, so ``import crfmap.crf`` stays cheap):
"""
from __future__ import annotations

from crfmap.lazy import api_listing, attach

_API = {
    "DEFAULT_HIDDEN": "model.potentials",
    "DEFAULT_LINK": "model.potentials",
    "check_table": "model.potentials",
    "check_pairing": "model.potentials",
    "directional_tables": "model.potentials",
    "link_unary": "model.potentials",
    "DEFAULT_PRESET": "presets",
    "PRESETS": "presets",
    "Preset": "presets",
    "get_preset": "presets",
    "custom_preset": "presets",
    "CRITICAL_COUPLING": "presets",
    "table_coupling": "presets",
    "infer": "inference.lbp",
    "message": "inference.lbp",
    "LBPResult": "inference.result",
    "SCHEDULES": "inference.schedules",
    "Checkerboard": "inference.schedules",
    "Flooding": "inference.schedules",
    "Sweep": "inference.schedules",
    "Thesis": "inference.schedules",
    "near_known": "inference.regions",
    "near_cells": "inference.regions",
    "disc_region": "inference.regions",
    "initial_messages": "engine.messages",
    "MESSAGE_FLOOR": "engine.messages",
    "PackedBlock": "engine.packed",
    "IncrementalLBP": "engine.incremental",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
__doc__ += api_listing(__name__, _API)
