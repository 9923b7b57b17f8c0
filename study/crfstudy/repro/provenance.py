"""Which run made a result: its notebook, parameters and ``quick`` flag, stored in the result itself.

:mod:`crfstudy.repro.report` stamps every file it saves with :func:`current` (a JSON file gets a
``"_provenance"`` key, a Markdown table an HTML comment on its last line, a PNG figure a text chunk),
and the paper build accepts only full default runs (:func:`problem`), so a quick run, a sweep point
or a browser run with an edited parameters cell can never slip into the paper.

Where the run context comes from, first match wins:

- ``CRFMAP_RUN``: JSON ``{"notebook": "04_denoising.ipynb", "parameters": {...}}`` set by the
  workflow's runner (:mod:`crfstudy.repro.run`) for the kernel it starts;
- a Jupyter kernel: the notebook of the session (``__session__`` / ``JPY_SESSION_NAME``) and the
  current values of its parameters in the kernel's namespace.
"""
from __future__ import annotations

import json
import math
import os
import sys
from pathlib import Path

from crfstudy import paths
from crfstudy.repro.dependencies import parameter_defaults
from crfstudy.repro.variables import run_context

KEY = "_provenance"  # in JSON results
PNG_KEY = "crfmap-provenance"  # PNG text chunk
MD_PREFIX = "<!-- crfmap-provenance: "


def _jsonable(value):
    try:
        json.dumps(value, allow_nan=False)
        return True
    except (TypeError, ValueError):
        return False


def _session_notebook(namespace) -> str | None:
    name = namespace.get("__session__") or os.environ.get("JPY_SESSION_NAME")
    return Path(str(name)).name if name and str(name).endswith(".ipynb") else None


def current() -> dict:
    """The run context of the process saving a result (see the module docstring).

    >>> sorted(current())
    ['notebook', 'parameters', 'quick']
    """
    namespace = vars(sys.modules.get("__main__", object()))
    given = run_context()
    if given:
        notebook, overrides = given["notebook"], dict(given["parameters"])
    else:
        notebook, overrides = _session_notebook(namespace), {}
    parameters = {}
    source = paths.NOTEBOOKS / notebook if notebook else None
    if source is not None and source.is_file():
        for name, default in parameter_defaults(source).items():
            # papermill: the defaults and what it injected; a browser kernel: the values it holds
            # (an edited parameters cell shows here)
            value = overrides.get(name, default) if given else namespace.get(name, default)
            parameters[name] = value if _jsonable(value) else repr(value)
    parameters.update({k: v for k, v in overrides.items() if _jsonable(v)})
    quick = bool(parameters.get("quick", namespace.get("quick", False)))
    return {"notebook": notebook, "parameters": parameters, "quick": quick}


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, (int, float)) and not isinstance(b, bool):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def read(path) -> dict | None:
    """The provenance stamped into a saved result, or None if it has none."""
    path = Path(path)
    if not path.is_file():
        return None
    if path.suffix == ".json":
        data = json.loads(path.read_text())
        return data.get(KEY) if isinstance(data, dict) else None
    if path.suffix == ".md":
        lines = path.read_text().rstrip("\n").splitlines()
        if lines and lines[-1].startswith(MD_PREFIX) and lines[-1].endswith(" -->"):
            return json.loads(lines[-1][len(MD_PREFIX):-4])
        return None
    if path.suffix == ".png":
        from PIL import Image

        with Image.open(path) as image:
            text = image.info.get(PNG_KEY)
        return json.loads(text) if text else None
    return None


def strip(text: str) -> str:
    """A Markdown table's text without its provenance line."""
    lines = text.rstrip("\n").splitlines()
    if lines and lines[-1].startswith(MD_PREFIX):
        lines = lines[:-1]
    return "\n".join(lines).rstrip("\n") + "\n"


def problem(path) -> str | None:
    """Why a result may not go into the paper (None if it may): no provenance, quick, or non-default.

    A result is default when every parameter it records equals the notebook's ``parameters`` cell.
    """
    stamp = read(path)
    if stamp is None:
        return f"{path}: records no run parameters (saved by an older crfmap or by hand); rerun its notebook"
    if stamp.get("quick"):
        return f"{path}: made by a quick run of {stamp.get('notebook')} (quick=True); run `make reproduce`"
    notebook = stamp.get("notebook")
    source = paths.NOTEBOOKS / notebook if notebook else None
    if source is None or not source.is_file():
        return f"{path}: made outside a known notebook ({notebook}); rerun its notebook with `make reproduce`"
    defaults = parameter_defaults(source)
    changed = [f"{k}={v!r} (default {defaults[k]!r})" for k, v in stamp.get("parameters", {}).items()
               if k in defaults and not _same(v, defaults[k])]
    changed += [f"{k}={v!r} (not a parameter)" for k, v in stamp.get("parameters", {}).items() if k not in defaults]
    if changed:
        return f"{path}: made by {notebook} with non-default parameters {', '.join(changed)}; run `make reproduce`"
    return None
