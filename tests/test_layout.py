"""The package layout: every subpackage's public API resolves, no import circles, no private names across subpackages,
no re-export shims (a name is imported from the module that defines it)."""
import ast
import json
import importlib
from pathlib import Path

import pytest

LIB = Path(__file__).resolve().parents[1] / "lib" / "crfmap"
SUBPACKAGES = sorted(p.name for p in LIB.iterdir() if (p / "__init__.py").exists())


@pytest.mark.parametrize("sub", SUBPACKAGES)
def test_public_api_resolves(sub):
    package = importlib.import_module(f"crfmap.{sub}")
    for name in getattr(package, "__all__", []):
        assert getattr(package, name) is not None, f"crfmap.{sub}.{name}"


def _module_name(path):
    rel = path.relative_to(LIB.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _imports(path):
    """(module imported, names imported, at module level?) of every crfmap import in a file."""
    tree = ast.parse(path.read_text())
    top = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("crfmap"):
            yield node.module, [a.name for a in node.names], id(node) in top
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("crfmap"):
                    yield a.name, [], id(node) in top


def _subpackage(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 2 or (len(parts) == 2 and parts[1] in SUBPACKAGES) else ""


def _graph():
    graph = {}
    for path in LIB.rglob("*.py"):
        name = _module_name(path)
        deps = set()
        for mod, names, _ in _imports(path):
            for n in names:  # `from crfmap.crf import packed` imports a module
                if importlib.util.find_spec(f"{mod}.{n}") if _is_package(mod) else False:
                    deps.add(f"{mod}.{n}")
            deps.add(mod)
        graph[name] = deps - {name}
    return graph


def _is_package(mod):
    spec = importlib.util.find_spec(mod)
    return spec is not None and spec.submodule_search_locations is not None


def test_no_import_circles():
    graph = _graph()
    # a package's __init__ resolves names lazily; it imports nothing at load time
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for dep in graph.get(node, ()):
            if dep not in graph:
                continue
            if state.get(dep) == "open":
                cycle = stack[stack.index(dep):] + [dep]
                pytest.fail("import circle: " + " -> ".join(cycle))
            if dep not in state:
                visit(dep)
        stack.pop()
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node)


def test_no_private_name_across_subpackages():
    offenders = []
    for path in LIB.rglob("*.py"):
        here = _subpackage(_module_name(path))
        for mod, names, _ in _imports(path):
            there = _subpackage(mod)
            if there == here:
                continue
            private_module = any(part.startswith("_") for part in mod.split(".")[1:])
            private_names = [n for n in names if n.startswith("_")]
            if private_module or private_names:
                offenders.append(f"{_module_name(path)}: from {mod} import {', '.join(names)}")
    assert not offenders, "\n".join(offenders)


def test_modules_stay_small():
    big = {str(p.relative_to(LIB)): n for p in LIB.rglob("*.py") if (n := len(p.read_text().splitlines())) > 420}
    assert not big, f"modules over ~400 lines: {big}"


def _crf_private_imports(tree):
    """``from crfmap.crf... import _name`` or any import of a ``crfmap.crf`` module with a private part."""
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("crfmap.crf"):
            parts = node.module.split(".")[2:]
            names = [a.name for a in node.names]
            if any(p.startswith("_") for p in parts) or any(n.startswith("_") for n in names):
                yield f"from {node.module} import {', '.join(names)}"
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("crfmap.crf") and any(p.startswith("_") for p in a.name.split(".")[2:]):
                    yield f"import {a.name}"


def test_nothing_outside_crf_imports_a_private_name_of_crf():
    """crf/'s kernels stay behind its public functions: library, tests of other packages and notebooks."""
    root = LIB.parents[1]
    offenders = []
    files = [p for p in LIB.rglob("*.py") if "crf" not in p.relative_to(LIB).parts[:1]]
    files += [p for p in (root / "tests").rglob("*.py") if p.relative_to(root / "tests").parts[0] != "crf"]
    for path in files:
        offenders += [f"{path.relative_to(root)}: {s}" for s in _crf_private_imports(ast.parse(path.read_text()))]
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        for cell in json.loads(path.read_text())["cells"]:
            if cell["cell_type"] == "code":
                source = "\n".join(line for line in "".join(cell["source"]).splitlines()
                                   if not line.lstrip().startswith(("%", "!")))
                offenders += [f"{path.name}: {s}" for s in _crf_private_imports(ast.parse(source))]
    assert not offenders, "\n".join(offenders)


def _top_level(tree):
    """(names a module defines, {name: module} of what it imports from other crfmap modules) at its top level."""
    defined, imported = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            defined.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            defined.update(e.id for t in targets for e in ast.walk(t) if isinstance(e, ast.Name))
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("crfmap"):
            imported.update({a.asname or a.name: node.module for a in node.names})
    return defined, imported


def _dunder_all(tree):
    return {e.value for node in tree.body if isinstance(node, ast.Assign)
            and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets)
            for e in ast.walk(node.value) if isinstance(e, ast.Constant) and isinstance(e.value, str)}


def _modules():
    """{module name: parsed tree} of every crfmap module but the packages' ``__init__`` (their lazy public APIs)."""
    return {_module_name(p): ast.parse(p.read_text()) for p in LIB.rglob("*.py") if p.name != "__init__.py"}


def test_no_module_re_exports_a_name_it_imports():
    """A crfmap name imported into a module is used there; it is not passed on (unused, or listed in ``__all__``)."""
    offenders = []
    for name, tree in sorted(_modules().items()):
        _, imported = _top_level(tree)
        used = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
        exported = _dunder_all(tree)
        offenders += [f"{name}: {n} (from {mod})" for n, mod in sorted(imported.items())
                      if n not in used or n in exported]
    assert not offenders, "re-exported names (import them from their own module):\n" + "\n".join(offenders)


def _sources(root):
    for path in [*(root / "lib").rglob("*.py"), *(root / "tests").rglob("*.py"), *(root / "workflow").rglob("*.py")]:
        yield str(path.relative_to(root)), path.read_text()
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        for cell in json.loads(path.read_text())["cells"]:
            if cell["cell_type"] == "code":
                yield path.name, "\n".join(line for line in "".join(cell["source"]).splitlines()
                                            if not line.lstrip().startswith(("%", "!")))


def test_names_are_imported_from_the_module_that_defines_them():
    """``from crfmap.x import y`` names the module defining ``y``, not one that merely imports it (lib, tests, notebooks)."""
    tops = {name: _top_level(tree) for name, tree in _modules().items()}
    offenders = []
    for where, source in _sources(LIB.parents[1]):
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.ImportFrom) and node.module in tops:
                pairs = [(node.module, a.name) for a in node.names]
            elif isinstance(node, ast.Call) and len(node.args) >= 2 and all(
                    isinstance(a, ast.Constant) and isinstance(a.value, str) for a in node.args[:2]):
                pairs = [(node.args[0].value, node.args[1].value)]  # importlib-style: f("crfmap.x", "name")
            else:
                continue
            for module, name in pairs:
                defined, imported = tops.get(module, ((), {}))
                if name not in defined and name in imported:
                    offenders.append(f"{where}:{node.lineno}: {name} from {module} (defined in {imported[name]})")
    assert not offenders, "\n".join(offenders)


def test_presets_are_the_one_place_that_names_a_preset():
    """Outside ``crf/presets.py`` the library says ``DEFAULT_PRESET`` (or a preset's ``.name``), never the
    default preset's name as a literal: changing the default is one line."""
    import re

    from crfmap.crf.presets import DEFAULT_PRESET, PRESETS

    literal = re.compile(r"""["']({})["']""".format("|".join(map(re.escape, PRESETS))))
    offenders = [f"{p.relative_to(LIB)}:{n}: {line.strip()}" for p in sorted(LIB.rglob("*.py"))
                 if p.relative_to(LIB).as_posix() != "crf/presets.py"
                 for n, line in enumerate(p.read_text().splitlines(), 1)
                 if any(m.group(1) == DEFAULT_PRESET for m in literal.finditer(line))]
    assert not offenders, "\n".join(offenders)


def test_the_library_never_imports_the_study_and_the_study_uses_public_names_only():
    """The line between the installed library (lib/crfmap) and the study beside it (study/crfstudy): no arrow from the
    library to the study, and the study imports no private module or name of the library."""
    study = LIB.parents[1] / "study" / "crfstudy"
    up = [f"{p.relative_to(LIB)}: {node.module if isinstance(node, ast.ImportFrom) else node.names[0].name}"
          for p in LIB.rglob("*.py") for node in ast.walk(ast.parse(p.read_text()))
          if (isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "crfstudy")
          or (isinstance(node, ast.Import) and any(a.name.split(".")[0] == "crfstudy" for a in node.names))]
    private = [f"{p.relative_to(study.parent)}: {mod} {names}" for p in study.rglob("*.py")
               for mod, names, _ in _imports(p) if mod.split(".")[0] == "crfmap"
               and (any(part.startswith("_") for part in mod.split(".")) or any(n.startswith("_") for n in names))]
    assert study.is_dir() and not up and not private, "\n".join(up + private)
