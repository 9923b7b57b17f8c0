"""Read CARMEN laser logs (the Radish data sets: Intel lab, ACES building, ...).

A CARMEN log is text, one message per line (optionally gzip-compressed)::

    FLASER n r_1 ... r_n  x y theta  odom_x odom_y odom_theta  ipc_timestamp ipc_hostname logger_timestamp
    ODOM   x y theta tv rv accel  ipc_timestamp ipc_hostname logger_timestamp
    PARAM  name value ...

The n beams span 180 degrees counter-clockwise from the robot's right:
``angle_k = -pi/2 + k * pi / (n - 1)``. In the "corrected" logs both pose triples of a
FLASER line hold the SLAM-corrected pose, which we use as the laser pose (a zero laser
mount; ``robot_frontlaser_offset`` is 0 in these logs and is kept in ``meta``). ODOM
lines are the raw odometry track. The largest reading in a file is the sensor's
no-return code (81.83 m in Intel, 50.00 m in ACES); those readings become ``+inf``
(REP 117 "no return"). Other message types (NEFF, SYNC, ...) are skipped and counted.
"""
from __future__ import annotations

import gzip
import math
from collections import Counter
from pathlib import Path

import numpy as np

from crfmap.errors import InputError
from crfmap.recording import Recording, ScanSet, Trajectory

NO_RETURN_TOLERANCE = 0.005  # [m] readings this close to the no-return code are no-returns (logs print cm)
FLASER_FIXED_FIELDS = 9  # after the ranges: x y theta odom_x odom_y odom_theta ipc_ts hostname logger_ts
ODOM_FIELDS = 9  # x y theta tv rv accel ipc_ts hostname logger_ts


def _read_text(path: Path) -> str:
    if not path.exists():
        raise InputError(path, "no such file")
    if path.is_dir():
        raise InputError(path, "is a folder, expected a CARMEN log file (.log or .log.gz)")
    raw = path.read_bytes()
    if raw[:2] == b"\x1f\x8b":
        try:
            raw = gzip.decompress(raw)
        except (OSError, EOFError) as exc:
            raise InputError(path, f"corrupt gzip data ({exc})") from None
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(path, f"not a text CARMEN log (byte {exc.start} is not UTF-8)") from None


def _parse_rows(path, rows, line_numbers, width, what):
    """Float array (len(rows), width) from token lists, or an InputError naming the first bad line."""
    flat = [tok for row in rows for tok in row]
    try:
        values = np.array(flat, dtype=np.float64)
    except ValueError:
        for row, line_no in zip(rows, line_numbers):
            for tok in row:
                try:
                    float(tok)
                except ValueError:
                    raise InputError(path, f"line {line_no}: {what} value {tok!r} is not a number") from None
        raise  # pragma: no cover - np.array failed but every token parsed
    return values.reshape(len(rows), width)


def _no_return_code(ranges: np.ndarray, no_return):
    """The no-return code to use: a number, or None; 'auto' = the file's largest reading if repeated."""
    if no_return is None:
        return None
    if isinstance(no_return, str):
        if no_return != "auto":
            raise InputError("no_return", f"expected 'auto', a range in metres or None, got {no_return!r}")
        finite = ranges[np.isfinite(ranges)]
        if finite.size == 0:
            return None
        largest = float(finite.max())
        # A genuine reading is rarely repeated exactly at the maximum; the code is (hundreds of times).
        return largest if np.count_nonzero(finite >= largest - NO_RETURN_TOLERANCE) >= 2 else None
    code = float(no_return)
    if not (math.isfinite(code) and code > 0):
        raise InputError("no_return", f"the no-return code must be a positive range in metres, got {no_return!r}")
    return code


def read_carmen(path, no_return="auto") -> Recording:
    """Read a CARMEN log (plain or gzip) into a :class:`~crfmap.recording.Recording`.

    Parameters
    ----------
    path : str or Path
        The log (``.log`` or ``.log.gz``; compression is detected from the content).
    no_return : 'auto', float or None
        The range [m] the sensor reports when nothing returned; readings within
        ``NO_RETURN_TOLERANCE`` of it become ``+inf``. 'auto' takes the file's largest
        reading when it occurs more than once; None keeps every reading as it is.

    Returns
    -------
    Recording
        ``scans`` (laser poses = corrected FLASER poses in ``map``), ``true_poses``
        (the same poses as base_link in map), ``odometry`` (ODOM lines, with twists),
        ``meta`` (PARAM values, counts, the no-return code).

    Examples
    --------
    >>> rec = read_carmen(data_file("carmen/intel-corrected.log.gz"))  # doctest: +SKIP
    >>> rec.scans.ranges.shape  # doctest: +SKIP
    (910, 180)
    """
    path = Path(path)
    text = _read_text(path)
    laser_rows, laser_lines = [], []
    odom_rows, odom_lines = [], []
    params = {}
    skipped = Counter()
    n_beams = None
    for line_no, line in enumerate(text.splitlines(), start=1):
        head = line[:8]
        if head.startswith("FLASER"):
            tokens = line.split()
            if tokens[0] != "FLASER":
                skipped[tokens[0]] += 1
                continue
            if len(tokens) < 2 or not tokens[1].isdigit():
                raise InputError(path, f"line {line_no}: FLASER needs the number of readings after the keyword")
            n = int(tokens[1])
            if n < 2:
                raise InputError(path, f"line {line_no}: FLASER with {n} reading(s); need at least 2")
            if n_beams is None:
                n_beams = n
            elif n != n_beams:
                raise InputError(
                    path, f"line {line_no}: FLASER with {n} readings, earlier lines have {n_beams} (inconsistent beam count)"
                )
            if len(tokens) != 2 + n + FLASER_FIXED_FIELDS:
                raise InputError(
                    path,
                    f"line {line_no}: FLASER with {n} readings needs {2 + n + FLASER_FIXED_FIELDS} fields, "
                    f"found {len(tokens)}",
                )
            laser_rows.append(tokens[2 : 2 + n + 7] + tokens[2 + n + 8 :])  # drop the hostname
            laser_lines.append(line_no)
        elif head.startswith("ODOM"):
            tokens = line.split()
            if tokens[0] != "ODOM":
                skipped[tokens[0]] += 1
                continue
            if len(tokens) != 1 + ODOM_FIELDS:
                raise InputError(path, f"line {line_no}: ODOM needs {1 + ODOM_FIELDS} fields, found {len(tokens)}")
            odom_rows.append(tokens[1:8] + tokens[9:])
            odom_lines.append(line_no)
        elif head.startswith("PARAM"):
            tokens = line.split()
            if tokens[0] == "PARAM":
                if len(tokens) < 3:
                    raise InputError(path, f"line {line_no}: PARAM needs a name and a value")
                params[tokens[1]] = tokens[2]
            else:
                skipped[tokens[0]] += 1
        else:
            stripped = line.strip()
            if stripped and not stripped.startswith("#"):
                skipped[stripped.split()[0]] += 1

    if not laser_rows:
        raise InputError(path, "no FLASER lines: not a CARMEN laser log (or only unsupported laser messages)")
    laser = _parse_rows(path, laser_rows, laser_lines, n_beams + 8, "FLASER")
    ranges = laser[:, :n_beams]
    poses = laser[:, n_beams : n_beams + 3]
    stamps = laser[:, n_beams + 6]
    bad_pose = ~np.all(np.isfinite(poses), axis=1)
    if bad_pose.any():
        raise InputError(path, f"line {laser_lines[int(np.argmax(bad_pose))]}: FLASER pose is not finite")
    negative = np.nan_to_num(ranges, nan=0.0) < 0
    if negative.any():
        row = int(np.argmax(negative.any(axis=1)))
        raise InputError(path, f"line {laser_lines[row]}: negative range reading")

    code = _no_return_code(ranges, no_return)
    ranges = ranges.astype(np.float32)
    n_no_return = 0
    if code is not None:
        is_code = np.abs(ranges - np.float32(code)) <= np.float32(NO_RETURN_TOLERANCE)
        n_no_return = int(np.count_nonzero(is_code))
        ranges[is_code] = np.inf
    finite = ranges[np.isfinite(ranges)]
    range_max = code if code is not None else (float(finite.max()) if finite.size else 0.0)

    scans = ScanSet(
        ranges=ranges,
        angle_min=-math.pi / 2,
        angle_increment=math.pi / (n_beams - 1),
        range_min=0.0,
        range_max=float(range_max),
        laser_poses=poses.copy(),
        stamps=stamps.copy(),
        frame_id="map",
        laser_frame_id="laser",
        source=str(path),
    )
    true_poses = Trajectory(stamps.copy(), poses.copy(), frame_id="map", child_frame_id="base_link")
    odometry = None
    if odom_rows:
        odom = _parse_rows(path, odom_rows, odom_lines, 8, "ODOM")
        if not np.all(np.isfinite(odom[:, :3])):
            row = int(np.argmax(~np.all(np.isfinite(odom[:, :3]), axis=1)))
            raise InputError(path, f"line {odom_lines[row]}: ODOM pose is not finite")
        odometry = Trajectory(odom[:, 6].copy(), odom[:, :3].copy(), frame_id="odom",
                              child_frame_id="base_link", twists=odom[:, 3:5].copy())
    meta = {
        "source": str(path),
        "format": "carmen",
        "params": params,
        "no_return_code": code,
        "no_return_readings": n_no_return,
        "skipped_messages": dict(skipped),
    }
    return Recording(scans=scans, laser_mount=(0.0, 0.0, 0.0), odometry=odometry,
                     true_poses=true_poses, meta=meta)
