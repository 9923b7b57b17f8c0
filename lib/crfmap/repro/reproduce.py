"""Reproduce the paper: run the Snakemake workflow (``workflow/Snakefile``) over every notebook.

``python -m crfmap.repro.reproduce`` (what ``make reproduce`` runs) first names any shared-data file
the notebooks need and this machine lacks (and runs nothing), then runs the workflow with
``--cores 2``: each notebook executes with papermill only when it, a library module it imports, a data
file it reads or its parameters changed since its figures and tables were made; independent notebooks
run in parallel; the paper is rendered on top (:mod:`crfmap.repro.paper`). A second run with nothing
changed does nothing and says so.

- ``--quick``: the small settings CI uses, into ``out/quick/`` (never the checkout's figures/ or the paper);
- ``--only 04 07``: the notebooks whose names start with these prefixes (not the paper);
- ``--sweep 04_noise``: the sweep ``workflow/sweeps/04_noise.yaml`` (:mod:`crfmap.repro.sweep`);
- ``--dry-run``: say what would run, and why; ``--profile workflow/profiles/slurm``: on a cluster;
- anything after ``--`` goes to snakemake as is.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

from crfmap import paths
from crfmap.errors import DataMissingError
from crfmap.repro.dependencies import data_needed, notebooks

SNAKEFILE = paths.PROJECT_ROOT / "workflow" / "Snakefile"


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


def snakemake_command(targets=(), cores=2, directory=None, quick=False, dry_run=False, profile=None,
                      extra=()) -> list[str]:
    """The ``snakemake`` command line running the workflow (in this interpreter's environment)."""
    # targets first: several snakemake options (--config, --quiet) take lists
    command = [sys.executable, "-m", "snakemake", *targets, "--snakefile", str(SNAKEFILE),
               "--directory", str(directory or paths.OUTPUT_ROOT), "--cores", str(cores),
               "--show-failed-logs", "--printshellcmds"]
    if quick:
        command += ["--config", "quick=true"]
    if dry_run:
        command += ["--dry-run"]
    if profile:
        command += ["--workflow-profile", str(profile)]
    return command + list(extra)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crfmap.repro.reproduce", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small settings (quick=True), into out/quick/")
    parser.add_argument("--only", nargs="*", help="notebook name prefixes to run, e.g. 04 07")
    parser.add_argument("--no-paper", action="store_true", help="do not build the paper (same as --only with all)")
    parser.add_argument("--sweep", nargs="*", default=[], help="sweeps of workflow/sweeps/ to run, by name")
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--dry-run", "-n", action="store_true", help="only say what would run, and why")
    parser.add_argument("--profile", type=Path, help="a workflow profile folder, e.g. workflow/profiles/slurm")
    parser.add_argument("--started-at", type=float, help="Unix time `make reproduce` started (before the venv "
                        "and the warm-up): recorded with the workflow's own time after a full run")
    parser.add_argument("extra", nargs=argparse.REMAINDER, help="-- then arguments for snakemake")
    args = parser.parse_args(argv)

    todo = [] if args.sweep and not args.only else notebooks(args.only)
    if args.sweep:
        from crfmap.repro.sweep import load

        todo += [load(paths.PROJECT_ROOT / "workflow" / "sweeps" / f"{name}.yaml").notebook for name in args.sweep]
    missing = missing_data(todo)
    if missing:  # say it before anything runs, not after half the figures were regenerated
        for line in missing:
            print(f"reproduce: {line}", file=sys.stderr)
        print("reproduce: see data/README.md; nothing was run", file=sys.stderr)
        return 2
    targets = [f"out/runs/{name}/collected.csv" for name in args.sweep]
    if args.only or (args.no_paper and not args.sweep):
        targets += [f"notebook_{nb.stem}" for nb in notebooks(args.only)]
    elif not args.sweep:
        targets += ["all"]  # every notebook, then the paper (with --quick: no paper)
    directory = paths.OUT / "quick" if args.quick else paths.OUTPUT_ROOT
    extra = [a for a in args.extra if a != "--"]
    command = snakemake_command(targets, args.cores, directory, args.quick, args.dry_run, args.profile, extra)
    start = time.perf_counter()
    code = subprocess.call(command, env={**os.environ, "MPLBACKEND": os.environ.get("MPLBACKEND", "Agg")})
    seconds = time.perf_counter() - start
    print(f"reproduce: {'dry run' if args.dry_run else 'workflow'} {'finished' if code == 0 else 'failed'} "
          f"in {seconds:.1f} s (outputs under {directory})", file=sys.stderr)
    if code == 0 and targets == ["all"] and not (args.dry_run or args.quick or extra or args.profile):
        write_wall_record(seconds, args.started_at, args.cores)
    return code


def write_wall_record(workflow_seconds, started_at=None, cores=2, path=None) -> Path:
    """Record a full run's wall-clock time (``out/logs/reproduce_wall.json``), read by ``crfmap bench``.

    ``started_at`` (Unix time) is when ``make reproduce`` began, before the venv and the warm-up;
    without it only the workflow's own time is known. A run that found nothing to do records that
    too (its time is not a reproduction's): ``workflow_seconds`` is what this run took.
    """
    import json

    from crfmap.io.atomic import atomic_path

    path = Path(path or paths.OUT / "logs" / "reproduce_wall.json")
    now = time.time()
    record = {"workflow_seconds": round(float(workflow_seconds), 1), "cores": int(cores),
              "finished": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(now)),
              "make_seconds": None if started_at is None else round(now - float(started_at), 1)}
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(record, indent=1) + "\n")
    return path


if __name__ == "__main__":
    sys.exit(main())
