"""Planar poses as 3x3 homogeneous matrices: an independent reference for crfmap.frames."""
import math

import numpy as np


def se2(x, y, yaw):
    """Homogeneous matrix of a planar pose: an independent check of the pose algebra."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0, 0, 1.0]])


def pose_of(m):
    return np.array([m[0, 2], m[1, 2], math.atan2(m[1, 0], m[0, 0])])


def angle_diff(a, b):
    return np.abs((np.asarray(a) - np.asarray(b) + np.pi) % (2 * np.pi) - np.pi)
