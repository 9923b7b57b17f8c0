"""Where the study writes its outputs: the one place that knows the checkout's folders.

Notebooks and commands never build paths from the working directory; they ask here.

- ``PROJECT_ROOT``: the checkout (``CRFMAP_ROOT`` overrides it); ``CRFMAP_OUTPUT_ROOT`` moves
  every output folder below elsewhere.
- ``FIGURES``: generated figures (``figures/``), ``GENERATED``: generated tables and
  numbers for the paper (``paper/generated/``), ``OUT``: executed notebooks and
  other run outputs (``out/``). None of these are committed.
- The public data recorded by others: :mod:`crfmap.data` (the library reads it too).
"""
from __future__ import annotations

from pathlib import Path

from crfmap import environment
from crfmap.errors import InputError

# PROJECT_ROOT, NOTEBOOKS, PAPER, OUTPUT_ROOT, FIGURES, GENERATED and OUT are read from the environment
# at each use (module __getattr__ below), so a bad value is refused where it is read, in one line.
_LAZY = {"PROJECT_ROOT": (), "NOTEBOOKS": ("notebooks",), "PAPER": ("paper",), "OUTPUT_ROOT": (),
         "FIGURES": ("figures",), "GENERATED": ("paper", "generated"), "OUT": ("out",)}
for _name in _LAZY:  # importlib.reload keeps old module attributes: a value a test once set must not stick
    globals().pop(_name, None)


def project_root() -> Path:
    """The checkout: ``$CRFMAP_ROOT`` (an existing folder) or the folder holding ``lib/crfmap``."""
    return environment.folder("CRFMAP_ROOT", Path(__file__).resolve().parents[2], must_exist=True)


def output_root() -> Path:
    """Where outputs go: ``$CRFMAP_OUTPUT_ROOT`` or the checkout. The tests set it, so executing the
    notebooks in CI never touches the checkout's figures/."""
    return environment.folder("CRFMAP_OUTPUT_ROOT", project_root())


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    root = output_root() if name in ("OUTPUT_ROOT", "FIGURES", "GENERATED", "OUT") else project_root()
    return root.joinpath(*_LAZY[name])


def output_dir(folder) -> Path:
    """``folder`` (under the output root) created if missing; InputError naming CRFMAP_OUTPUT_ROOT if it cannot be."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"CRFMAP_OUTPUT_ROOT={output_root()}",
                         f"cannot create {folder} ({exc.strerror or exc})") from None
    return folder


def ensure_output_dirs() -> None:
    """Create the output folders (figures, generated tables, run outputs)."""
    root = output_root()
    for folder in (root / "figures", root / "paper" / "generated", root / "out"):
        output_dir(folder)
