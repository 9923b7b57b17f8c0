"""What a command may write: never over its input (unless ``--force``), never over a folder of other files."""
from __future__ import annotations

import os
from pathlib import Path

from crfmap.errors import InputError
from crfmap.io.map_server import read_map_yaml
from crfmap.checks import check_path_arg

MAP_IMAGE_SUFFIXES = (".pgm", ".png")


def written_files(output) -> list[Path]:
    """The files saving a grid to ``output`` may replace: ``x.npy`` + ``x.npy.yaml``, ``x.yaml`` + its image."""
    out = Path(output)
    if out.suffix.lower() == ".npy":
        return [out, out.with_name(out.name + ".yaml")]
    if out.suffix.lower() in (".yaml", ".yml"):
        return [out] + [out.with_suffix(s) for s in MAP_IMAGE_SUFFIXES]
    return [out]


def named_files(item) -> list[Path]:
    """The files an input names besides itself: a map YAML's ``image:`` (none if unreadable: loading says why)."""
    item = Path(item)
    if item.suffix.lower() not in (".yaml", ".yml") or item.name.lower().endswith(".npy.yaml"):
        return []

    try:
        return [Path(read_map_yaml(item)["image_path"])]
    except (InputError, OSError, RecursionError):
        return []


def _same(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def check_output(inputs, output, force=False, option="--force"):
    """InputError naming ``output`` if writing it would replace one of ``inputs`` or a file they name (a map YAML's
    image, whatever its name), unless ``force`` (an in-place update, atomic still)."""
    out_files = written_files(output)
    in_files = []
    for item in inputs:
        in_files += written_files(item)
        item = Path(item)
        if item.suffix.lower() in (".yaml", ".yml") and not item.name.lower().endswith(".npy.yaml"):
            in_files += [item.with_suffix(s) for s in MAP_IMAGE_SUFFIXES]
        in_files += named_files(item)
    for o in out_files:
        for i in in_files:
            if o == i or _same(o, i) or Path(os.path.abspath(o)) == Path(os.path.abspath(i)):
                if force:
                    return
                raise InputError(output, f"would replace the input file {i} (pass {option} to update it in place)")


GRID_SUFFIXES = (".yaml", ".yml", ".npy")


def check_grid_output(output):
    """InputError naming ``output`` unless it names a grid file (map_server ``.yaml``/``.yml`` or ``.npy``), checked
    before any work: not ``.``, not ``out.npy/`` (which ``Path`` reads as ``out.npy``).

    >>> check_grid_output("out.npy/")
    Traceback (most recent call last):
    ...
    crfmap.errors.InputError: out.npy/: ends in '/', a folder's name; expected a grid file name (.yaml or .npy)
    """
    path = check_path_arg(output, "grid file name (.yaml or .npy)", file=True)
    if not path.name.lower().endswith(GRID_SUFFIXES):
        raise InputError(output, "the output must end in .yaml/.yml (map_server map) or .npy")


def check_output_folder(output):
    """InputError naming ``output`` if it is an existing folder that is neither empty nor a ROS 2 bag."""
    out = Path(output)
    if out.is_dir():
        if not (out / "metadata.yaml").is_file() and any(out.iterdir()):
            raise InputError(out, "is a folder of other files, not a ROS 2 bag; not replacing it (choose a new name)")
    elif out.exists() and out.suffix != ".bag":
        raise InputError(out, "exists and is not a bag; not replacing it (choose a new name)")
