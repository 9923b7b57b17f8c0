"""Lazy public APIs for the subpackages: a name is imported from its submodule on first use.

Each subpackage's ``__init__`` holds ``_API = {"name": "submodule", ...}`` (the list of what it offers, also
read by :mod:`crfstudy.repro.dependencies`) and ends with
``__getattr__, __dir__, __all__ = attach(__name__, _API)``, as scikit-image's lazy_loader does, so that
``import crfmap.io`` stays cheap and ``from crfmap.io import read_bag`` still works.
"""
from __future__ import annotations

import importlib
import sys


def attach(package: str, api: dict) -> tuple:
    """(``__getattr__``, ``__dir__``, ``__all__``) for the package named ``package`` exposing ``api``.

    >>> getattr_, dir_, all_ = attach("crfmap.crf", {"infer": "inference.lbp"})
    >>> getattr_("infer").__name__, all_
    ('infer', ['infer'])
    """
    def __getattr__(name):
        module = api.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)  # imported once: later lookups skip __getattr__
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(api))

    return __getattr__, __dir__, sorted(api)
