"""Reproducing the thesis: saving figures and tables, running the notebooks, rendering the paper.

Public API (imported on first use, so ``import crfmap.repro`` stays cheap):

- :mod:`crfmap.repro.report`: ``save_figure``, ``save_table``, ``save_numbers``, ``load_numbers``, ``markdown_table``
- :mod:`crfmap.repro.paper`: ``build_paper``, ``render``
- :mod:`crfmap.repro.dependencies`: ``notebooks``, ``data_needed``, ``library_sources``, ``declared_outputs``, ``parameter_defaults``
- :mod:`crfmap.repro.run`: ``run_notebook`` (one notebook, papermill, into an output root)
- :mod:`crfmap.repro.sweep`: ``load``, ``collect`` (parameter grids over a notebook)
- :mod:`crfmap.repro.provenance`: what run made a result (``current``, ``read``, ``problem``)
- :mod:`crfmap.repro.reproduce`: the workflow (``workflow/Snakefile``) from the command line
"""
from __future__ import annotations

from crfmap.lazy import attach

_API = {
    "save_figure": "report",
    "save_table": "report",
    "save_numbers": "report",
    "load_numbers": "report",
    "markdown_table": "report",
    "build_paper": "paper",
    "render": "paper",
    "run_notebook": "run",
    "notebooks": "dependencies",
    "data_needed": "dependencies",
    "library_sources": "dependencies",
    "declared_outputs": "dependencies",
    "parameter_defaults": "dependencies",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
