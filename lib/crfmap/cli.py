"""The ``crfmap`` command: one sub-command per module in :mod:`crfmap.commands`. Bad input ends the run with one line on
stderr naming the input and the problem, and exit status 2; no traceback, no half-written output.
"""
from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys
import warnings
from importlib.metadata import entry_points

from crfmap.errors import CrfmapError, one_line
from crfmap import environment
from crfmap.io.atomic import Interrupted, record_written, signals_raise

# Sub-command name -> module providing add_parser(subparsers) and run(args): the library's own commands, then those
# other installed distributions register under the entry-point group "crfmap.commands" (the study's `bench`).
COMMANDS = {name: f"crfmap.commands.{name}" for name in ("infer", "metrics", "simulate", "build", "convert",
                                                         "evaluate", "node")}
ENTRY_POINT_GROUP = "crfmap.commands"


def commands() -> dict:
    """{name: module path} of every sub-command: the library's, then the plug-ins' (a plug-in cannot replace one)."""
    found = dict(COMMANDS)
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        found.setdefault(ep.name, ep.value)
    return found


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (plus where to find help), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="crfmap",
        description="Clean and complete occupancy grids with CRFs and loopy belief propagation.",
    )
    parser.add_argument("--max-cells", default=None, metavar="N",
                        help="largest grid an input may ask for, in cells: a whole number such as 4e8 (default "
                        "100 million; also $CRFMAP_MAX_CELLS; there is no 'no limit')")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in commands().values():
        module = importlib.import_module(module_name)
        cmd = module.add_parser(sub)
        cmd.set_defaults(_run=module.run)
    return parser


def _os_error_line(exc: OSError, written=()) -> str:
    """One line for a failed file operation: the file, then what went wrong (and what was written before it)."""
    name = exc.filename if exc.filename is not None else ""
    what = exc.strerror or str(exc)
    if exc.errno == errno.ENOSPC:
        what = f"no space left on the device ({_written_note(written)})"
    elif exc.errno == errno.EFBIG:
        what = f"file too large for the file-size limit ({_written_note(written)})"
    return f"{name}: {what}" if name else what


def _written_note(written) -> str:
    """What a failed run leaves: ``nothing was written``, or the outputs it completed before the failure.

    >>> _written_note([]), _written_note(["o.npy", "o.npy.yaml"])
    ('nothing was written', 'written before it, complete: o.npy, o.npy.yaml')
    """
    return f"written before it, complete: {', '.join(map(str, written))}" if written else "nothing was written"


STDOUT_NAME = "standard output"


class _Stdout:
    """``sys.stdout`` whose failed writes name it: an OSError from ``print`` names no file (stdout on /dev/full,
    a full disk, a closed pipe), and would read as the failure of an output file."""

    def __init__(self, stream):
        self._stream = stream

    def _named(self, call, *args):
        try:
            return call(*args)
        except OSError as exc:
            if exc.filename is not None:
                raise
            raise OSError(exc.errno, exc.strerror or str(exc), STDOUT_NAME) from None

    def write(self, text):
        return self._named(self._stream.write, text)

    def flush(self):
        return self._named(self._stream.flush)

    def __getattr__(self, attr):
        return getattr(self._stream, attr)


def _input_name(args) -> str:
    return str(getattr(args, "input", None) or getattr(args, "prediction", None) or getattr(args, "scene", ""))


def main(argv=None) -> int:
    try:  # before the sub-commands import numba, which reads NUMBA_NUM_THREADS once and fails on 0
        environment.prepare(numba_cache_too=False)
    except CrfmapError as exc:
        return _fail(f"crfmap: error: {exc}")
    parser = build_parser()
    args = parser.parse_args(argv)  # --help and usage errors end here: they need no kernel cache
    try:
        environment.prepare_cache()
    except CrfmapError as exc:
        return _fail(f"crfmap: error: {exc}")
    previous = os.environ.get("CRFMAP_MAX_CELLS")
    if args.max_cells is not None:
        try:
            cells = environment.whole_number("--max-cells", args.max_cells, "cells")
        except CrfmapError as exc:
            parser.error(str(exc))
        os.environ["CRFMAP_MAX_CELLS"] = str(cells)
    try:
        return _run(args)
    finally:  # main() may be called in-process (tests, notebooks): leave the environment as it was
        if previous is None:
            os.environ.pop("CRFMAP_MAX_CELLS", None)
        else:
            os.environ["CRFMAP_MAX_CELLS"] = previous


def _run(args) -> int:
    prefix = f"crfmap {args.command}"
    stdout = sys.stdout
    # Warnings wait until the run succeeds: a failed run prints its one error line and nothing else.
    with warnings.catch_warnings(record=True) as caught, signals_raise(), record_written() as written:
        warnings.simplefilter("default")
        sys.stdout = _Stdout(stdout)
        try:
            status = args._run(args)
            sys.stdout.flush()  # a report that cannot be written fails here, where it is named, not at exit
        except CrfmapError as exc:
            return _fail(f"{prefix}: error: {exc}")
        except Interrupted as exc:
            return _fail(f"{prefix}: {exc}; {_written_note(written)}", 128 + exc.signum)
        except KeyboardInterrupt:
            return _fail(f"{prefix}: interrupted; {_written_note(written)}", 130)
        except FileNotFoundError as exc:
            return _fail(f"{prefix}: error: {exc.filename}: no such file or folder")
        except OSError as exc:
            if exc.filename == STDOUT_NAME and exc.errno not in (errno.ENOSPC, errno.EFBIG):
                return _fail(f"{prefix}: error: {STDOUT_NAME}: {exc.strerror or exc} ({_written_note(written)})")
            return _fail(f"{prefix}: error: {_os_error_line(exc, written)}")
        except RecursionError:
            return _fail(f"{prefix}: error: {_input_name(args)}: input nested too deeply")
        except MemoryError:
            return _fail(f"{prefix}: error: {_input_name(args)}: out of memory (a smaller input or --max-cells?)")
        finally:
            sys.stdout = stdout
    for w in caught:  # one line each (the message names the input), not Python's "file:line: category" pair
        print(_warning_line(prefix, w), file=sys.stderr)
    return int(status or 0)


def _warning_line(prefix, w) -> str:
    """``crfmap CMD: warning: MESSAGE``, naming a category other than UserWarning (``warning (FutureWarning)``)."""
    kind = "warning" if w.category is UserWarning else f"warning ({w.category.__name__})"
    return one_line(f"{prefix}: {kind}: {w.message}", limit=1000)


def _fail(line, status=2) -> int:
    print(one_line(line, limit=1000), file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
