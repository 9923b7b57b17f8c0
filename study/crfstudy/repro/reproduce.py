"""Reproduce the paper: run the Snakemake workflow (``workflow/Snakefile``) over every notebook.

``python -m crfstudy.repro.reproduce`` (what ``make reproduce`` runs) first names any shared-data file
the notebooks need and this machine lacks (and runs nothing), then runs the workflow with
``--cores 2``: each notebook executes with papermill only when it, a library module it imports, a data
file it reads or its parameters changed since its figures and tables were made; independent notebooks
run in parallel; the paper is rendered on top (:mod:`crfstudy.repro.paper`). A second run with nothing
changed does nothing and says so.

- ``--quick``: the small settings CI uses, into ``out/quick/`` (never the checkout's figures/ or the paper);
- ``--only 04 07``: the notebooks whose names start with these prefixes (not the paper);
- ``--sweep 04_noise``: the sweep ``workflow/sweeps/04_noise.yaml`` (:mod:`crfstudy.repro.sweep`);
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
import json

from crfstudy import paths
from crfmap.data import data_file
from crfmap.errors import CrfmapError, DataMissingError, one_line
from crfstudy.repro import variables
from crfstudy.repro.dependencies import data_needed, notebooks
from crfmap.environment import whole_number
from crfmap import environment
from crfmap.io.atomic import atomic_path


def snakefile() -> Path:
    """The workflow's Snakefile in the checkout (``$CRFMAP_ROOT``)."""
    return paths.PROJECT_ROOT / "workflow" / "Snakefile"


def missing_data(todo) -> list[str]:
    """One line per shared-data file the notebooks need and this machine lacks: what to download, where."""
    lines = []
    for relative in sorted({f for nb in todo for f in data_needed(nb)}):
        try:
            data_file(relative)
        except DataMissingError as error:
            users = ", ".join(nb.name for nb in todo if relative in data_needed(nb))
            lines.append(f"{error} -- needed by {users}")
    return lines


def snakemake_command(targets=(), cores=2, directory=None, quick=False, dry_run=False, profile=None,
                      extra=(), config=None) -> list[str]:
    """The ``snakemake`` command line running the workflow (in this interpreter's environment).

    ``config``: more ``--config`` entries (``{"max_points": 500}``; lists are written as YAML flow lists).
    """
    # targets first: several snakemake options (--config, --quiet) take lists
    command = [sys.executable, "-m", "snakemake", *targets, "--snakefile", str(snakefile()),
               "--directory", str(directory or paths.OUTPUT_ROOT), "--cores", str(cores),
               "--show-failed-logs", "--printshellcmds"]
    entries = {"quick": "true"} if quick else {}
    for key, value in (config or {}).items():
        entries[key] = "[" + ",".join(value) + "]" if isinstance(value, (list, tuple)) else str(value)
    if entries:
        command += ["--config", *(f"{k}={v}" for k, v in entries.items())]
    if dry_run:
        command += ["--dry-run"]
    if profile:
        command += ["--workflow-profile", str(profile)]
    return command + list(extra)


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (plus where to find help), exit status 2."""

    def error(self, message):
        self.exit(2, one_line(f"{self.prog}: error: {message} (see {self.prog} --help)", 1000) + "\n")


def _positive(text) -> int:
    try:
        return whole_number("--max-points", text, "points")
    except CrfmapError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def sweep_file(given) -> Path:
    """The sweep file ``--sweep`` names: ``NAME`` is ``workflow/sweeps/NAME.yaml``; a path ending in .yaml is itself."""
    if given.endswith(".yaml") or os.sep in given:
        return Path(given).resolve()
    return paths.PROJECT_ROOT / "workflow" / "sweeps" / f"{given}.yaml"


def main(argv=None) -> int:
    parser = _Parser(prog="python -m crfstudy.repro.reproduce", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small settings (quick=True), into out/quick/")
    parser.add_argument("--only", nargs="*", help="notebook name prefixes to run, e.g. 04 07")
    parser.add_argument("--no-paper", action="store_true", help="do not build the paper (same as --only with all)")
    parser.add_argument("--sweep", nargs="+", default=[], help="sweeps to run: names of workflow/sweeps/ or "
                        "files NAME.yaml (of one folder)")
    parser.add_argument("--max-points", type=_positive, help="run a sweep of more points than "
                        "crfstudy.repro.sweep.MAX_POINTS (200)")
    parser.add_argument("--cores", type=_cores, default=2)
    parser.add_argument("--dry-run", "-n", action="store_true", help="only say what would run, and why")
    parser.add_argument("--profile", type=Path, help="a workflow profile folder, e.g. workflow/profiles/slurm")
    parser.add_argument("--started-at", type=float, help="Unix time `make reproduce` started (before the venv "
                        "and the warm-up): recorded with the workflow's own time after a full run")
    parser.add_argument("--new-venv", action="store_true", help="make created the virtual environment in this "
                        "run (a fresh clone): recorded with the run")
    parser.add_argument("extra", nargs=argparse.REMAINDER, help="-- then arguments for snakemake")
    args = parser.parse_args(argv)
    try:
        return _reproduce(args)
    except CrfmapError as exc:
        print(one_line(f"reproduce: error: {exc}", 1000), file=sys.stderr)
        return 2


def _cores(text) -> int:
    try:
        return whole_number("--cores", text, "cores")
    except CrfmapError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _reproduce(args) -> int:
    variables.prepare()  # before snakemake's jobs import numba, which reads NUMBA_NUM_THREADS once
    todo = [] if args.sweep and not args.only else notebooks(args.only)
    loaded = []
    if args.sweep:
        from crfstudy.repro.sweep import load

        files = [sweep_file(name) for name in args.sweep]
        if len({f.parent for f in files}) > 1:
            raise CrfmapError(f"--sweep: the sweep files must be in one folder, got {', '.join(map(str, files))}")
        loaded = [load(f, args.max_points) for f in files]
        names = {}
        for s in loaded:  # out/runs/<name>/: one folder on a case-insensitive file system
            other = names.setdefault(s.name.casefold(), s)
            if other is not s:
                raise CrfmapError(f"--sweep: {other.source} and {s.source} would both write to out/runs/{s.name}/")
        todo += [s.notebook for s in loaded]
    missing = missing_data(todo)
    if missing:  # say it before anything runs, not after half the figures were regenerated
        for line in missing:
            print(f"reproduce: {line}", file=sys.stderr)
        print("reproduce: see data/README.md; nothing was run", file=sys.stderr)
        return 2
    targets = [f"out/runs/{s.name}/collected.csv" for s in loaded]
    if args.only or (args.no_paper and not args.sweep):
        targets += [f"notebook_{nb.stem}" for nb in notebooks(args.only)]
    elif not args.sweep:
        targets += ["all"]  # every notebook, then the paper (with --quick: no paper)
    directory = paths.OUT / "quick" if args.quick else paths.OUTPUT_ROOT
    environment.writable_folder(directory, "CRFMAP_OUTPUT_ROOT")
    config = {"sweep_names": [s.name for s in loaded]}
    if loaded and loaded[0].source.parent.resolve() != (paths.PROJECT_ROOT / "workflow" / "sweeps").resolve():
        config["sweeps"] = loaded[0].source.parent
    if args.max_points is not None:
        config["max_points"] = args.max_points
    for sweep in loaded:
        print(f"reproduce: {estimate(sweep, args.cores)}", file=sys.stderr)
    extra = [a for a in args.extra if a != "--"]
    command = snakemake_command(targets, args.cores, directory, args.quick, args.dry_run, args.profile, extra,
                                config)
    start = time.perf_counter()
    env = {**os.environ, "MPLBACKEND": os.environ.get("MPLBACKEND", "Agg")}
    if args.started_at is not None:  # the paper states how long this run took up to its build
        env["CRFMAP_REPRODUCE_STARTED"] = repr(float(args.started_at))
    code = subprocess.call(command, env=env)
    seconds = time.perf_counter() - start
    print(f"reproduce: {'dry run' if args.dry_run else 'workflow'} {'finished' if code == 0 else 'failed'} "
          f"in {seconds:.1f} s (outputs under {directory})", file=sys.stderr)
    if code == 0 and targets == ["all"] and not (args.dry_run or args.quick or extra or args.profile):
        write_wall_record(seconds, args.started_at, args.cores, new_venv=args.new_venv)
    return code


def estimate(sweep, cores) -> str:
    """What a sweep will run and about how long it takes (each point as long as the notebook's last full run)."""
    # here, not at the top: timings imports numba, which must come after variables.prepare() (NUMBA_NUM_THREADS)
    from crfstudy.repro.timings import BENCHMARKS, describe, expected_seconds

    points = len(sweep.points())
    each = expected_seconds([sweep.notebook.stem], paths.OUTPUT_ROOT)[sweep.notebook.stem]
    side_by_side = 1 if sweep.notebook.stem in BENCHMARKS else max(1, cores)
    total = each * -(-points // side_by_side)
    settings = "quick settings: likely less" if sweep.fixed.get("quick") else "full settings"
    return (f"sweep {sweep.name}: {points} point{'s' * (points != 1)} of {sweep.notebook.name}, about "
            f"{describe(total)} on {cores} core{'s' * (cores != 1)} ({describe(each)} per point at {settings})")


def write_wall_record(workflow_seconds, started_at=None, cores=2, path=None, new_venv=False) -> Path:
    """Record a full run's wall-clock time in ``out/logs/reproduce_wall.json``, read by ``crfmap bench``.

    ``started_at`` (Unix time) is when ``make reproduce`` began, before the venv and the warm-up;
    without it only the workflow's own time is known. A run that found nothing to do records that
    too (its time is not a reproduction's): ``workflow_seconds`` is what this run took. The file's
    top-level fields are the last run's; ``runs`` lists every run recorded there, oldest first, so a
    fresh clone's first run (``new_venv``) stays on record after quick reruns.
    """
    from crfstudy.repro.buildinfo import wall_record  # imports numba: after variables.prepare(), as timings

    path = Path(path or paths.OUT / "logs" / "reproduce_wall.json")
    now = time.time()
    record = {"workflow_seconds": round(float(workflow_seconds), 1), "cores": int(cores),
              "finished": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(now)),
              "make_seconds": None if started_at is None else round(now - float(started_at), 1),
              "new_venv": bool(new_venv)}
    earlier = wall_record(path)  # {} when there is none or it cannot be read: a new list (the file is replaced whole)
    runs = (earlier.get("runs") or [{k: v for k, v in earlier.items() if k != "runs"}]) if earlier else []
    runs = [r for r in runs if isinstance(r, dict)] + [record]
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps({**record, "runs": runs}, indent=1) + "\n")
    return path


if __name__ == "__main__":
    sys.exit(main())
