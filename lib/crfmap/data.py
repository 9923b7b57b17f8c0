"""Where the public data recorded by others is read from: ``$CRFMAP_DATA``, else ``shared/data`` beside the checkout
that holds this package (``$CRFMAP_ROOT``). The data is never part of the project; a missing file's error says what
to download and where.
"""
from __future__ import annotations

from pathlib import Path

from crfmap import environment
from crfmap.errors import DataMissingError

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


__all__ = ["data_root", "data_file", "have_data"]


def data_root() -> Path:
    """The folder holding the public data (``CRFMAP_DATA`` or ``../shared/data``)."""
    given = environment.folder("CRFMAP_DATA")
    return (given or _checkout().parent / "shared" / "data").resolve()


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


def _checkout() -> Path:
    """The checkout this package was loaded from (``$CRFMAP_ROOT`` overrides it)."""
    return environment.folder("CRFMAP_ROOT", Path(__file__).resolve().parents[2], must_exist=True)
