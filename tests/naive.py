"""Slow, obviously correct references for the fast kernels.

The textbook LBP lives in the study (:mod:`crfstudy.references`) because notebook 04 uses it
as the independent implementation too; this file adapts it for the tests.
"""
from crfstudy.references import lattice_neighbours, reference_lbp  # noqa: F401


def naive_flooding(observed, hidden, link, iterations, pairing="receiver", damping=0.0):
    """Beliefs after exactly ``iterations`` synchronous updates."""
    return reference_lbp(observed, hidden, link, iterations, pairing=pairing, damping=damping)[0]
