"""The hostile-input catalogue (cases.py, cases_more.py): every case is refused cleanly.

Clean means: exit status 2 (library: InputError), exactly one stderr line naming the input,
no traceback, the folder exactly as before (no output, previous output intact, no
temporary file), within a CPU-time limit (never the wall clock: a busy machine must not fail a case;
slow cases are listed in the summary); children also under an address-space limit.
Most cases run in this process (fast); signals and resource limits need a child.
"""
import pytest

from harness import all_cases, run_case

CASES = all_cases()


# a case run in a child process (a fresh interpreter importing crfmap) is among the slowest: marked, for information
@pytest.mark.parametrize("case", [pytest.param(c, marks=pytest.mark.slow) if c.subprocess else c for c in CASES],
                         ids=[f"{c.cls}/{c.name}" for c in CASES])
def test_refused_cleanly(case):
    found, err, _ = run_case(case, inprocess=True)
    assert not found, f"{found}\n--- stderr ---\n{err[-1500:]}"


def test_catalogue_covers_every_class():
    classes = {c.cls for c in CASES}
    assert len(CASES) >= 80
    assert classes >= {"maps", "yaml", "npy", "carmen", "ros1", "ros2", "potentials", "options", "output",
                       "faults", "signals", "library", "sweep", "environment"}
