"""The study's own environment variables, checked before its entry points run anything (crfmap's own variables:
:mod:`crfmap.environment`, which :func:`prepare` checks too).

============================  ==================================  ==================================================
variable                      read by                             accepted
============================  ==================================  ==================================================
``CRFMAP_OUTPUT_ROOT``        :mod:`crfstudy.paths`               a folder, existing or not; writable where written
``CRFMAP_RUN``                :mod:`crfstudy.repro.provenance`    a JSON object (set by :mod:`crfstudy.repro.run`)
``CRFMAP_REPRODUCE_STARTED``  :mod:`crfstudy.repro.buildinfo`     a Unix time (set by ``make reproduce`` for the paper)
============================  ==================================  ==================================================
"""
from __future__ import annotations

import json
import math
import os

from crfmap import environment
from crfmap.environment import named_value
from crfmap.errors import InputError
from crfstudy import paths


def run_context() -> dict | None:
    """``$CRFMAP_RUN`` (the notebook :mod:`crfstudy.repro.run` executes and its parameters), or None if unset.

    >>> os.environ["CRFMAP_RUN"] = '{"notebook": "04_denoising.ipynb", "parameters": {"noise": 0.3}}'
    >>> run_context()["parameters"]
    {'noise': 0.3}
    >>> del os.environ["CRFMAP_RUN"]
    """
    text = os.environ.get("CRFMAP_RUN", "")
    if not text.strip():
        return None
    try:
        run = json.loads(text)
    except ValueError as exc:
        raise InputError(named_value("CRFMAP_RUN", text), f"not JSON ({exc.msg})") from None
    notebook, parameters = (run.get("notebook"), run.get("parameters", {})) if isinstance(run, dict) else (0, 0)
    if not (notebook is None or (isinstance(notebook, str) and "/" not in notebook)) \
            or not isinstance(parameters, dict):
        raise InputError(named_value("CRFMAP_RUN", text), 'expected {"notebook": "NAME.ipynb", "parameters": {...}}')
    return {"notebook": notebook, "parameters": parameters}


def reproduce_started() -> float | None:
    """``$CRFMAP_REPRODUCE_STARTED``: when ``make reproduce`` started (Unix time), or None when unset or empty."""
    text = os.environ.get("CRFMAP_REPRODUCE_STARTED", "")
    if not text.strip():
        return None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value <= 0:
        raise InputError(named_value("CRFMAP_REPRODUCE_STARTED", text), "expected a Unix time in seconds")
    return value


def prepare() -> None:
    """:func:`crfmap.environment.prepare` after checking the study's variables (InputError naming the first bad one):
    what the study's entry points (the workflow's runner, ``reproduce``, the warm-up, a notebook's first cell) call
    first."""
    run_context()
    reproduce_started()
    paths.output_root()
    environment.prepare()
