"""The study around the crfmap library: what reproduces the thesis and goes beyond it.

Not installed by ``pip install crfmap``; ``make venv`` installs it beside the library. It uses only the
library's public API.

- :mod:`crfstudy.repro`: running the notebooks (papermill, the Snakemake workflow), saving figures and tables,
  provenance, the paper;
- :mod:`crfstudy.experiments`: the thesis's experiments and the study's own as functions the notebooks call;
- :mod:`crfstudy.analysis`: the searches and ablations that chose and test the presets;
- :mod:`crfstudy.bench`: benchmarks that print numbers (``python -m crfstudy.bench``, ``make bench``);
- :mod:`crfstudy.paths`: the checkout's output folders; :mod:`crfstudy.plotting`: the figures' drawing helpers.
"""
