"""Execute every numbered notebook headlessly with papermill, then build the paper.

``python -m crfmap.repro.reproduce`` (what ``make reproduce`` runs) executes ``notebooks/NN_*.ipynb`` in
order into ``out/notebooks/``, regenerating ``figures/`` and ``paper/generated/``, and then renders
the paper. ``--quick`` passes ``quick=True`` to every notebook (the small settings CI uses);
``--only 04`` runs the notebooks whose names start with the given prefixes.
"""
from __future__ import annotations

import argparse
import os
import re
import sys
import time
from pathlib import Path

from crfmap import paths
from crfmap.errors import DataMissingError


def notebooks(only=None) -> list[Path]:
    found = sorted(p for p in paths.NOTEBOOKS.glob("[0-9][0-9]_*.ipynb"))
    if only:
        found = [p for p in found if any(p.name.startswith(prefix) for prefix in only)]
    return found


def data_needed(notebook: Path) -> list[str]:
    """The shared-data files (relative to :func:`crfmap.paths.data_root`) a notebook reads with ``data_file``."""
    return sorted(set(re.findall(r'data_file\(\\"([^"\\]+)\\"\)', Path(notebook).read_text())))


def missing_data(todo) -> list[str]:
    """One line per shared-data file the notebooks need and this machine lacks: what to download, where."""
    lines = []
    for relative in sorted({f for nb in todo for f in data_needed(nb)}):
        try:
            paths.data_file(relative)
        except DataMissingError as error:
            users = ", ".join(nb.name for nb in todo if relative in data_needed(nb))
            lines.append(f"{error} -- needed by {users}")
    return lines


def execute(notebook: Path, parameters: dict | None = None, output_dir: Path | None = None,
            progress: bool = False, timeout: int = 3600) -> Path:
    """Execute one notebook with papermill (kernel ``python3``), cwd = the notebooks folder."""
    import papermill as pm

    output_dir = Path(output_dir or (paths.OUT / "notebooks"))
    output_dir.mkdir(parents=True, exist_ok=True)
    target = output_dir / notebook.name
    os.environ.setdefault("MPLBACKEND", "Agg")
    pm.execute_notebook(
        str(notebook), str(target), parameters=parameters or {}, kernel_name="python3",
        cwd=str(notebook.parent), progress_bar=progress, execution_timeout=timeout,
    )
    return target


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crfmap.repro.reproduce", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small settings (quick=True) in every notebook")
    parser.add_argument("--only", nargs="*", help="notebook name prefixes to run, e.g. 04 07")
    parser.add_argument("--no-paper", action="store_true", help="do not build the paper")
    args = parser.parse_args(argv)
    from tqdm.auto import tqdm

    todo = notebooks(args.only)
    missing = missing_data(todo)
    if missing:  # say it before anything runs, not after half the figures were regenerated
        for line in missing:
            print(f"reproduce: {line}", file=sys.stderr)
        print("reproduce: see data/README.md; nothing was run", file=sys.stderr)
        return 2
    paths.ensure_output_dirs()
    params = {"quick": True} if args.quick else {}
    timings = {}
    start = time.perf_counter()
    for nb in tqdm(todo, desc="notebooks", unit="nb"):
        t0 = time.perf_counter()
        try:
            execute(nb, params)
        except Exception as exc:  # papermill re-raises the cell's error; say which notebook and what
            what = f"{exc.ename}: {exc.evalue}" if hasattr(exc, "ename") else f"{type(exc).__name__}: {exc}"
            print(f"reproduce: {nb.name} failed: {what.splitlines()[0] if what else ''}", file=sys.stderr)
            print(f"reproduce: the executed notebook with the traceback is {paths.OUT / 'notebooks' / nb.name}",
                  file=sys.stderr)
            return 1
        timings[nb.name] = time.perf_counter() - t0
    if not args.no_paper:
        from crfmap.repro.paper import build_paper

        out = build_paper()
        print(f"paper: {out}")
    total = time.perf_counter() - start
    from crfmap.repro.report import save_numbers

    save_numbers("reproduce_timings", {"seconds": timings, "total_seconds": total, "quick": args.quick})
    for name, secs in timings.items():
        print(f"{secs:8.1f} s  {name}")
    print(f"{total:8.1f} s  total ({len(todo)} notebooks)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
