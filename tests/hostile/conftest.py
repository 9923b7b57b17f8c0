"""The hostile catalogue's terminal summary (harness, cases and faults are on pytest's pythonpath)."""


def pytest_terminal_summary(terminalreporter):
    """The catalogue's cases by class; slow ones are reported here instead of failing (a loaded machine is no
    fault of the input)."""
    from harness import TIMINGS, class_counts, slow_cases

    if TIMINGS:  # catalogue cases ran: how many of each class
        terminalreporter.write_sep("-", "hostile catalogue: cases by class")
        terminalreporter.write_line(class_counts(TIMINGS))
    lines = slow_cases(TIMINGS)
    if lines:
        terminalreporter.write_sep("-", f"{len(lines)} slow hostile case(s)")
        for line in lines:
            terminalreporter.write_line(line)
