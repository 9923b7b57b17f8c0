"""A preset's temperature fitted on a scan split of the training recording (Intel), and the preset with it.

:func:`crfmap.assess.calibration.fit_temperature` fits T (``P' = sigmoid(logit(P) / T)``) by the log-loss;
:func:`fit_split_temperature` does so for a map of a scan split, and :func:`tempered_preset` gives the preset with
that T (its ``temperature`` field, applied by the preset's own refinement).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from crfmap.assess.calibration import fit_temperature
from crfmap.crf.presets import get_preset
from crfmap.errors import InputError


def fit_split_temperature(split, prediction, group: str = "all") -> float:
    """The temperature of ``prediction`` ([y, x] P on ``split``'s grid) fitted to the second half's labels.

    Fit it on the training recording (Intel) only; the P given is the untempered one (a preset of
    temperature 1), and the T returned is what :func:`tempered_preset` puts in the preset.
    """
    values = np.asarray(getattr(prediction, "probability", prediction), dtype=np.float64)
    if values.shape != split.shape:
        raise InputError("prediction", f"shape {values.shape} does not match the split's grid {split.shape}")
    mask = split.group(group)
    if not mask.any():
        raise InputError("split", f"no cell of group {group!r} to fit a temperature on")
    return fit_temperature(values[mask], split.labels()[mask])


def tempered_preset(preset, temperature: float):
    """``preset`` (a :class:`~crfmap.crf.presets.Preset` or its name) with ``temperature`` T.

    >>> from crfmap.crf.presets import DEFAULT_PRESET
    >>> tempered_preset(DEFAULT_PRESET, 0.9).temperature
    0.9
    """
    base = get_preset(preset) if isinstance(preset, str) else preset
    return replace(base, temperature=temperature)
