"""Watching a long LBP run: the iteration loops report each pass to whoever asked, inside a :func:`watch` block.

A run that does not settle iterates until ``max_iter``; it can be watched (``crfmap infer``'s bar on a terminal) and
stopped (Ctrl-C lands between passes). Outside a :func:`watch` block :func:`passed` is one context-variable read.

>>> seen = []
>>> with watch(lambda done, limit, change: seen.append((done, limit))):
...     passed(8, 100, 0.5)
>>> seen
[(8, 100)]
>>> passed(9, 100, 0.4)  # nobody watches: nothing happens
"""
from __future__ import annotations

import contextlib
import contextvars

_WATCHER = contextvars.ContextVar("crfmap_lbp_watcher", default=None)


@contextlib.contextmanager
def watch(callback):
    """Inside the block, ``callback(iterations_done, max_iter, last_measured_change)`` runs after every LBP pass
    (a pass is one iteration of the plain schedules, up to a block of them on the packed engine)."""
    token = _WATCHER.set(callback)
    try:
        yield
    finally:
        _WATCHER.reset(token)


def passed(done: int, limit: int, change: float) -> None:
    """Report a finished pass to the watcher, if any."""
    callback = _WATCHER.get()
    if callback is not None:
        callback(int(done), int(limit), float(change))


def bar(total: int, desc: str = "LBP", disable: bool = False):
    """A tqdm bar over iterations and the ``watch`` callback that moves it: ``(bar, callback)``."""
    from tqdm.auto import tqdm

    progress = tqdm(total=int(total), desc=desc, unit="it", disable=disable, leave=False)

    def callback(done, limit, change):
        progress.update(done - progress.n)
        if change == change:  # a measured change (NaN: not measured in this pass)
            progress.set_postfix_str(f"max change {change:.2e}", refresh=False)

    return progress, callback
