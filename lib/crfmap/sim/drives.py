"""How :func:`crfmap.sim.simulator.simulate` drives the robot: one small settings object per mode.

Each drive holds only its own settings, so none can go to a mode that would ignore it; shared ones (start pose,
``dt``, speed limits) are keywords of ``simulate``. A mode's name (``"explore"``, ...) means its drive's defaults.

>>> drive_for("look")
Look(turns=1)
>>> Explore(stride=0)
Traceback (most recent call last):
...
crfmap.errors.InputError: stride: must be >= 1, got 0
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from crfmap.checks import check_int, check_number, check_positive, check_settings
from crfmap.sim.motion import explore_reachable, follow_waypoints, look_around


def _radius(value):
    return None if value is None else check_number("robot_radius", value, low=0.0)


@dataclass(frozen=True)
class Explore:
    """Visit every reachable cell and look around (:func:`~crfmap.sim.motion.explore_reachable`)."""

    stride: int = 1  # look around only at cells farther than stride - 1 cells from the last look-around
    robot_radius: float | None = None  # [m], None: the scene's
    mode: ClassVar[str] = "explore"

    def __post_init__(self):
        object.__setattr__(self, "stride", check_int("stride", self.stride, low=1))
        object.__setattr__(self, "robot_radius", _radius(self.robot_radius))

    def motion(self, scene, laser, *, start, dt, linear_speed, angular_speed):
        return explore_reachable(scene, laser, start=start, robot_radius=self.robot_radius, stride=self.stride,
                                 dt=dt, linear_speed=linear_speed, angular_speed=angular_speed)


@dataclass(frozen=True)
class Look:
    """Stand at the start and turn in place, ``turns`` full look-arounds (:func:`~crfmap.sim.motion.look_around`)."""

    turns: int = 1
    mode: ClassVar[str] = "look"

    def __post_init__(self):
        object.__setattr__(self, "turns", check_int("turns", self.turns, low=1))

    def motion(self, scene, laser, *, start, dt, linear_speed, angular_speed):
        # linear_speed: a robot turning in place never translates
        return look_around(scene, laser, start=start, dt=dt, angular_speed=angular_speed, turns=self.turns)


@dataclass(frozen=True)
class Waypoints:
    """Drive through waypoints, scanning every ``scan_period`` s (:func:`~crfmap.sim.motion.follow_waypoints`)."""

    waypoints: object = None  # (k, 2) x, y [m], None: the scene's; checked when the robot drives
    robot_radius: float | None = None  # [m], None: the scene's
    scan_period: float = 0.2  # [s]
    mode: ClassVar[str] = "waypoints"

    def __post_init__(self):
        object.__setattr__(self, "robot_radius", _radius(self.robot_radius))
        object.__setattr__(self, "scan_period", check_positive("scan_period", self.scan_period))

    def motion(self, scene, laser, *, start, dt, linear_speed, angular_speed):
        return follow_waypoints(scene, laser, self.waypoints, start=start, robot_radius=self.robot_radius, dt=dt,
                                linear_speed=linear_speed, angular_speed=angular_speed, scan_period=self.scan_period)


DRIVES = {d.mode: d for d in (Explore, Look, Waypoints)}
# Settings that belong to a drive, for the error that says where they go.
DRIVE_SETTINGS = {"stride": "Explore", "robot_radius": "Explore or Waypoints", "turns": "Look",
                  "waypoints": "Waypoints", "scan_period": "Waypoints"}


def drive_for(drive):
    """The drive object for ``drive``: a drive itself, or a mode name meaning that drive with its defaults."""
    return check_settings("drive", drive, DRIVES,
                          f"expected one of {', '.join(map(repr, DRIVES))} or an Explore, Look or Waypoints")
