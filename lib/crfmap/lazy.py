"""Lazy public APIs for the subpackages: a name is imported from its submodule on first use (``lazy_loader``).

Each subpackage's ``__init__`` holds ``_API = {"name": "submodule", ...}`` (the list of what it offers, also
read by :mod:`crfstudy.repro.dependencies`) and ends with ``__getattr__, __dir__, __all__ = attach(__name__, _API)``,
so that ``import crfmap.io`` stays cheap and ``from crfmap.io import read_bag`` still works.
"""
from __future__ import annotations

import lazy_loader


def attach(package: str, api: dict) -> tuple:
    """(``__getattr__``, ``__dir__``, ``__all__``) of ``package`` exposing ``api`` ({name: submodule}), by lazy_loader.

    >>> getattr_, dir_, all_ = attach("crfmap.crf", {"infer": "inference.lbp"})
    >>> getattr_("infer").__name__, all_
    ('infer', ['infer'])
    """
    names_of = {}
    for name, module in api.items():
        names_of.setdefault(module, []).append(name)
    return lazy_loader.attach(package, submod_attrs=names_of)


def api_listing(package: str, api: dict) -> str:
    """The end of ``package``'s docstring: its public API ``api``, one line a name with the module defining it.

    >>> print(api_listing("crfmap.crf", {"infer": "inference.lbp"}), end="")
    <BLANKLINE>
    - ``infer`` (:mod:`crfmap.crf.inference.lbp`)
    """
    return "\n" + "\n".join(f"- ``{name}`` (:mod:`{package}.{module}`)" for name, module in api.items()) + "\n"
