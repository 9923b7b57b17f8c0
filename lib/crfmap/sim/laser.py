"""The simulated laser scanner: beam geometry as a sensor_msgs/LaserScan describes it."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from crfmap.errors import InputError
from crfmap.frames import TWO_PI
from crfmap.checks import check_number as _number

LEGACY_NO_RETURN = -1.0  # the thesis's "nothing within range" code (sec. 3.1.1)


@dataclass
class Laser:
    """A planar laser scanner: beam i points at ``angle_min + i * angle_increment`` (CCW, laser frame) up to
    ``angle_max``. ``no_return``: what a beam that hits nothing reports, ``inf`` (REP 117) or :data:`LEGACY_NO_RETURN`.

    >>> Laser.with_fov(180, 5).angles.round(3).tolist()
    [-1.571, -0.785, 0.0, 0.785, 1.571]
    """

    angle_min: float = -math.pi  # [rad]
    angle_max: float = math.pi - TWO_PI / 360  # [rad]
    angle_increment: float = TWO_PI / 360  # [rad]
    range_min: float = 0.05  # [m]
    range_max: float = 5.0  # [m]
    no_return: float = math.inf  # reported for beams that hit nothing within range_max

    def __post_init__(self):
        for name in ("angle_min", "angle_max", "angle_increment", "range_min", "range_max"):
            setattr(self, name, _number(f"laser.{name}", getattr(self, name)))
        if self.angle_increment <= 0:
            raise InputError("laser.angle_increment", f"must be > 0, got {self.angle_increment:g}")
        if self.angle_max < self.angle_min:
            raise InputError("laser.angle_max", f"must be >= angle_min ({self.angle_min:g}), got {self.angle_max:g}")
        if self.fov > TWO_PI + 1e-9:
            raise InputError("laser", f"the beams span {math.degrees(self.fov):g} deg, more than a full turn")
        if not 0 <= self.range_min < self.range_max:
            raise InputError("laser.range_min",
                             f"need 0 <= range_min < range_max, got {self.range_min:g}, {self.range_max:g}")
        nr = float(self.no_return)
        if not (nr == math.inf or nr < 0):
            raise InputError("laser.no_return", f"must be inf (REP 117) or negative (legacy -1), got {nr:g}")
        self.no_return = nr

    @classmethod
    def with_fov(cls, fov_deg=360.0, n_beams=360, range_max=5.0, range_min=0.05, no_return=math.inf) -> "Laser":
        """A laser of ``n_beams`` beams centred on +x. A 360 deg one spreads them evenly over the circle from -pi.

        >>> Laser.with_fov(360, 4).angles.round(3).tolist()
        [-3.142, -1.571, 0.0, 1.571]
        """
        fov_deg = _number("fov", fov_deg, 0.0, low_open=True)
        if fov_deg > 360:
            raise InputError("fov", f"must be at most 360 deg, got {fov_deg:g}")
        if isinstance(n_beams, bool) or not isinstance(n_beams, (int, np.integer)) or n_beams < 1:
            raise InputError("beams", f"must be a positive integer, got {n_beams!r}")
        if fov_deg == 360:
            inc = TWO_PI / n_beams
            return cls(-math.pi, math.pi - inc, inc, range_min, range_max, no_return)
        fov = math.radians(fov_deg)
        if n_beams == 1:
            return cls(0.0, 0.0, fov, range_min, range_max, no_return)
        return cls(-fov / 2, fov / 2, fov / (n_beams - 1), range_min, range_max, no_return)

    @property
    def n_beams(self) -> int:
        return int(math.floor((self.angle_max - self.angle_min) / self.angle_increment + 1e-6)) + 1

    @property
    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.n_beams)

    @property
    def fov(self) -> float:
        """Angle [rad] the beams cover, counting half an increment on each side."""
        return self.angle_max - self.angle_min + self.angle_increment

    def headings_per_turn(self) -> int:
        """How many scans, turning by ``2 pi / n`` between them, cover a full circle."""
        return max(1, int(math.ceil(TWO_PI / self.fov - 1e-9)))
