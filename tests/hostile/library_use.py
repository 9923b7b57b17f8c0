"""A library user's script, for the catalogue's child processes: ``crfmap.prepare()`` (the explicit check a script
makes first: importing crfmap changes nothing, so it checks nothing either), load a grid, ``infer`` it.

A library user sees the exception: a crfmap error is printed as its one line (exit 2), as the in-process
``call`` cases do; anything else escapes as a traceback (exit 1), which the catalogue counts as not clean.
"""
from __future__ import annotations

import sys


def main(argv):
    from crfmap.errors import CrfmapError

    try:
        import crfmap

        crfmap.prepare()  # names a bad NUMBA_NUM_THREADS before numba reads it (0: a traceback; abc: ignored)
        from crfmap.crf import infer
        from crfmap.io import load_grid

        infer(load_grid(argv[0]))
    except CrfmapError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
