"""Run one catalogue case (in this process or a child) and say what, if anything, was not clean.

``python tests/hostile/harness.py [--json FILE]`` runs every case, each command line in a
child process (a time limit, an address-space limit), and prints the table per class:
tried / clean / other. The pytest suite (test_catalogue.py) runs the same checks, most
cases in-process.
"""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import resource
import signal
import stat
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

# A case is bounded by the CPU time it burns, which a busy machine does not inflate, not by the wall clock.
CPU_LIMIT = 120  # [s of CPU] per case: a refusal takes a few seconds at most
# Only a guard against a case that blocks without burning CPU (a FIFO with no writer): 10x the slowest
# case's quiet-machine time, so load never trips it. Slow cases are reported, not failed.
HANG_LIMIT = 1200.0  # [s, wall clock]
SLOW_SECONDS = 30.0  # [s, wall clock] cases slower than this are listed in the summary
TIMINGS = {}  # case key -> wall seconds of its last run, for that summary
MEMORY_LIMIT = 3 << 30  # [bytes] address space of a child (numba needs some)
FSIZE_LIMIT = 8 << 20  # [bytes] RLIMIT_FSIZE for the "fsize" fault (numba cache files stay below it)


def snapshot(folder):
    """{relative path: (kind, content hash)} of everything under ``folder`` (links and FIFOs not followed)."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            p = Path(root) / name
            st = p.lstat()
            if stat.S_ISREG(st.st_mode):
                out[str(p.relative_to(folder))] = ("file", hashlib.sha1(p.read_bytes()).hexdigest())
            else:
                out[str(p.relative_to(folder))] = (stat.S_IFMT(st.st_mode), None)
    return out


def _cpu_exceeded(signum, frame):
    raise TimeoutError(f"used more than {CPU_LIMIT} s of CPU time")


def _hung(signum, frame):
    raise TimeoutError(f"no answer within {HANG_LIMIT:g} s (blocked)")


ENTRIES = {"crfmap": "crfmap.cli", "reproduce": "crfstudy.repro.reproduce", "run": "crfstudy.repro.run",
           "warmup": "crfstudy.repro.warmup", "library": "library_use"}  # a case's command line: its module


@contextlib.contextmanager
def environment(changes):
    """Inside the block, ``os.environ`` holds ``changes`` (None: the variable is removed)."""
    saved = {name: os.environ.get(name) for name in changes}
    try:
        _apply(os.environ, changes)
        yield
    finally:
        _apply(os.environ, saved)


def _apply(env, changes):
    for name, value in changes.items():
        if value is None:
            env.pop(name, None)
        else:
            env[name] = value


class FullStdout(io.StringIO):
    """Standard output on a full disk (``> /dev/full``): every write fails with ENOSPC, naming no file."""

    def write(self, text):
        import errno

        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def run_inprocess(case, spec, d):
    """(exit status, stderr text) of running ``spec`` here, with the case's fault and environment."""
    import importlib

    from faults import fault
    from crfmap.errors import CrfmapError

    main = importlib.import_module(ENTRIES[case.entry]).main

    err = io.StringIO()
    old_prof = signal.signal(signal.SIGPROF, _cpu_exceeded)
    old_alarm = signal.signal(signal.SIGALRM, _hung)
    signal.setitimer(signal.ITIMER_PROF, CPU_LIMIT)  # this process's CPU time, all threads
    signal.alarm(int(HANG_LIMIT))
    cwd = os.getcwd()
    os.chdir(d)
    try:
        out = FullStdout() if spec.get("stdout") == "full" else io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out), fault(case.fault, d), \
                environment(spec.get("env", {})):
            if "call" in spec:
                try:
                    spec["call"]()
                    rc = 0
                except CrfmapError as exc:
                    print(f"error: {exc}", file=sys.stderr)
                    rc = 2
            else:
                try:
                    rc = main(spec["argv"])
                except SystemExit as exc:
                    rc = exc.code if isinstance(exc.code, int) else 1
    except BaseException as exc:  # what the command line would show: a traceback
        import traceback

        err.write("Traceback (most recent call last):\n" + "".join(traceback.format_exception_only(exc)))
        rc = 1
    finally:
        signal.alarm(0)
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGALRM, old_alarm)
        signal.signal(signal.SIGPROF, old_prof)
        os.chdir(cwd)
    return rc, err.getvalue()


def _child_limits(fsize):
    def apply():
        # A background job inherits SIGINT ignored (and Python then keeps it ignored): a user's Ctrl-C reaches it.
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
        resource.setrlimit(resource.RLIMIT_CPU, (CPU_LIMIT, CPU_LIMIT + 10))  # SIGXCPU, then SIGKILL
        if fsize:
            resource.setrlimit(resource.RLIMIT_FSIZE, (FSIZE_LIMIT, FSIZE_LIMIT))
    return apply


def _cpu_seconds(pid) -> float:
    """User + system CPU seconds process ``pid`` has used (0 once it is gone)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def run_subprocess(case, spec, d):
    """(exit status, stderr text) of a child ``crfmap`` process; signals are sent once a temporary appears (or
    ``signal_after`` seconds of the child's CPU time into the run, a case's ``extra``: its imports done however
    busy the machine)."""
    entry = ENTRIES[case.entry]
    if case.fault not in (None, "fsize"):
        code = (f"import sys; sys.path.insert(0, {str(HERE)!r}); from faults import fault; "
                f"from {entry} import main\nwith fault({case.fault!r}, {str(d)!r}): rc = main(sys.argv[1:])\n"
                "sys.exit(rc)")
    else:
        code = f"import sys; sys.path.insert(0, {str(HERE)!r}); from {entry} import main; sys.exit(main(sys.argv[1:]))"
    env = dict(os.environ, PYTHONWARNINGS="default")
    _apply(env, spec.get("env", {}))
    stdout = open("/dev/full", "w") if spec.get("stdout") == "full" else subprocess.DEVNULL  # noqa: SIM115
    proc = subprocess.Popen([sys.executable, "-c", code, *spec["argv"]], cwd=d, env=env, stdout=stdout,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_child_limits(case.fault == "fsize"))
    if stdout is not subprocess.DEVNULL:
        stdout.close()
    start = time.monotonic()
    sent = case.signal is None
    after = case.extra.get("signal_after")  # CPU seconds into the work (a long LBP run: no temporary exists yet)
    while not sent and proc.poll() is None and time.monotonic() - start < HANG_LIMIT:
        if (_cpu_seconds(proc.pid) >= after) if after is not None else any(n.startswith(".") for n in os.listdir(d)):
            proc.send_signal(case.signal)
            sent = True
        else:
            time.sleep(0.002)
    try:
        _, err = proc.communicate(timeout=max(1.0, HANG_LIMIT - (time.monotonic() - start)))
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        return None, err + f"\n(killed after {HANG_LIMIT:g} s: blocked)"
    if proc.returncode in (-signal.SIGXCPU, -signal.SIGKILL) and case.signal is None:
        err += f"\n(killed: more than {CPU_LIMIT} s of CPU time)"
    if not sent:
        err += "\n(finished before any temporary file appeared: signal not sent)"
    return proc.returncode, err


def problems(case, spec, rc, err, before, after):
    """What is wrong with a run (empty: a clean refusal)."""
    found = []
    if rc != case.expect_rc:
        found.append(f"exit status {rc}, expected {case.expect_rc}")
    lines = [line for line in err.splitlines() if line.strip()]
    if "Traceback" in err:
        found.append("traceback")
    if len(lines) != 1:
        found.append(f"{len(lines)} stderr lines")
    elif not any(n in lines[0] for n in spec["names"]):
        found.append(f"error line does not name {spec['names']}")
    if case.fault == "rival":  # the rival's folder is there, as the rival wrote it: nothing of it replaced
        from faults import RIVAL_TEXT

        before = dict(before, **{spec["rival"]: (stat.S_IFDIR, None),
                                 spec["rival"] + "/metadata.yaml": ("file", hashlib.sha1(RIVAL_TEXT).hexdigest())})
    written = spec.get("written", ())  # outputs completed before a failure (which the error line must name)
    for name in written:
        if name not in after:
            found.append(f"{name} not written")
        elif lines and name not in lines[-1]:
            found.append(f"error line does not say {name} was written")
    after = {k: v for k, v in after.items() if k not in written}
    if after != before:
        added = sorted(set(after) - set(before))
        changed = sorted(k for k in before if after.get(k) != before[k])
        found.append(f"folder changed (added {added[:3]}, changed/removed {changed[:3]})")
    return found


def run_case(case, inprocess=True):
    """Set the case up in a fresh folder, run it, return (problems, stderr, seconds)."""
    with tempfile.TemporaryDirectory(prefix="hostile-") as d:
        d = Path(d).resolve()
        spec = case.setup(d)
        before = snapshot(d)
        start = time.monotonic()
        if "call" in spec or (inprocess and not case.subprocess):
            rc, err = run_inprocess(case, spec, d)
        else:
            rc, err = run_subprocess(case, spec, d)
        seconds = time.monotonic() - start
        TIMINGS[f"{case.cls}/{case.name}"] = seconds
        after = snapshot(d)
        found = problems(case, spec, rc, err, before, after)
        if "whole" in spec and not found:  # the outputs it says were written are complete
            found += [problem for problem in [spec["whole"](d)] if problem]
        return found, err, seconds


def all_cases():
    import cases
    import cases_batch  # noqa: F401  (sweep files, environment variables)
    import cases_more  # noqa: F401  (registers the rest)
    import cases_issue40  # noqa: F401  (data lost or misread, concurrent writers, unbounded, API misuse)

    unique = {}
    for c in cases.CASES:
        unique.setdefault((c.cls, c.name), c)
    return list(unique.values())


def table(results):
    """Markdown table per class: tried / clean / other / slow (wall clock over SLOW_SECONDS: reported, not failed)."""
    classes = {}
    for case, found, seconds in results:
        row = classes.setdefault(case.cls, [0, 0, 0])
        row[0] += 1
        row[1] += not found
        row[2] += seconds > SLOW_SECONDS
    lines = ["| class | tried | clean | other | slow |", "|---|---|---|---|---|"]
    for cls, (tried, clean, slow) in classes.items():
        lines.append(f"| {cls} | {tried} | {clean} | {tried - clean} | {slow} |")
    tried, clean, slow = (sum(r[i] for r in classes.values()) for i in range(3))
    lines.append(f"| all | {tried} | {clean} | {tried - clean} | {slow} |")
    return "\n".join(lines)


def class_counts(keys) -> str:
    """One line: how many cases of each class ran (``keys``: ``class/name``), e.g. ``maps 14, yaml 12; 26 in all``.

    >>> class_counts(["maps/a", "maps/b", "misread/c"])
    'maps 2, misread 1; 3 in all'
    """
    counts = {}
    for key in keys:
        cls = key.split("/", 1)[0]
        counts[cls] = counts.get(cls, 0) + 1
    return ", ".join(f"{cls} {n}" for cls, n in counts.items()) + f"; {sum(counts.values())} in all"


def slow_cases(timings):
    """Lines naming the cases of ``timings`` ({case key: wall seconds}) slower than SLOW_SECONDS, slowest first."""
    slow = sorted(((s, k) for k, s in timings.items() if s > SLOW_SECONDS), reverse=True)
    return [f"{k}: {s:.0f} s (wall clock; CPU-bounded at {CPU_LIMIT} s)" for s, k in slow]


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser()
    parser.add_argument("--json", help="write every case's result here")
    parser.add_argument("--only", help="run cases whose class/name contains this")
    parser.add_argument("--start", help="skip the cases before this class/name")
    args = parser.parse_args()
    results, records = [], []
    started = args.start is None
    for case in all_cases():
        key = f"{case.cls}/{case.name}"
        started = started or key == args.start
        if (args.only and args.only not in key) or not started:
            continue
        found, err, seconds = run_case(case, inprocess=False)
        results.append((case, found, seconds))
        records.append(dict(case=key, problems=found, stderr=err[-600:], seconds=round(seconds, 2)))
        print(f"{'clean' if not found else 'OTHER'} {key} ({seconds:.1f} s) {'; '.join(found)}", flush=True)
    print(table(results))
    if args.json:
        Path(args.json).write_text(json.dumps(records, indent=1))
