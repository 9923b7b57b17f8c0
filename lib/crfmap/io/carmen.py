"""Read CARMEN laser logs (the Radish data sets: Intel lab, ACES building, ...).

A CARMEN log is text, one message per line (optionally gzip-compressed)::

    FLASER n r_1 ... r_n  x y theta  odom_x odom_y odom_theta  ipc_timestamp ipc_hostname logger_timestamp
    ODOM   x y theta tv rv accel  ipc_timestamp ipc_hostname logger_timestamp
    PARAM  name value ...

The n beams span 180 degrees counter-clockwise from the robot's right: ``angle_k = -pi/2 + k * pi / (n - 1)``. In
"corrected" logs both pose triples of a FLASER line hold the SLAM-corrected pose, our laser pose (zero mount); ODOM
lines are the raw odometry. FLASER stamps are kept as logged (a few run back by a tenth of a second: each is its own /tf
knot, so the scans still resolve to their poses). Other messages are skipped and counted. Readings at or beyond the
laser's maximum range are "no return" codes, which become ``+inf`` (REP 117), never hits (:mod:`crfmap.io.no_return`).
"""
from __future__ import annotations

import gzip
import math
import warnings
import zlib
from collections import Counter
from pathlib import Path

import numpy as np

from crfmap.checks import check_input_file, check_path_arg
from crfmap.grid import MAX_EXTENT_M
from crfmap.errors import InputError
from crfmap.io.no_return import NO_RETURN_TOLERANCE, no_return_rule
from crfmap.recording import Recording, ScanSet, Trajectory

MAX_LOG_BYTES = 256 << 20  # [bytes] of (decompressed) log text: Intel's is 6 MB; more is a gzip bomb or not a log
_CHUNK = 8 << 20  # [bytes] read at a time, so that binary content is refused early
MAX_BEAMS = 100_000  # readings per FLASER line
FLASER_FIXED_FIELDS = 9  # after the ranges: x y theta odom_x odom_y odom_theta ipc_ts hostname logger_ts
ODOM_FIELDS = 9  # x y theta tv rv accel ipc_ts hostname logger_ts
MAX_ODOM_SPEED = 2.0  # [m/s] faster than the robots of these logs drive (a Pioneer: 1.5 m/s) ...
MAX_ODOM_TURN = math.pi  # [rad/s] ... or turn
ODOM_JITTER = (0.25, 0.5)  # [m], [rad] moves this small pass whatever the stamps (logger timestamps jitter)


def _read_text(path: Path) -> str:
    path = check_input_file(path, "a CARMEN log file (.log or .log.gz)", missing="no such file")
    if path.stat().st_size > MAX_LOG_BYTES:
        raise InputError(path, f"larger than {MAX_LOG_BYTES >> 20} MB: not a CARMEN log crfmap reads")
    with open(path, "rb") as f:
        gzipped = f.read(2) == b"\x1f\x8b"
    chunks, size = [], 0
    try:
        with (gzip.open(path, "rb") if gzipped else open(path, "rb")) as f:
            while chunk := f.read(_CHUNK):  # decompress at most MAX_LOG_BYTES: a gzip bomb stops there
                if b"\0" in chunk:
                    raise InputError(path, f"not a text CARMEN log (a NUL byte at byte {size + chunk.index(0)})")
                chunks.append(chunk)
                size += len(chunk)
                if size > MAX_LOG_BYTES:
                    raise InputError(path, f"expands to more than {MAX_LOG_BYTES >> 20} MB of text (a gzip "
                                           "bomb?): not a CARMEN log crfmap reads")
    except (OSError, EOFError, zlib.error) as exc:
        raise InputError(path, f"corrupt gzip data ({exc})") from None
    raw = b"".join(chunks)
    try:
        return raw.decode("utf-8-sig")  # a byte-order mark (Windows editors) is not part of the first line
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


def _max_range(ranges, params, path, max_range, no_return):
    """(maximum range [m] or None, where it came from)."""
    name = "max_range"
    if no_return is not _UNSET:  # the older keyword: a range [m], 'auto' or None
        max_range, name = no_return, "no_return"
    if max_range is None:
        return None, "none (every reading is a hit)"
    if isinstance(max_range, str):
        if max_range != "auto":
            raise InputError(name, f"expected 'auto', a range in metres or None, got {max_range!r}")
        text = params.get("robot_front_laser_max")
        if text is not None:
            try:
                value = float(text)
            except ValueError:
                value = math.nan
            if not (math.isfinite(value) and value > 0):
                raise InputError(path, f"PARAM robot_front_laser_max {text!r} is not a positive range in metres")
            return value, "PARAM robot_front_laser_max"
        guess = no_return_rule(ranges)
        if guess.warning is not None:
            warnings.warn(f"{path.name}: {guess.warning}", stacklevel=3)
        return guess.max_range, (f"guessed from the readings ({guess.reason})" if guess.max_range is not None
                                 else guess.reason)
    if isinstance(max_range, bool) or not isinstance(max_range, (int, float, np.integer, np.floating)):
        raise InputError(name, f"expected 'auto', a range in metres or None, got {max_range!r}")
    value = float(max_range)
    if not (math.isfinite(value) and value > 0):
        raise InputError(name, f"the maximum range must be a positive number of metres, got {max_range!r}")
    return value, "given"


_UNSET = object()


def clean_odometry_stamps(stamps) -> np.ndarray:
    """Which odometry records to keep: a stamp above 0 ns and above every earlier kept one (logs have corrupt ODOM
    stamps, 0 or running back by seconds: as ROS messages, odometry at "no time" and tf going back in time).

    >>> clean_odometry_stamps(np.array([0.5, 0.0, 0.7, 0.6, 0.7, 0.9])).tolist()
    [True, False, True, False, False, True]
    """
    keep = np.zeros(len(stamps), dtype=bool)
    last = 0.0
    for i, t in enumerate(np.asarray(stamps, dtype=np.float64)):
        if round(t * 1e9) > 0 and t > last:
            keep[i] = True
            last = t
    return keep


def odometry_jumps(stamps, poses) -> np.ndarray:
    """Indices i of the moves i -> i+1 faster than :data:`MAX_ODOM_SPEED` / :data:`MAX_ODOM_TURN` allow
    over their time step, beyond :data:`ODOM_JITTER` (time-ordered ``stamps`` [s], ``poses`` (n, 3))."""
    if len(stamps) < 2:
        return np.zeros(0, dtype=np.int64)
    dt = np.diff(stamps)
    step = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    turn = np.abs((np.diff(poses[:, 2]) + math.pi) % (2 * math.pi) - math.pi)
    fast = (step > MAX_ODOM_SPEED * dt + ODOM_JITTER[0]) | (turn > MAX_ODOM_TURN * dt + ODOM_JITTER[1])
    return np.nonzero(fast)[0]


def read_carmen(path, max_range="auto", no_return=_UNSET, warn=True) -> Recording:
    """Read a CARMEN log (plain or gzip, detected from the content) into a :class:`~crfmap.recording.Recording`.

    ``max_range`` [m]: readings at or beyond it (less ``NO_RETURN_TOLERANCE``) become ``+inf``; ``"auto"``: the log's
    ``PARAM robot_front_laser_max``, else :func:`crfmap.io.no_return.no_return_rule`; None keeps every reading.
    ``no_return``: its older name. ``warn``: warn of dropped ODOM records (:func:`clean_odometry_stamps`) and of moves
    their stamps cannot explain (:func:`odometry_jumps`, kept). ``scans`` and ``true_poses`` hold the corrected FLASER
    poses in ``map``, ``odometry`` the ODOM lines with twists; ``meta`` the PARAM values, counts, the maximum range and
    where it came from."""
    path = check_path_arg(path, "CARMEN log file name", file=True)
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
            if n > MAX_BEAMS:
                raise InputError(path, f"line {line_no}: FLASER with {n} readings; at most {MAX_BEAMS} are accepted")
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
    far = np.abs(poses[:, :2]).max(axis=1) > MAX_EXTENT_M
    if far.any():
        row = int(np.argmax(far))
        raise InputError(path, f"line {laser_lines[row]}: FLASER pose ({poses[row, 0]:g}, {poses[row, 1]:g}) lies "
                               f"beyond {MAX_EXTENT_M:g} m: a corrupt field?")
    bad_stamp = ~np.isfinite(stamps) | (np.abs(stamps) > 1e11)  # 1e11 s: year 5138; beyond is a corrupt field
    if bad_stamp.any():
        raise InputError(path, f"line {laser_lines[int(np.argmax(bad_stamp))]}: FLASER timestamp "
                               f"{stamps[int(np.argmax(bad_stamp))]!r} is not a time")
    negative = np.nan_to_num(ranges, nan=0.0) < 0
    if negative.any():
        row = int(np.argmax(negative.any(axis=1)))
        raise InputError(path, f"line {laser_lines[row]}: negative range reading")

    code, code_source = _max_range(ranges, params, path, max_range, no_return)
    n_no_return = 0
    if code is not None:
        is_code = ranges >= code - NO_RETURN_TOLERANCE  # compared in float64, as the log printed them
        n_no_return = int(np.count_nonzero(is_code))
        ranges = np.where(is_code, np.inf, ranges)
    ranges = ranges.astype(np.float32)
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
    odometry, odometry_meta = None, {}
    if odom_rows:
        odom = _parse_rows(path, odom_rows, odom_lines, 8, "ODOM")
        if not np.all(np.isfinite(odom[:, :3])):
            row = int(np.argmax(~np.all(np.isfinite(odom[:, :3]), axis=1)))
            raise InputError(path, f"line {odom_lines[row]}: ODOM pose is not finite")
        bad = ~np.isfinite(odom[:, 6]) | (np.abs(odom[:, 6]) > 1e11)
        if bad.any():
            raise InputError(path, f"line {odom_lines[int(np.argmax(bad))]}: ODOM timestamp is not a time")
        keep = clean_odometry_stamps(odom[:, 6])
        n_dropped = len(keep) - int(np.count_nonzero(keep))
        if n_dropped and warn:
            warnings.warn(f"{path.name}: dropped {n_dropped} of {len(keep)} ODOM records with a zero or "
                          "non-increasing timestamp (corrupt odometry)", stacklevel=2)
        odom, odom_lines = odom[keep], [line for line, k in zip(odom_lines, keep) if k]
        jumps = odometry_jumps(odom[:, 6], odom[:, :3])
        if jumps.size and warn:
            i = int(jumps[0])
            warnings.warn(f"{path.name}: {jumps.size} ODOM moves faster than {MAX_ODOM_SPEED:g} m/s or "
                          f"{MAX_ODOM_TURN:.3g} rad/s that the log's timestamps cannot explain (first: line "
                          f"{odom_lines[i + 1]}, {np.hypot(*(odom[i + 1, :2] - odom[i, :2])):.2f} m in "
                          f"{odom[i + 1, 6] - odom[i, 6]:.3g} s); kept as logged", stacklevel=2)
        odometry = Trajectory(odom[:, 6].copy(), odom[:, :3].copy(), frame_id="odom",
                              child_frame_id="base_link", twists=odom[:, 3:5].copy())
        odometry_meta = {"odometry_dropped": n_dropped, "odometry_jumps": int(jumps.size)}
    meta = {
        "source": str(path),
        "format": "carmen",
        "params": params,
        "no_return_code": code,  # the maximum range [m]: readings at or beyond it are no-returns
        "max_range_source": code_source,
        "no_return_readings": n_no_return,
        "skipped_messages": dict(skipped),
        **odometry_meta,
    }
    return Recording(scans=scans, laser_mount=(0.0, 0.0, 0.0), odometry=odometry,
                     true_poses=true_poses, meta=meta)
