"""environment.yml (conda) and pyproject.toml (pip) describe the same dependencies: the library's and the study's."""
import re
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def _name(spec: str) -> str:
    return re.split(r"[<>=!~ \[]", spec.strip(), maxsplit=1)[0].lower().replace("_", "-")


def test_environment_yml_matches_pyproject():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    pip_names = {_name(d) for d in project["dependencies"]}
    for extra in ("study", "ros", "test"):  # the study's full environment
        pip_names |= {_name(d) for d in project["optional-dependencies"][extra]}
    env = yaml.safe_load((ROOT / "environment.yml").read_text())
    conda_names = set()
    for dep in env["dependencies"]:
        if isinstance(dep, dict):
            conda_names |= {_name(d) for d in dep.get("pip", []) if not d.startswith("-")}
        else:
            conda_names.add(_name(dep))
    conda_names -= {"python", "pip"}
    assert conda_names == pip_names, (sorted(conda_names - pip_names), sorted(pip_names - conda_names))


def test_make_lab_allows_root_only_for_root():
    """JupyterLab refuses to start as root without --allow-root (containers and CI images run as root)."""
    import os
    import subprocess

    out = subprocess.run(["make", "-n", "-o", "warm", "lab"], capture_output=True, text=True, cwd=ROOT).stdout
    assert "jupyter lab notebooks/" in out and ("--allow-root" in out) == (os.getuid() == 0)
