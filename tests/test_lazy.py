"""The subpackages' lazy public APIs (lazy_loader): every ``_API`` name resolves to its submodule's object, as the
hand-written loader it replaced did (tests/naive_replaced.py)."""
import ast
import importlib
from pathlib import Path

import pytest

import naive_replaced as old

LIB = Path(importlib.import_module("crfmap").__file__).parent
LAZY = sorted(p.parent.name for p in LIB.glob("*/__init__.py") if "_API = {" in p.read_text())


def _api(package):
    tree = ast.parse((LIB / package / "__init__.py").read_text())
    return next(ast.literal_eval(n.value) for n in tree.body
                if isinstance(n, ast.Assign) and any(getattr(t, "id", None) == "_API" for t in n.targets))


def test_some_subpackages_are_lazy():
    assert {"io", "crf", "assess", "world", "sim", "mapping"} <= set(LAZY)


@pytest.mark.parametrize("package", LAZY)
def test_every_public_name_is_its_submodules_object(package):
    api = _api(package)
    module = importlib.import_module(f"crfmap.{package}")
    old_getattr, _, old_all = old.attach(f"crfmap.{package}", api)
    assert module.__all__ == old_all
    assert set(api) <= set(dir(module))
    for name, submodule in api.items():
        want = getattr(importlib.import_module(f"crfmap.{package}.{submodule}"), name)
        assert getattr(module, name) is want is old_getattr(name)
    with pytest.raises(AttributeError):
        getattr(module, "no_such_name")


def test_from_import_works():
    from crfmap.io import read_bag
    from crfmap.io.bag_reader import read_bag as direct

    assert read_bag is direct
