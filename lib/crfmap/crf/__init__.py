"""The CRF and its inference: potentials, loopy belief propagation, exact enumeration and a textbook reference LBP.

Public API (imported on first use, so ``import crfmap.crf`` stays cheap):

- :mod:`crfmap.crf.potentials`: ``DEFAULT_HIDDEN``, ``DEFAULT_LINK``, ``check_table``, ``check_pairing``, ``directional_tables``, ``link_unary``
- :mod:`crfmap.crf.lbp`: ``infer``, ``LBPResult``, ``SCHEDULES``, ``near_known``, ``disc_region``, ``initial_messages``
- :mod:`crfmap.crf.packed`: ``PackedBlock``
- :mod:`crfmap.crf.exact`: ``exact_marginals``
- :mod:`crfmap.crf.reference`: ``reference_lbp``
"""
from __future__ import annotations

from crfmap.lazy import attach

_API = {
    "DEFAULT_HIDDEN": "potentials",
    "DEFAULT_LINK": "potentials",
    "check_table": "potentials",
    "check_pairing": "potentials",
    "directional_tables": "potentials",
    "link_unary": "potentials",
    "infer": "lbp",
    "LBPResult": "lbp",
    "SCHEDULES": "lbp",
    "near_known": "lbp",
    "disc_region": "lbp",
    "initial_messages": "lbp",
    "PackedBlock": "packed",
    "exact_marginals": "exact",
    "reference_lbp": "reference",
}
__getattr__, __dir__, __all__ = attach(__name__, _API)
