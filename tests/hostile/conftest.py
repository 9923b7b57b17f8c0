"""The hostile catalogue's terminal summary (harness, cases and faults are on pytest's pythonpath)."""


def pytest_terminal_summary(terminalreporter):
    """Slow catalogue cases are reported here instead of failing (a loaded machine is no fault of the input)."""
    from harness import TIMINGS, slow_cases

    lines = slow_cases(TIMINGS)
    if lines:
        terminalreporter.write_sep("-", f"{len(lines)} slow hostile case(s)")
        for line in lines:
            terminalreporter.write_line(line)
