"""The thesis's experiments as functions the notebooks call: the scan -> grid -> LBP -> score pipeline, the explorer, the background chapter.

Public API (imported on first use, so ``import crfmap.experiments`` stays cheap):

- :mod:`crfmap.experiments.pipeline`: ``scan_scene``, ``evaluate_pipeline``, ``train_and_test``, ``search_tables``, ``PipelineResult``, ``TrainTest``
- :mod:`crfmap.experiments.explorer`: ``explore``, ``observe``, ``run``, ``draw``, ``warm_up``
- :mod:`crfmap.experiments.explorer_view` / ``explorer_panel``: the live figure updated in place, the widget panel
- :mod:`crfmap.experiments.office_online`: ``map_online``, ``online_numbers``, ``OnlineRun``, ``versus_offline``, ``near_versus_offline``, ``default_table_drift``
- :mod:`crfmap.experiments.background`: ``gibbs_ising``, ``ising_exact``, ``ising_energy``
- :mod:`crfmap.experiments.thesis_learning`: the learning experiments' tables (notebooks 05, 06): ``make_learners``, ``metrics_table``, ``potentials_rows``, ``results_summary``, ``same_cells_predictions``
- :mod:`crfmap.experiments.scene_figures`: ``draw`` (a grid with the robot's start), ``landscape_figure``
- :mod:`crfmap.experiments.occlusion_why`: why the occlusion result does not reproduce (``why_study`` and its tables)
- :mod:`crfmap.experiments.speed_tables` / ``speed_figures``: notebook 09's tables and goals figure from ``crfmap bench`` records
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
