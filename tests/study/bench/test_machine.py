"""The machine rows: bandwidth bound and division ceiling, per thread count, from the same measurements."""
import numpy as np

from crfstudy.bench import machine
from crfstudy.bench.common import BYTES_PER_CELL_PASS


def test_the_division_kernel_divides():
    a, b, out = np.array([1.0, 3.0], np.float32), np.array([2.0, 4.0], np.float32), np.zeros(2, np.float32)
    machine._divide(a, b, out, 3)
    assert np.array_equal(out, a / b)


def test_the_rows_give_each_thread_count_its_bound_and_ceiling():
    rows, bounds, ceilings = machine.machine_rows((1, 2), mbytes=2)
    by = {(r["method"], r["threads"]): r for r in rows}
    assert set(by) == {(m, t) for m in ("memory-bandwidth", "division-throughput") for t in (1, 2)}
    for t in (1, 2):
        bw, div = by["memory-bandwidth", t], by["division-throughput", t]
        assert bounds[t] == bw["gbytes_per_second"] * 1e3 / BYTES_PER_CELL_PASS["float32"] > 0
        assert ceilings[t] == div["gdivisions_per_second"] * 1e3 / machine.DIVISIONS_PER_CELL > 0
        assert div["divisions_per_cell"] == machine.DIVISIONS_PER_CELL and div["dtype"] == "float32"
