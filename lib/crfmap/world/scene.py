"""The :class:`Scene` type, apart from the modules that build scenes so that they need not import each other."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from crfmap.grid import OccupancyGrid
from crfmap.world.reachability import pose_cell

MODES = ("explore", "look", "waypoints")  # how a scene is scanned (crfmap.sim.simulator.simulate)


@dataclass
class Scene:
    """A ground-truth grid and where the robot starts in it; ``default_mode``: how the thesis scanned such a scene."""

    name: str
    truth: OccupancyGrid  # P(occupied) 0.0 / 1.0
    start: tuple  # (x [m], y [m], yaw [rad]) of base_link in map, in a free reachable cell
    description: str = ""
    default_mode: str = "explore"
    waypoints: np.ndarray | None = None  # (k, 2) x [m], y [m] in map, visited in order
    robot_radius: float = 0.0  # [m] footprint used for reachability (0 = the thesis's point robot)

    @property
    def occupied(self) -> np.ndarray:
        """Boolean [y, x] mask of occupied cells (P > 0.5)."""
        return self.truth.probability > 0.5

    def start_cell(self) -> tuple:
        """(ix, iy) of the cell holding the start pose."""
        return pose_cell(self.truth, self.start)



def scene_grid(cells, resolution, **meta) -> OccupancyGrid:
    return OccupancyGrid(cells.astype(np.float64), resolution=resolution, origin=(0.0, 0.0, 0.0), meta=dict(meta))
