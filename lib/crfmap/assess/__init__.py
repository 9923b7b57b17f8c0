"""How good a grid is, and learning the potentials that make it better.

Public API (imported on first use, so ``import crfmap.assess`` stays cheap):
"""
from __future__ import annotations

from crfmap.lazy import api_listing, attach

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
__doc__ += api_listing(__name__, _API)
