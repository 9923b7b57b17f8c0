"""The ``crfmap`` command: one sub-command per module in :mod:`crfmap.commands`.

Bad input ends the run with one line on stderr naming the input and the problem, and
exit status 2; no traceback, no half-written output.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from crfmap.errors import CrfmapError

# Sub-command name -> module in crfmap.commands providing add_parser(subparsers) and run(args).
COMMANDS = ("infer", "metrics", "simulate", "build", "convert", "bench", "evaluate")


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (plus where to find help), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="crfmap",
        description="Clean and complete occupancy grids with CRFs and loopy belief propagation.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"crfmap.commands.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"crfmap.commands.{name}":
                continue  # a command not built yet
            raise
        cmd = module.add_parser(sub)
        cmd.set_defaults(_run=module.run)
    return parser



def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        status = args._run(args)
    except CrfmapError as exc:
        print(f"crfmap {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except FileNotFoundError as exc:
        print(f"crfmap {args.command}: error: {exc.filename}: no such file", file=sys.stderr)
        return 2
    except (IsADirectoryError, PermissionError) as exc:
        print(f"crfmap {args.command}: error: {exc.filename}: {exc.strerror}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"crfmap {args.command}: interrupted", file=sys.stderr)
        return 130
    return int(status or 0)


if __name__ == "__main__":
    sys.exit(main())
