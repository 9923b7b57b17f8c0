"""`pip install crfmap` gets the library, not the study: its required dependencies hold no study tool."""
import re
import tomllib
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDY_TOOLS = {"jupyterlab", "papermill", "nbmake", "snakemake", "typst", "pypandoc-binary", "ipywidgets",
               "ipykernel", "nbstripout", "matplotlib", "pytest"}


def _name(requirement: str) -> str:
    return re.split(r"[<>=!~ ;\[]", requirement.strip(), maxsplit=1)[0].lower().replace("_", "-")


def test_the_installed_distribution_requires_no_study_tool():
    """Read from the installed distribution's metadata (what pip resolves), not only from pyproject.toml."""
    required = [r for r in metadata.requires("crfmap") or [] if "extra ==" not in r]
    assert required and not {_name(r) for r in required} & STUDY_TOOLS, required
    extras = {m.group(1) for r in metadata.requires("crfmap") or [] for m in [re.search(r'extra == "([^"]+)"', r)] if m}
    assert {"study", "ros", "test"} <= extras


def test_pyproject_keeps_the_study_in_its_extra_and_its_own_distribution():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert not {_name(r) for r in project["dependencies"]} & STUDY_TOOLS
    assert {"jupyterlab", "papermill", "snakemake", "typst"} <= {_name(r) for r in project["optional-dependencies"]["study"]}
    study = tomllib.loads((ROOT / "study" / "pyproject.toml").read_text())
    assert study["project"]["name"] == "crfmap-study"
    assert study["project"]["entry-points"]["crfmap.commands"] == {"bench": "crfstudy.bench.cli"}
    assert not list((ROOT / "lib").glob("crfstudy")), "the study must not sit inside lib/ (setuptools would ship it)"
