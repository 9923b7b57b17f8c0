"""Every numbered notebook executes headlessly under papermill with its small (quick) settings, and reads as the study.

Outputs go to a temporary folder (CRFMAP_OUTPUT_ROOT), never into the checkout.
"""
import json
from pathlib import Path

import pytest

from crfmap.data import data_root, have_data
from crfstudy.repro.dependencies import data_needed

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))


def test_every_numbered_notebook_is_found():
    assert [nb.stem[:2] for nb in NOTEBOOKS] == [f"{i:02d}" for i in range(1, len(NOTEBOOKS) + 1)]
    assert len(NOTEBOOKS) >= 12  # the parametrized tests below would pass on an empty folder


@pytest.mark.slow  # 15 s to minutes each; `make test` runs them in parallel (pytest -n)
@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(notebook, tmp_path, monkeypatch):
    from crfstudy.repro.run import import_papermill

    pm = import_papermill()

    missing = [f for f in data_needed(notebook) if not have_data(f)]
    if missing:
        pytest.skip(f"{notebook.name} needs shared data not found under {data_root()}: {', '.join(missing)} "
                    "(see data/README.md)")

    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    out = tmp_path / "out" / notebook.name
    out.parent.mkdir(parents=True)
    pm.execute_notebook(str(notebook), str(out), parameters={"quick": True}, kernel_name="python3",
                        cwd=str(notebook.parent), progress_bar=False, execution_timeout=1200)
    produced = list((tmp_path / "figures").glob("*.png")) + list((tmp_path / "paper" / "generated").glob("*"))
    assert produced, f"{notebook.name} saved no figure or table"


# ---- the shape of a notebook: the study read as a story of library calls -------------------------------------------
# A notebook imports the library's public API (the names a package lists in __all__), the study's notebook plumbing
# (crfstudy.repro.report: start, save, show) and at most one other study module, its helper; it defines nothing (a
# function a notebook needs is study code, tested where it lives); a code cell is at most SHAPE_CELL_LINES lines.
PUBLIC_PACKAGES = ("crfmap", "crfmap.data", "crfmap.world", "crfmap.sim", "crfmap.io", "crfmap.mapping", "crfmap.crf",
                   "crfmap.assess")
STUDY_PLUMBING = "crfstudy.repro.report"
SHAPE_CELL_LINES = 20


def shape_problems(notebook) -> list:
    """What keeps ``notebook`` from the shape above, one string each (empty: none)."""
    import ast
    import importlib

    cells = json.loads(Path(notebook).read_text())["cells"]
    code = [c for c in cells if c["cell_type"] == "code"]
    problems = []
    if not any("parameters" in c.get("metadata", {}).get("tags", []) for c in code):
        problems.append("no code cell tagged 'parameters'")
    helpers = set()
    for index, cell in enumerate(code):
        source = "".join(cell["source"])
        lines = len(source.splitlines())
        if lines > SHAPE_CELL_LINES:
            problems.append(f"code cell {index}: {lines} lines (at most {SHAPE_CELL_LINES})")
        tree = ast.parse("\n".join(line for line in source.splitlines() if not line.lstrip().startswith(("%", "!"))))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
                kind = "lambda" if isinstance(node, ast.Lambda) else f"{type(node).__name__} {node.name}"
                problems.append(f"code cell {index} defines {kind}")
            modules = []
            if isinstance(node, ast.Import):
                modules = [(alias.name, None) for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                modules = [(node.module, [alias.name for alias in node.names])]
            for module, names in modules:
                top = module.split(".")[0]
                if top == "crfmap":
                    if module not in PUBLIC_PACKAGES or names is None and module != "crfmap":
                        problems.append(f"code cell {index} imports {module}: not one of the public packages "
                                        f"{', '.join(PUBLIC_PACKAGES)}")
                        continue
                    public = set(importlib.import_module(module).__all__)
                    for name in names or []:
                        if name not in public:
                            problems.append(f"code cell {index} imports {name} from {module}: not in its __all__")
                elif top == "crfstudy" and module != STUDY_PLUMBING:
                    helpers.add(module if names is None or module != "crfstudy" else f"crfstudy.{names[0]}")
    if len(helpers) > 1:
        problems.append(f"imports {len(helpers)} study modules besides {STUDY_PLUMBING}: {', '.join(sorted(helpers))}")
    return problems


def _notebook(tmp_path, *sources, tagged=True):
    cells = [{"cell_type": "code", "source": s, "metadata": {"tags": ["parameters"] if tagged and i == 0 else []},
              "outputs": []} for i, s in enumerate(sources)]
    path = tmp_path / "nb.ipynb"
    path.write_text(json.dumps({"cells": cells}))
    return path


def test_the_shape_check_accepts_a_notebook_of_public_calls(tmp_path):
    nb = _notebook(tmp_path, "seed = 0", "import numpy as np\nfrom crfmap.crf import infer, get_preset\n"
                   "from crfstudy.repro.report import save_figure\nfrom crfstudy.experiments import denoising\n"
                   "%matplotlib inline\nresult = infer(np.zeros((3, 3)))")
    assert shape_problems(nb) == []


def test_the_shape_check_names_every_departure(tmp_path):
    nb = _notebook(tmp_path, "x = 1", "from crfmap.crf.inference.lbp import infer\nfrom crfmap.crf import _secret\n"
                   "import crfmap.assess.metrics\nfrom crfstudy import plotting\nfrom crfstudy.paired import a\n"
                   "def f():\n    return 1\nsquare = lambda v: v * v", "\n".join(["y = 2"] * 21), tagged=False)
    problems = shape_problems(nb)
    assert any("no code cell tagged 'parameters'" in p for p in problems)
    assert any("imports crfmap.crf.inference.lbp" in p for p in problems)
    assert any("imports _secret from crfmap.crf" in p for p in problems)
    assert any("imports crfmap.assess.metrics" in p for p in problems)
    assert any("2 study modules" in p and "crfstudy.plotting" in p and "crfstudy.paired" in p for p in problems)
    assert any("defines FunctionDef f" in p for p in problems)
    assert any("defines lambda" in p for p in problems)
    assert any("code cell 2: 21 lines" in p for p in problems)
    assert len(problems) == 8


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[nb.stem for nb in NOTEBOOKS])
def test_notebook_reads_as_the_study(notebook):
    assert shape_problems(notebook) == []
