"""Tests mirror the package (tests/crf/ for crfmap.crf, ...); the naive references stay here, importable from all
(pyproject.toml's ``[tool.pytest.ini_options] pythonpath`` puts tests/ on the path)."""
import signal

import pytest

# Under `nohup make test` SIGHUP arrives ignored and every child would inherit that: the signal tests (the hostile
# catalogue's, tests/io/test_atomic_signals.py) send SIGHUP to see a command stop cleanly, so it gets its default back
if signal.getsignal(signal.SIGHUP) is signal.SIG_IGN:
    signal.signal(signal.SIGHUP, signal.SIG_DFL)

# a two-scan CARMEN log that the command tests build maps from (tests/mapping, tests/commands/test_ros_options.py)
CARMEN_LINES = [
    "PARAM robot_frontlaser_offset 0.0 nohost 0",
    "FLASER 5 1.0 1.1 9.0 1.2 1.3 0.0 0.0 0.0 0.0 0.0 0.0 1.0 host 1.0",
    "FLASER 5 1.0 9.0 1.2 1.2 1.3 0.1 0.0 0.1 0.1 0.0 0.1 2.0 host 2.0",
]


@pytest.fixture
def small_log(tmp_path):
    path = tmp_path / "small.log"
    path.write_text("\n".join(CARMEN_LINES) + "\n")
    return path
