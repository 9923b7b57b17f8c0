"""Reproducing the thesis: saving figures and tables, running the notebooks, rendering the paper.

Modules:

- :mod:`crfstudy.repro.report`: ``save_figure``, ``save_table``, ``save_numbers``, ``load_numbers``, ``markdown_table``
- :mod:`crfstudy.repro.paper`: ``build_paper``, ``render``
- :mod:`crfstudy.repro.dependencies`: ``notebooks``, ``data_needed``, ``library_sources``, ``declared_outputs``, ``parameter_defaults``
- :mod:`crfstudy.repro.run`: ``run_notebook`` (one notebook, papermill, into an output root)
- :mod:`crfstudy.repro.sweep`: ``load``, ``collect`` (parameter grids over a notebook)
- :mod:`crfstudy.repro.provenance`: what run made a result (``current``, ``read``, ``problem``)
- :mod:`crfstudy.repro.reproduce`: the workflow (``workflow/Snakefile``) from the command line
"""
