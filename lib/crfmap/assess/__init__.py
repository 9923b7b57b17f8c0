"""How good a grid is, and learning the potentials that make it better: metrics, scan-split validation, baselines
and peers as rows, navigation and localisation, learning.

Public API (imported on first use, so ``import crfmap.assess`` stays cheap):

- :mod:`crfmap.assess.metrics`: ``evaluate``, ``Report``, ``mse``, ``confusion``, ``roc_curve``, ``auc``
- :mod:`crfmap.assess.scansplit`: ``scan_split``, ``ScanSplit``, ``score`` (validation on scans the map never saw)
- :mod:`crfmap.assess.baselines`: ``all_baselines``, ``window_mean``, ``window_median``, ``grey_closing``, ``graph_cut``
- :mod:`crfmap.assess.navigation`: ``nav_scores``, ``nav2_classes``, ``wall_shape`` (the map as nav2 reads the written trinary file, scored on a scan split)
- :mod:`crfmap.assess.localisation`: ``localise``, ``compare_localisation`` (maps scored by nav2_amcl's likelihood field on held-out scans)
- :mod:`crfmap.assess.likelihood_field`: ``LaserModel``, ``LikelihoodField`` (nav2_amcl's laser model, as nav2 computes it)
- :mod:`crfmap.assess.comparison`: ``compare``, ``method_names`` (every evaluated row of a scan split)
- :mod:`crfmap.assess.calibration`: ``fit_temperature`` (one temperature for a model's log-odds)
- :mod:`crfmap.assess.learning`: ``learn_thesis``, ``learn_gradient``, ``learn_pseudolikelihood``, ``LearningResult``, ``lbp_mse``, ``rescale``
"""
from __future__ import annotations

from crfmap.lazy import attach

_API = {
    "evaluate": "metrics",
    "Report": "metrics",
    "mse": "metrics",
    "confusion": "metrics",
    "roc_curve": "metrics",
    "auc": "metrics",
    "learn_thesis": "learning",
    "learn_gradient": "learning",
    "learn_pseudolikelihood": "learning",
    "LearningResult": "learning",
    "lbp_mse": "learning",
    "rescale": "learning",
    "scan_split": "scansplit",
    "ScanSplit": "scansplit",
    "score": "scansplit",
    "compare": "comparison",
    "method_names": "comparison",
    "LikelihoodField": "likelihood_field",
    "all_baselines": "baselines",
    "window_mean": "baselines",
    "window_median": "baselines",
    "grey_closing": "baselines",
    "graph_cut": "baselines",
    "nav_scores": "navigation",
    "nav2_classes": "navigation",
    "wall_shape": "navigation",
    "localise": "localisation",
    "compare_localisation": "localisation",
    "LaserModel": "likelihood_field",
    "fit_temperature": "calibration",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
