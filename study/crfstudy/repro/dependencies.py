"""What a notebook depends on and what it makes, read from its source (no kernel, no imports).

The workflow (``workflow/Snakefile``) asks here for each notebook's

- :func:`library_sources`: the ``lib/crfmap`` files it imports, followed transitively through the
  library's own imports (lazy package APIs included), so touching one module reruns only the
  notebooks that import it;
- :func:`declared_outputs`: the figures and tables it saves through :mod:`crfstudy.repro.report`
  (``save_figure(fig, "name")``, ``save_table("name", ...)``, ``save_numbers("name", ...)``; a name
  must be a string literal, so the list is known before the notebook runs);
- :func:`parameter_defaults`: the literals of its ``parameters`` cell.
"""
from __future__ import annotations

import ast
import json
import re
from functools import lru_cache
from pathlib import Path
import importlib

from crfstudy import paths
from crfmap.errors import InputError

# the library (lib/crfmap) and the study (study/crfstudy) of the checkout (CRFMAP_ROOT moves it, as the workflow
# tests do with a copy); a notebook runs both, so a change to either reruns it
PACKAGES = {"crfmap": ("lib", "crfmap"), "crfstudy": ("study", "crfstudy")}


def _package_root(package: str) -> Path:
    """The package's folder in the checkout, else the imported package's (read at each use: CRFMAP_ROOT is checked
    then)."""
    checkout = paths.PROJECT_ROOT.joinpath(*PACKAGES[package])
    if checkout.is_dir():
        return checkout

    return Path(importlib.import_module(package).__file__).resolve().parent


def _ours(module: str) -> str | None:
    """The package of ours (crfmap or crfstudy) that ``module`` belongs to, or None."""
    top = module.split(".")[0]
    return top if top in PACKAGES else None


def code_cells(notebook) -> list[dict]:
    """The code cells of a notebook file, in order."""
    return [c for c in json.loads(Path(notebook).read_text())["cells"] if c["cell_type"] == "code"]


def _source(cell) -> str:
    text = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
    # IPython magics and shell escapes are not Python: blank them so the rest still parses
    return "\n".join("" if line.lstrip().startswith(("%", "!")) else line for line in text.splitlines())


def _tree(notebook, cell) -> ast.Module:
    try:
        return ast.parse(_source(cell))
    except SyntaxError as error:
        raise InputError(notebook, f"a code cell does not parse ({error.msg}, line {error.lineno})") from None


def parameter_defaults(notebook) -> dict:
    """The values the ``parameters`` cell assigns (literals only).

    >>> parameter_defaults(paths.NOTEBOOKS / "04_denoising.ipynb")["quick"]
    False
    """
    for cell in code_cells(notebook):
        if "parameters" in cell.get("metadata", {}).get("tags", []):
            values = {}
            for node in _tree(notebook, cell).body:
                if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
                    try:
                        values[node.targets[0].id] = ast.literal_eval(node.value)
                    except ValueError:
                        raise InputError(notebook, f"parameter {node.targets[0].id!r} is not a literal") from None
            return values
    return {}


def _module_file(module: str) -> Path | None:
    """The source file of a ``crfmap`` or ``crfstudy`` module or package, or None if there is none."""
    package = _ours(module)
    if package is None:
        return None
    base = _package_root(package).joinpath(*module.split(".")[1:])
    for candidate in (base / "__init__.py", base.with_suffix(".py")):
        if candidate.is_file():
            return candidate
    return None


def _lazy_api(tree: ast.Module) -> dict:
    """A package's ``_API = {"name": "submodule", ...}`` map (names imported on first use)."""
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_API" for t in node.targets):
            try:
                return dict(ast.literal_eval(node.value))
            except ValueError:
                return {}
    return {}


@lru_cache(maxsize=None)
def _parsed(file: Path) -> ast.Module:
    return ast.parse(file.read_text(), filename=str(file))


def _imports(tree: ast.Module, module: str, is_package: bool) -> set[str]:
    """The crfmap modules an AST imports (anywhere, functions included), as dotted names."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: from this module's package upwards
                parts = module.split(".") if is_package else module.split(".")[:-1]
                parts = parts[: len(parts) - node.level + 1]
                base = ".".join(parts + ([base] if base else []))
            found.add(base)
            found |= {f"{base}.{alias.name}" for alias in node.names}  # a submodule or a (lazy) attribute
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", "")) == "import_module":
            if node.args and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                found.add(node.args[0].value)
    return {name for name in found if _ours(name)}


def _closure(start: set[str]) -> set[Path]:
    files: set[Path] = set()
    todo = list(start)
    seen: set[str] = set()
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        seen.add(name)
        parts = name.split(".")
        todo += [".".join(parts[:i]) for i in range(1, len(parts))]  # importing a.b.c runs a and a.b
        file = _module_file(name)
        if file is None:  # an attribute of a package: a lazy API entry names the submodule that defines it
            parent = _module_file(".".join(parts[:-1]))
            if parent is not None and parent.name == "__init__.py":
                target = _lazy_api(_parsed(parent)).get(parts[-1])
                if target:
                    todo.append(".".join(parts[:-1] + [target]))
            continue
        files.add(file)
        todo += sorted(_imports(_parsed(file), name, file.name == "__init__.py"))
    return files


def module_sources(modules) -> list[Path]:
    """The library files that importing the given crfmap modules runs, transitively (sorted).

    >>> [p.name for p in module_sources(["crfmap.errors"])]
    ['__init__.py', '_numba_cache.py', 'environment.py', 'errors.py', 'grid.py']
    """
    return sorted(_closure(set(modules)))


def imported_modules(notebook) -> set[str]:
    """The crfmap names a notebook's code imports (``from crfmap.crf import infer`` gives ``crfmap.crf.infer``)."""
    found = set()
    for cell in code_cells(notebook):
        found |= _imports(_tree(notebook, cell), "__main__", False)
    return found


def library_sources(notebook) -> list[Path]:
    """The library files a notebook runs, transitively (sorted).

    >>> sorted(p.name for p in library_sources(paths.NOTEBOOKS / "04_denoising.ipynb"))[:2]
    ['__init__.py', '__init__.py']
    """
    return sorted(_closure(imported_modules(notebook)))


_SAVERS = {"save_figure": 1, "save_table": 0, "save_numbers": 0}  # which argument is the name
_SUFFIXES = {"save_figure": ("figures", [".png"]), "save_table": ("paper/generated", [".md", ".json"]),
             "save_numbers": ("paper/generated", [".json"])}


def declared_outputs(notebook) -> list[str]:
    """The files a notebook saves, relative to the output root (``figures/x.png``, ``paper/generated/t.md``).

    >>> "paper/generated/table14_denoising.md" in declared_outputs(paths.NOTEBOOKS / "04_denoising.ipynb")
    True
    """
    outputs = []
    for cell in code_cells(notebook):
        for node in ast.walk(_tree(notebook, cell)):
            if not isinstance(node, ast.Call):
                continue
            saver = getattr(node.func, "id", None) or getattr(node.func, "attr", None)
            if saver not in _SAVERS:
                continue
            position = _SAVERS[saver]
            name = node.args[position] if len(node.args) > position else next(
                (k.value for k in node.keywords if k.arg == "name"), None)
            if not (isinstance(name, ast.Constant) and isinstance(name.value, str)):
                raise InputError(notebook, f"{saver}(...) at line {node.lineno} of a cell does not name its output "
                                 "with a string literal (the workflow must know every output before it runs)")
            folder, suffixes = _SUFFIXES[saver]
            outputs += [f"{folder}/{name.value}{suffix}" for suffix in suffixes]
    return sorted(set(outputs))


def data_needed(notebook) -> list[str]:
    """The shared-data files (relative to :func:`crfmap.data.data_root`) a notebook reads with ``data_file``."""
    return sorted(set(re.findall(r'data_file\(\\"([^"\\]+)\\"\)', Path(notebook).read_text())))


def notebooks(only=None) -> list[Path]:
    """The numbered notebooks ``notebooks/NN_*.ipynb`` (a new one is picked up by its name alone)."""
    found = sorted(paths.NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))
    if only:
        found = [p for p in found if any(p.name.startswith(prefix) for prefix in only)]
    return found
