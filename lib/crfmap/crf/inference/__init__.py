"""How the CRF is solved: ``infer`` (``lbp``), its result, schedules, regions, the coarse start, and the references."""
