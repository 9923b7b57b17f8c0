"""Every numbered notebook executes headlessly under papermill with its small (quick) settings.

Outputs go to a temporary folder (CRFMAP_OUTPUT_ROOT), never into the checkout.
"""
from pathlib import Path

import pytest

from crfmap import paths
from crfmap.repro.dependencies import data_needed

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.ipynb"))


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(notebook, tmp_path, monkeypatch):
    import papermill as pm

    missing = [f for f in data_needed(notebook) if not paths.have_data(f)]
    if missing:
        pytest.skip(f"{notebook.name} needs shared data not found under {paths.data_root()}: {', '.join(missing)} "
                    "(see data/README.md)")

    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    out = tmp_path / "out" / notebook.name
    out.parent.mkdir(parents=True)
    pm.execute_notebook(str(notebook), str(out), parameters={"quick": True}, kernel_name="python3",
                        cwd=str(notebook.parent), progress_bar=False, execution_timeout=1200)
    produced = list((tmp_path / "figures").glob("*.png")) + list((tmp_path / "paper" / "generated").glob("*"))
    assert produced, f"{notebook.name} saved no figure or table"
