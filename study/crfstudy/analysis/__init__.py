"""The study's analyses of the presets: the searches that chose them and what coupling adds.

- :mod:`crfstudy.analysis.preset_search`: ``coordinate_search`` (the search that chose the certainty preset, on Intel)
- :mod:`crfstudy.analysis.coordinate`: ``coordinate_descent``, the search rule of the preset's and the peers' searches
- :mod:`crfstudy.analysis.gate_search`: the gated preset's J x pi search (``python -m crfstudy.analysis.gate_search``)
- :mod:`crfstudy.analysis.peer_search`: ``octomap_search``, ``hilbert_coordinate_search`` (the peers' constants, on Intel)
- :mod:`crfstudy.analysis.ablations`: ``ablation_presets``, ``IsotonicEvidence``, ``PlattRaw``
- :mod:`crfstudy.analysis.modelspace`: ``symmetric_tables``, ``fit_scaled``, ``scaled_scores``, ``fit_pseudolikelihood``
- :mod:`crfstudy.analysis.crossval`: ``cross_validate``, ``leave_one_out``, ``random_folds``, ``block_folds``, ``neighbour_mean`` (the office's hidden-cell folds, Table 26)
- :mod:`crfstudy.analysis.samecells`: ``fold_scores``, ``block_scores`` (every method on the cells all decide)
"""
