"""What :func:`crfmap.crf.inference.lbp.infer` returns: beliefs, messages (unpacked on first read) and diagnostics."""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from crfmap.grid import OccupancyGrid


@dataclass
class LBPResult:
    """What :func:`infer` returns.

    - ``beliefs``: P(occupied) of every hidden cell, with the input grid's metadata.
    - ``iterations``: iterations done (one iteration updates every message once; for ``"thesis"`` one pass).
    - ``max_change``: the largest message change at every iteration (length ``iterations``); NaN where the fast kernel
      did not measure it (it measures the last iteration of each block).
    - ``converged``: whether the last change fell below ``tol``.
    - ``messages``: the final messages, shape (4, H, W); pass them back as ``messages=`` to warm-start. The whole-grid
      fast kernel unpacks them on first read (most callers never do).
    - ``seconds``: wall time of the inference, without the time numba spent compiling kernels or loading them from
      its disk cache (a first call's wait: ``timings["compile"]``).
    - ``kernel``: ``"fast"`` or ``"plain"``: which kernels ran.
    - ``timings``: seconds spent packing ("pack"), iterating ("iterate") and unpacking beliefs and messages ("unpack")
      on the whole-grid fast kernel, and on the coarse levels of ``init="coarse"`` ("coarse"); "compile": seconds
      numba spent compiling or loading kernels during the call (not in ``seconds``; absent when none); "pack" and
      "iterate" include it.
    - ``gated``: a preset's beliefs moved by its evidence gate into the nav2 class each cell's own evidence allows
      (:meth:`crfmap.crf.model.gating.EvidenceGate.beliefs_and_map`); None when no gate ran. Read it as :attr:`nav2_map`.
    """

    beliefs: OccupancyGrid
    iterations: int
    max_change: np.ndarray
    converged: bool
    messages: np.ndarray = field(repr=False)
    seconds: float = 0.0
    schedule: str = "checkerboard"
    kernel: str = "plain"
    timings: dict = field(default_factory=dict)
    gated: OccupancyGrid | None = field(default=None, repr=False)

    @property
    def nav2_map(self) -> OccupancyGrid:
        """The map to hand nav2 (write as a map_server map, publish on /map): the gated beliefs, else the beliefs.

        :attr:`beliefs` are the probabilities (score them, fuse them); this is the decision nav2 reads from them.
        """
        return self.beliefs if self.gated is None else self.gated

    @property
    def last_change(self) -> float:
        """The largest message change of the last iteration (NaN if none was done)."""
        return float(self.max_change[-1]) if len(self.max_change) else float("nan")

    def summary(self) -> str:
        last = f"{self.max_change[-1]:.2e}" if len(self.max_change) else "n/a"
        state = "converged" if self.converged else "not converged"
        return f"{self.schedule}: {self.iterations} iterations, {state} (last max message change {last})"


def _messages(self):
    value = self.__dict__["_messages"]
    if callable(value):  # packed messages: unpack on first read (saves a pass and 16 bytes per cell)
        value = self.__dict__["_messages"] = value()
    return value


LBPResult.messages = property(_messages, lambda self, value: self.__dict__.__setitem__("_messages", value))


def result_grid(grid: OccupancyGrid, probability) -> OccupancyGrid:
    """``grid.with_probability(probability)`` without checking ``probability`` again (LBP's beliefs are
    probabilities by construction; the check reads every cell three times)."""
    out = copy.copy(grid)
    out.probability, out.meta = probability, dict(grid.meta)
    return out
