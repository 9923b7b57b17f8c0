"""The Snakemake workflow: its DAG, what reruns after a change, a failed notebook, a quick sweep, the cluster profile.

Every run goes to a temporary --directory (outputs) and, where files of the checkout would change,
to a temporary copy of it (CRFMAP_ROOT), so the checkout's figures/ and paper/generated/ are never touched.
"""
import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from crfstudy import paths
from crfstudy.repro import dependencies as deps
from crfstudy.repro import provenance

ROOT = Path(__file__).resolve().parents[3]
SNAKEFILE = ROOT / "workflow" / "Snakefile"


def snakemake(*args, cwd, env=None, check=True):
    command = [sys.executable, "-m", "snakemake", *args, "--snakefile", str(SNAKEFILE), "--directory", str(cwd),
               "--cores", "2"]
    done = subprocess.run(command, capture_output=True, text=True, env={**os.environ, **(env or {})}, timeout=900)
    if check and done.returncode != 0:
        raise AssertionError(f"snakemake failed:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}")
    return done


def planned(done) -> dict:
    """{rule: count} from the job table snakemake prints."""
    rules, table = {}, False
    for line in (done.stdout + done.stderr).splitlines():
        parts = line.split()
        if parts[:2] == ["job", "count"]:
            table, rules = True, {}
        elif table and len(parts) == 2 and parts[1].isdigit():
            if parts[0] != "total":
                rules[parts[0]] = int(parts[1])
        elif table and parts and not set(parts[0]) <= {"-"}:
            table = False
    return rules


@pytest.fixture
def fake_data(tmp_path, monkeypatch):
    """Empty stand-ins for the shared-data files (a dry run only needs them to exist)."""
    root = tmp_path / "data"
    for nb in deps.notebooks():
        for relative in deps.data_needed(nb):
            (root / relative).parent.mkdir(parents=True, exist_ok=True)
            (root / relative).touch()
    monkeypatch.setenv("CRFMAP_DATA", str(root))
    return root


@pytest.fixture
def checkout_copy(tmp_path):
    """A copy of the checkout's notebooks, library, study, paper template and workflow (what the DAG reads)."""
    root = tmp_path / "checkout"
    for folder in ("notebooks", "lib", "study", "paper", "workflow"):
        shutil.copytree(ROOT / folder, root / folder, ignore=shutil.ignore_patterns("generated", "__pycache__"))
    return root


def test_dry_run_plans_one_rule_per_notebook_and_the_paper(tmp_path, fake_data):
    done = snakemake("--dry-run", cwd=tmp_path / "out")
    expected = {f"notebook_{nb.stem}": 1 for nb in deps.notebooks()} | {"paper": 1, "all": 1}
    assert planned(done) == expected
    assert not (tmp_path / "out" / "figures").exists()  # a dry run writes no result


def test_touching_a_module_reruns_only_the_notebooks_that_import_it(checkout_copy, tmp_path, fake_data):
    env = {"CRFMAP_ROOT": str(checkout_copy)}
    work = tmp_path / "out"
    # make every output exist, then mark all of them up to date without running anything
    for nb in deps.notebooks():
        for relative in deps.declared_outputs(nb) + [f"out/notebooks/{nb.name}"]:
            (work / relative).parent.mkdir(parents=True, exist_ok=True)
            (work / relative).touch()
    for relative in ("paper/generated/paper.md", "paper/generated/reproduce_timings.json"):
        (work / relative).touch()
    snakemake("--touch", cwd=work, env=env)
    assert "Nothing to be done" in snakemake("--dry-run", cwd=work, env=env).stdout
    module = checkout_copy / "study" / "crfstudy" / "paired.py"
    module.write_text(module.read_text() + "\n# an edit\n")  # a content change (a bare touch is not one to snakemake)
    users = {f"notebook_{nb.stem}" for nb in deps.notebooks()
             if any(p.name == "paired.py" and p.parent.name == "crfstudy" for p in deps.library_sources(nb))}
    assert users and len(users) < len(deps.notebooks())
    assert planned(snakemake("--dry-run", cwd=work, env=env)) == {**{u: 1 for u in users}, "paper": 1, "all": 1}


def test_static_dependencies_cover_what_a_notebook_really_imports():
    """Reference: execute each notebook's import lines in a fresh interpreter and list the crfmap files loaded."""
    probe = ("import ast, json, sys\nfrom crfstudy.repro.dependencies import code_cells\n"
             "nodes = [n for c in code_cells(sys.argv[1]) for n in ast.walk(ast.parse(''.join(c['source'])))\n"
             "         if isinstance(n, (ast.Import, ast.ImportFrom))]\n"
             "exec('\\n'.join(ast.unparse(n) for n in nodes))\n"
             "print(json.dumps(sorted(m.__file__ for n, m in sys.modules.items()\n"
             "                        if n.startswith(('crfmap', 'crfstudy')) and getattr(m, '__file__', None))))\n")
    runs = {nb: subprocess.Popen([sys.executable, "-c", probe, str(nb)], stdout=subprocess.PIPE, text=True)
            for nb in deps.notebooks()}
    for nb, run in runs.items():
        loaded = {Path(f).resolve() for f in json.loads(run.communicate(timeout=600)[0])}
        static = {p.resolve() for p in deps.library_sources(nb)}
        assert loaded - static == set(), f"{nb.name}: imports not seen by library_sources"


def _one_cell_notebook(source: str) -> dict:
    """A notebook with a ``parameters`` cell (quick = False) and one code cell."""
    return {"cells": [
        {"cell_type": "code", "metadata": {"tags": ["parameters"]}, "source": "quick = False", "outputs": [],
         "execution_count": None},
        {"cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None, "source": source}],
        "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}},
        "nbformat": 4, "nbformat_minor": 5}


def test_a_failed_notebook_leaves_no_stale_outputs_and_names_its_log(checkout_copy, tmp_path):
    failing = _one_cell_notebook("from crfstudy.repro.report import save_numbers\nsave_numbers('half_done', {'x': 1})\n"
                                 "raise ValueError('broken on purpose')")
    (checkout_copy / "notebooks" / "99_fails.ipynb").write_text(json.dumps(failing))
    work = tmp_path / "out"
    done = snakemake("notebook_99_fails", cwd=work, env={"CRFMAP_ROOT": str(checkout_copy)}, check=False)
    assert done.returncode != 0
    text = done.stdout + done.stderr
    assert "run: 99_fails.ipynb failed: ValueError: broken on purpose" in text
    assert "out/logs/99_fails.ipynb" in text and (work / "out" / "logs" / "99_fails.ipynb").is_file()
    assert not (work / "paper" / "generated" / "half_done.json").exists()
    assert not (work / "out" / "notebooks" / "99_fails.ipynb").exists()


def test_quick_sweep_of_two_points_runs_into_its_own_folders(tmp_path):
    sweeps = tmp_path / "sweeps"
    sweeps.mkdir()
    (sweeps / "toy.yaml").write_text("notebook: 02_worked_example\nparameters:\n  noise: [0.3, 0.5]\n"
                                     "fixed: {quick: true}\nheadline: [learning_toy.mse_observed]\n")
    work = tmp_path / "out"
    snakemake("out/runs/toy/collected.csv", "--config", f"sweeps={sweeps}", cwd=work)
    runs = work / "out" / "runs" / "toy"
    for point, noise in (("noise=0.3", 0.3), ("noise=0.5", 0.5)):
        assert (runs / point / "02_worked_example.ipynb").is_file()
        assert list((runs / point / "figures").glob("*.png"))
        stamp = provenance.read(runs / point / "paper" / "generated" / "learning_toy.json")
        assert stamp["parameters"]["noise"] == noise and stamp["quick"] is True
    rows = list(csv.DictReader((runs / "collected.csv").open()))
    assert [(r["point"], float(r["noise"])) for r in rows] == [("noise=0.3", 0.3), ("noise=0.5", 0.5)]
    assert all(float(r["learning_toy.mse_observed"]) > 0 for r in rows)
    assert rows[0]["learning_toy.mse_observed"] != rows[1]["learning_toy.mse_observed"]  # the parameter reached the run
    assert json.loads((runs / "collected.json").read_text())["rows"][1]["noise"] == 0.5
    assert (runs / "collected.png").stat().st_size > 0
    assert not (work / "figures").exists() and not (work / "paper").exists()  # the default results are untouched


def test_cluster_profile_dry_run(tmp_path, fake_data):
    pytest.importorskip("snakemake_executor_plugin_slurm")
    done = snakemake("--dry-run", "--workflow-profile", str(ROOT / "workflow" / "profiles" / "slurm"),
                     cwd=tmp_path / "out")
    assert "Using workflow specific profile" in done.stdout + done.stderr
    assert planned(done)["paper"] == 1


def test_sweep_file_errors_name_the_file(tmp_path):
    from crfmap.errors import InputError
    from crfstudy.repro.sweep import load

    bad = tmp_path / "bad.yaml"
    bad.write_text("notebook: 04_denoising\nparameters:\n  nosie: [0.3]\n")
    with pytest.raises(InputError, match=r"bad.yaml: nosie not in the parameters cell of 04_denoising.ipynb"):
        load(bad)


def test_committed_notebooks_hold_no_outputs():
    for nb in sorted(paths.NOTEBOOKS.glob("*.ipynb")):
        cells = json.loads(nb.read_text())["cells"]
        dirty = [i for i, c in enumerate(cells) if c["cell_type"] == "code" and (c.get("outputs") or c.get("execution_count"))]
        assert not dirty, f"{nb.name}: cells {dirty} hold outputs (install the nbstripout filter: make venv)"


def test_jupyter_kernel_uses_the_numba_cache_make_warms():
    if "NUMBA_CACHE_DIR" not in os.environ:
        pytest.skip("NUMBA_CACHE_DIR not set: run through make")
    from jupyter_client.kernelspec import KernelSpecManager

    spec = KernelSpecManager().get_kernel_spec("python3")
    assert spec.env.get("NUMBA_CACHE_DIR") == os.environ["NUMBA_CACHE_DIR"]


def test_notebooks_run_longest_first_and_a_benchmark_alone(tmp_path, fake_data):
    done = snakemake("--dry-run", cwd=tmp_path / "out")
    rules, current = {}, None
    for line in (done.stdout + done.stderr).splitlines():
        if line.startswith("rule notebook_"):
            current = rules.setdefault(line[len("rule notebook_"):].rstrip(":"), {"threads": 1})
        elif current is not None and line.strip().startswith(("priority:", "threads:")):
            key, value = line.strip().split(":")
            current[key] = int(value)
    assert set(rules) == {nb.stem for nb in deps.notebooks()}
    order = sorted(rules, key=lambda stem: -rules[stem]["priority"])
    assert order.index("07_office") < order.index("08_explorer") and order[-1] == "08_explorer"  # shortest last
    assert rules["09_speed"]["threads"] == 2 and order[0] == "09_speed"  # all of --cores 2, first: nothing beside it
    assert all(r["threads"] == 1 for stem, r in rules.items() if stem != "09_speed")


def test_a_notebook_runs_with_the_threads_its_rule_got(checkout_copy, tmp_path):
    probe = _one_cell_notebook("import os, numba\nfrom crfstudy.repro.report import save_numbers\n"
                               "save_numbers('threads', {'numba': numba.config.NUMBA_NUM_THREADS, "
                               "'omp': os.environ.get('OMP_NUM_THREADS')})")
    (checkout_copy / "notebooks" / "99_threads.ipynb").write_text(json.dumps(probe))
    work = tmp_path / "out"
    snakemake("notebook_99_threads", cwd=work, env={"CRFMAP_ROOT": str(checkout_copy)})
    saved = json.loads((work / "paper" / "generated" / "threads.json").read_text())
    assert (saved["numba"], saved["omp"]) == (1, "1")
