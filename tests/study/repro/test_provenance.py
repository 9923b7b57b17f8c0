"""What run made a result: the workflow's runner (CRFMAP_RUN) or a browser kernel (its namespace)."""
import json
import sys
import types

from crfstudy import paths
from crfstudy.repro import provenance


def test_workflow_run_records_defaults_and_what_papermill_injected(monkeypatch):
    monkeypatch.setenv("CRFMAP_RUN", json.dumps({"notebook": "04_denoising.ipynb", "parameters": {"noise": 0.3}}))
    run = provenance.current()
    assert run["notebook"] == "04_denoising.ipynb" and run["quick"] is False
    assert run["parameters"]["noise"] == 0.3 and run["parameters"]["train_seed"] == 1


def test_browser_kernel_with_an_edited_parameters_cell_is_not_default(monkeypatch, tmp_path):
    monkeypatch.delenv("CRFMAP_RUN", raising=False)
    kernel = types.ModuleType("__main__")  # what a JupyterLab kernel's namespace holds after Run All
    kernel.__session__ = str(paths.NOTEBOOKS / "04_denoising.ipynb")
    kernel.quick, kernel.seed, kernel.train_seed, kernel.noise, kernel.toolbox_seed = False, 0, 1, 0.5, 0
    monkeypatch.setitem(sys.modules, "__main__", kernel)
    run = provenance.current()
    assert run == {"notebook": "04_denoising.ipynb", "quick": False,
                   "parameters": {"quick": False, "seed": 0, "train_seed": 1, "noise": 0.5, "toolbox_seed": 0}}
    result = tmp_path / "r.json"
    result.write_text(json.dumps({"x": 1, provenance.KEY: run}))
    assert provenance.problem(result) == (f"{result}: made by 04_denoising.ipynb with non-default parameters "
                                          "noise=0.5 (default 0.42); run `make reproduce`")
    kernel.noise = 0.42
    result.write_text(json.dumps({"x": 1, provenance.KEY: provenance.current()}))
    assert provenance.problem(result) is None
