"""The thesis's experiments as functions the notebooks call: the scan -> grid -> LBP -> score pipeline, the explorer, the background chapter.

Modules:

- :mod:`crfstudy.experiments.pipeline`: ``scan_scene``, ``evaluate_pipeline``, ``train_and_test``, ``search_tables``, ``PipelineResult``, ``TrainTest``
- :mod:`crfstudy.experiments.explorer`: ``explore``, ``observe``, ``run``, ``draw``, ``warm_up``, ``panel``
- :mod:`crfstudy.experiments.explorer_view` / ``explorer_panel``: the live figure updated in place, the widget panel
- :mod:`crfstudy.experiments.office_online`: ``map_online``, ``online_numbers``, ``OnlineRun``, ``versus_offline``, ``near_versus_offline``, ``default_table_drift``
- :mod:`crfstudy.experiments.intel_office`: notebook 07's figures, Table 26's predictors, folds and rows, the
  leave-one-out check, the same-cell scores, the online runs and table, the paper's numbers
- :mod:`crfstudy.experiments.background`: ``gibbs_ising``, ``ising_exact``, ``ising_energy``
- :mod:`crfstudy.experiments.thesis_learning`: the learning experiments of notebooks 05 and 06, their helper: ``make_learners``, ``metrics_table``, ``potentials_rows``, ``same_cells_scores``, the scene panels (``panels_figure``, ``landscape_figure``, ``roc_figure``), why the occlusion result does not reproduce (``why_study`` and its tables), the noisy generated rooms paired room by room (``noisy_rooms``, ``paired_over_rooms``)
- :mod:`crfstudy.experiments.speed`: notebook 09's benchmark run, figures and tables from ``crfmap bench`` records
- :mod:`crfstudy.experiments.nav_goals`: issue 38's goal table (notebook 12; ``python -m crfstudy.experiments.nav_goals``)
"""
