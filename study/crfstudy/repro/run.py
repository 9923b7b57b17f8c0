"""Run one notebook with papermill into an output root: what each rule of the workflow does.

``python -m crfstudy.repro.run NOTEBOOK --output-root DIR [--parameters JSON] [--threads N] --executed
OUT.ipynb --log LOG.ipynb`` executes ``NOTEBOOK`` (kernel ``python3``, cwd = the notebooks folder) with its
figures and tables going to ``DIR/figures`` and ``DIR/paper/generated`` (``CRFMAP_OUTPUT_ROOT``)
and its run recorded in each of them (``CRFMAP_RUN``, :mod:`crfstudy.repro.provenance`). The executed
notebook is written to ``LOG`` as it runs and copied to ``OUT`` only on success; on failure one
stderr line names the notebook, the error and ``LOG`` (the workflow then deletes the rule's outputs,
so nothing stale is left).

``--threads N`` caps the kernel's numba, OpenMP and BLAS threads at N (the cores the workflow gave the
rule). The workflow runs notebooks side by side with one each: their LBP runs on grids of a few
thousand cells, where a parallel region's thread wake-up (on a machine whose other core is busy
with the other notebook, one scheduler time slice) costs far more than the work it shares.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
from pathlib import Path

from crfstudy.repro import variables
from crfmap.errors import CrfmapError


THREAD_VARIABLES = ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


def import_papermill():
    """papermill, imported without the IRI checker jsonschema would load with it.

    nbformat imports jsonschema, whose format module eagerly imports ``rfc3987_syntax`` when it is
    installed (jupyter-events pulls it in); that builds ~35 Lark parsers, about 2 s of every notebook
    run's start (python-jsonschema/jsonschema#1428). No notebook schema uses the ``iri`` formats it
    checks, so it is kept out of this process: jsonschema then leaves those two formats unchecked.
    """
    if "jsonschema" not in sys.modules:  # too late once jsonschema is in: leave that process as it is
        sys.modules.setdefault("rfc3987_syntax", None)  # None: its import raises ImportError, which jsonschema skips
    import papermill

    return papermill


def run_notebook(notebook, output_root, parameters=None, executed=None, log=None, timeout=3600,
                 threads=None) -> Path:
    """Execute ``notebook`` into ``output_root``; returns the executed notebook's path.

    ``threads``: the most threads the kernel's numba, OpenMP and BLAS may start (None: their defaults).

    Raises papermill's execution error (with ``ename``/``evalue``) when a cell fails.
    """
    pm = import_papermill()
    notebook, output_root = Path(notebook).resolve(), Path(output_root).resolve()
    parameters = dict(parameters or {})
    log = Path(log or output_root / "out" / "logs" / notebook.name)
    executed = Path(executed or output_root / "out" / "notebooks" / notebook.name)
    log.parent.mkdir(parents=True, exist_ok=True)
    # the kernel inherits this process's environment: where to write, and which run this is
    os.environ["CRFMAP_OUTPUT_ROOT"] = str(output_root)
    os.environ["CRFMAP_RUN"] = json.dumps({"notebook": notebook.name, "parameters": parameters})
    os.environ.setdefault("MPLBACKEND", "Agg")
    if threads is not None:
        if not (isinstance(threads, int) and threads >= 1):
            raise ValueError(f"threads must be a positive integer, got {threads!r}")
        os.environ.update({name: str(threads) for name in THREAD_VARIABLES})
    pm.execute_notebook(str(notebook), str(log), parameters=parameters, kernel_name="python3",
                        cwd=str(notebook.parent), progress_bar=False, execution_timeout=timeout)
    executed.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(log, executed)
    return executed


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crfstudy.repro.run", description=__doc__.splitlines()[0])
    parser.add_argument("notebook", type=Path)
    parser.add_argument("--output-root", type=Path, required=True)
    parser.add_argument("--parameters", default="{}", help="JSON object of papermill parameters")
    parser.add_argument("--executed", type=Path, help="the executed notebook, written on success")
    parser.add_argument("--log", type=Path, help="the executed notebook as it runs (kept on failure)")
    parser.add_argument("--threads", type=int, help="most threads the kernel's numba/OpenMP/BLAS may use")
    args = parser.parse_args(argv)

    try:  # the kernel inherits the environment: its numba reads NUMBA_NUM_THREADS once, at import
        variables.prepare()
    except CrfmapError as exc:
        print(f"run: error: {exc}", file=sys.stderr)
        return 2
    try:
        run_notebook(args.notebook, args.output_root, json.loads(args.parameters), args.executed, args.log,
                     threads=args.threads)
    except Exception as exc:  # papermill re-raises the cell's error: say which notebook, what, and where to look
        what = f"{exc.ename}: {exc.evalue}" if hasattr(exc, "ename") else f"{type(exc).__name__}: {exc}"
        first = what.splitlines()[0] if what.strip() else type(exc).__name__
        log = args.log or args.output_root / "out" / "logs" / args.notebook.name
        print(f"run: {args.notebook.name} failed: {first} -- the executed notebook with the traceback is {log}",
              file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
