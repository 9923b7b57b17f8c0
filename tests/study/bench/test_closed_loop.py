"""The closed-loop rows of crfmap bench: one record per onboard map kind, with what the run did."""
from crfstudy.bench.closed_loop import bench_closed_loop
from crfstudy.bench.suite import GROUPS


def test_one_exploration_per_kind_is_recorded_with_what_it_did():
    assert GROUPS["closed-loop"] == ("closed-loop",)
    rows = bench_closed_loop(quick=True)
    assert [r["method"] for r in rows] == ["closed-loop-raw", "closed-loop-online-crf"]
    for r in rows:
        assert r["seconds"] > 0 and r["scans"] > 0 and 0 < r["coverage"] <= 1 and r["collisions"] >= 0
        assert r["map_seconds"] + r["plan_seconds"] <= r["seconds"]
