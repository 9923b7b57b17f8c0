"""What :func:`crfmap.crf.inference.lbp.infer` returns: beliefs, messages (unpacked on first read) and diagnostics."""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from crfmap.grid import OccupancyGrid


@dataclass
class LBPResult:
    """What :func:`infer` returns (``max_change`` is NaN where the fast kernel did not measure it)."""

    beliefs: OccupancyGrid  # P(occupied) of every hidden cell, with the input grid's metadata
    iterations: int  # each updates every message once (for "thesis": one pass)
    max_change: np.ndarray  # the largest message change of every iteration
    converged: bool  # whether the last change fell below tol
    messages: np.ndarray = field(repr=False)  # (4, H, W); pass back as messages= to warm-start; unpacked when read
    seconds: float = 0.0  # wall time, without numba's compiling or cache loading (timings["compile"])
    schedule: str = "checkerboard"
    kernel: str = "plain"  # "fast" or "plain": which kernels ran
    # seconds spent packing, iterating, unpacking ("pack", "iterate", "unpack"; whole-grid fast kernel), on the coarse
    # levels ("coarse"), and compiling or loading kernels ("compile", within "pack" and "iterate"; absent when none)
    timings: dict = field(default_factory=dict)
    # a preset's beliefs moved by its evidence gate into the nav2 class each cell's evidence allows (None: no gate)
    gated: OccupancyGrid | None = field(default=None, repr=False)

    @property
    def nav2_map(self) -> OccupancyGrid:
        """The map to hand nav2 (a map_server map, published on /map): the gated beliefs, else the beliefs."""
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
