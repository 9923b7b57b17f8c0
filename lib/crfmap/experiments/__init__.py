"""The thesis's experiments as functions the notebooks call: the scan -> grid -> LBP -> score pipeline, the explorer, the background chapter.

Public API (imported on first use, so ``import crfmap.experiments`` stays cheap):

- :mod:`crfmap.experiments.pipeline`: ``scan_scene``, ``evaluate_pipeline``, ``train_and_test``, ``search_tables``, ``PipelineResult``, ``TrainTest``
- :mod:`crfmap.experiments.explorer`: ``explore``, ``observe``, ``run``, ``draw``, ``warm_up``
- :mod:`crfmap.experiments.explorer_view` / ``explorer_panel``: the live figure updated in place, the widget panel
- :mod:`crfmap.experiments.office_online`: ``map_online``, ``online_numbers``, ``OnlineRun``, ``versus_offline``, ``near_versus_offline``, ``default_table_drift``
- :mod:`crfmap.experiments.background`: ``gibbs_ising``, ``ising_exact``, ``ising_energy``
"""
from __future__ import annotations

from crfmap.lazy import attach

_API = {
    "scan_scene": "pipeline",
    "evaluate_pipeline": "pipeline",
    "train_and_test": "pipeline",
    "search_tables": "pipeline",
    "PipelineResult": "pipeline",
    "TrainTest": "pipeline",
    "explore": "explorer",
    "observe": "explorer",
    "run": "explorer",
    "draw": "explorer",
    "map_online": "office_online",
    "online_numbers": "office_online",
    "OnlineRun": "office_online",
    "versus_offline": "office_online",
    "near_versus_offline": "office_online",
    "default_table_drift": "office_online",
    "warm_up": "explorer",
    "gibbs_ising": "background",
    "ising_exact": "background",
    "ising_energy": "background",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
