"""crfstudy.bench.online: the Intel-log online rows of `crfmap bench`."""
import pytest

from crfmap.data import have_data
from crfstudy.bench.common import INTEL
from crfstudy.bench.online import bench_online


@pytest.mark.skipif(not have_data(INTEL), reason="Intel lab log not present")
def test_online_rows_on_the_intel_log():
    rows = {r["method"]: r for r in bench_online(quick=True)}
    assert set(rows) == {"builder-intel", "online-intel", "online-intel-margin", "online-intel-final"}
    assert rows["online-intel"]["margin_cells"] is None and rows["online-intel-margin"]["margin_cells"] == 3
    for name in ("online-intel", "online-intel-margin"):
        assert rows[name]["scans"] == 910 and rows[name]["ms_per_scan_median"] > 0
        assert rows[name]["real_time_factor"] > 1  # no timing claim: only that the fields are sane
    final = rows["online-intel-final"]
    assert final["observations_equal_builder"] is True
    # quick: both stop at a message change of 1e-5; slowly mixing cells are then ~1e-3 from the fixed point
    assert final["max_abs_difference"] < 2e-2


def test_online_rows_say_when_the_log_is_missing(monkeypatch, tmp_path):
    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path))
    rows = bench_online(quick=True)
    assert len(rows) == 1 and "not found" in rows[0]["note"]
