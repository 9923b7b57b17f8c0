"""Benchmarks that print numbers: the suite behind ``crfmap bench``, the NumPy baseline, external libraries, online mapping.

Modules:

- :mod:`crfstudy.bench.suite`: ``run``, ``format_record``, ``to_json``
- :mod:`crfstudy.bench.goals`: issue 13's rows (end to end vs kernel, cold / warm start, explorer redraw,
  reproduce time, convergence from each start), run by ``run(goals=True)``
"""
