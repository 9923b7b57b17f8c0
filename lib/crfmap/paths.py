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

import os
from pathlib import Path

from crfmap.errors import DataMissingError

PROJECT_ROOT = Path(os.environ.get("CRFMAP_ROOT", Path(__file__).resolve().parents[2]))
NOTEBOOKS = PROJECT_ROOT / "notebooks"
PAPER = PROJECT_ROOT / "paper"
# Outputs go under the checkout unless CRFMAP_OUTPUT_ROOT points elsewhere (the tests do that,
# so executing the notebooks in CI never touches the checkout's figures/).
OUTPUT_ROOT = Path(os.environ.get("CRFMAP_OUTPUT_ROOT", PROJECT_ROOT))
FIGURES = OUTPUT_ROOT / "figures"
GENERATED = OUTPUT_ROOT / "paper" / "generated"
OUT = OUTPUT_ROOT / "out"

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
    env = os.environ.get("CRFMAP_DATA")
    if env:
        return Path(env).expanduser().resolve()
    return (PROJECT_ROOT.parent / "shared" / "data").resolve()


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
    for folder in (FIGURES, GENERATED, OUT):
        folder.mkdir(parents=True, exist_ok=True)
