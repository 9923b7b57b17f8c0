"""Where crfmap reads data and writes outputs: the one place that knows paths.

Notebooks and commands never build paths from the working directory; they ask here.

- ``PROJECT_ROOT``: the checkout (``CRFMAP_ROOT`` overrides it); ``CRFMAP_OUTPUT_ROOT`` moves
  every output folder below elsewhere.
- ``FIGURES``: generated figures (``figures/``), ``GENERATED``: generated tables and
  numbers for the paper (``paper/generated/``), ``OUT``: executed notebooks and
  other run outputs (``out/``). None of these are committed.
- ``data_root()``: the public data recorded by others (``CRFMAP_DATA``, default
  ``../shared/data`` beside the checkout).
"""
from __future__ import annotations

from pathlib import Path

from crfmap import environment
from crfmap.errors import DataMissingError, InputError

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


# What each data file is and where to get it, for the error a user sees when it is missing.
DATA_SOURCES = {
    "carmen/intel-corrected.log.gz": "Intel Research Lab CARMEN log with corrected poses "
    "(Radish data set; e.g. the public repository acschaefer/ple, data/carmen/)",
    "carmen/aces-corrected.log.gz": "ACES building CARMEN log with corrected poses "
    "(Radish data set; e.g. the public repository acschaefer/ple, data/carmen/)",
    "carmen/csail-corrected.log.gz": "MIT CSAIL building CARMEN log with corrected poses "
    "(Radish data set; the public repository acschaefer/ple, data/carmen/)",
    "carmen/freiburg-101-corrected.log.gz": "Freiburg building 101 CARMEN log with corrected poses "
    "(Radish data set; the public repository acschaefer/ple, data/carmen/)",
    "rosbags/olin_comprobo24_turtlebot4/macfirst_floor_take_2": "ROS2 bag of a TurtleBot4 "
    "(public repository comprobo24/robot_localization, bags/)",
    "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml": "map_server map of the same "
    "floor (public repository comprobo24/robot_localization, bags/)",
    "rosbags/zaki0929_bagfiles/2019_jan17_expt04_bagfile.bag": "ROS1 bag (public repository "
    "zaki0929/bagfiles)",
    "images/ugm_X_32x32.csv": "the 32x32 'X' demo image of the UGM Matlab toolbox (X.mat), "
    "saved as CSV with 1 = background, 0 = stroke",
}


def data_root() -> Path:
    """The folder holding the public data (``CRFMAP_DATA`` or ``../shared/data``)."""
    given = environment.folder("CRFMAP_DATA")
    return (given or project_root().parent / "shared" / "data").resolve()


def data_file(relative: str) -> Path:
    """Path of a public data file under :func:`data_root`, or an error saying what to download.

    >>> data_file("carmen/intel-corrected.log.gz").name  # doctest: +SKIP
    'intel-corrected.log.gz'
    """
    path = data_root() / relative
    if not path.exists():
        what = DATA_SOURCES.get(relative, "this file")
        raise DataMissingError(
            path,
            f"not found; download {what} and put it at {path} "
            f"(or set CRFMAP_DATA to the folder that holds '{relative}')",
        )
    return path


def have_data(relative: str) -> bool:
    """Whether a public data file is present (tests skip, with a reason, when it is not)."""
    return (data_root() / relative).exists()


def ensure_output_dirs() -> None:
    """Create the output folders (figures, generated tables, run outputs)."""
    root = output_root()
    for folder in (root / "figures", root / "paper" / "generated", root / "out"):
        output_dir(folder)
