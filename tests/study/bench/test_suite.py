"""The benchmark runs, reports in its schema, and its baseline computes what crfmap computes."""
import io
import json
from contextlib import redirect_stdout

import numpy as np
import pytest

from crfstudy.bench import suite as bench
from crfmap.cli import main
from crfmap.crf.inference.schedules import Checkerboard
from crfmap.crf.inference.lbp import infer

KEYS = {"method", "size", "dtype", "threads", "seconds_per_iteration", "mcells_per_second"}


@pytest.fixture(scope="module")
def quick_records():
    out = io.StringIO()
    with redirect_stdout(out):
        status = main(["bench", "--quick", "--json", "--sizes", "64", "--repeats", "1", "--no-online", "--no-memory"])
    assert status == 0
    return [json.loads(line) for line in out.getvalue().splitlines() if line.strip()]


def test_quick_bench_records_follow_the_schema(quick_records):
    methods = {r["method"] for r in quick_records}
    assert {"numpy-baseline", "crfmap-fast", "crfmap-infer", "memory-bandwidth", "agreement",
            "crfmap-converge", "crfmap-converge-exact"} <= methods
    for r in quick_records:
        assert KEYS <= set(r), r
    timed = [r for r in quick_records if r["method"] in ("numpy-baseline", "crfmap-fast", "crfmap-infer")]
    for r in timed:
        assert r["size"] == 64 and r["seconds_per_iteration"] > 0 and r["mcells_per_second"] > 0
        assert r["dtype"] in ("float32", "float64")
    assert {r["threads"] for r in quick_records if r["method"] == "crfmap-fast"} >= {1}
    for r in quick_records:
        if r["method"].startswith("crfmap-converge"):
            assert r["iterations"] >= 1 and r["seconds_to_converge"] > 0 and r["converged"]
    # PGMax / PyMaxflow rows: a result when installed, else one record each saying how to install
    from crfstudy.bench.external import available

    for name, method in (("pgmax", "pgmax-bp"), ("pymaxflow", "pymaxflow-map")):
        rows = [r for r in quick_records if r["method"] == method]
        assert rows, method
        if available()[name] is None:
            assert len(rows) == 1 and rows[0]["note"].startswith("not installed")
    bw = [r for r in quick_records if r["method"] == "memory-bandwidth"]
    assert all(r["gbytes_per_second"] > 0 and r["bound_mcells_per_second"]["float32"] > 0 for r in bw)


def test_baseline_and_crfmap_agree_after_k_iterations(quick_records):
    (agree,) = [r for r in quick_records if r["method"] == "agreement"]
    assert agree["max_difference_baseline_vs_fast"] < 1e-10
    assert agree["max_difference_plain_vs_fast"] < 1e-10


@pytest.mark.parametrize("shape", [(1, 7), (6, 1), (5, 6), (33, 20)])
@pytest.mark.parametrize("hidden", [[[10.0, 1.0], [1.0, 10.0]], [[3.0, 0.7], [1.3, 2.5]], [[1.0, 0.0], [0.0, 1.0]]])
def test_numpy_baseline_equals_the_plain_kernel(shape, hidden):
    obs = np.random.default_rng(7).uniform(0.0, 1.0, shape)
    nb = bench.NumpyCheckerboard(obs, hidden, dtype=np.float64)
    nb.iterate(6)
    plain = infer(obs, hidden, max_iter=6, tol=0.0, schedule=Checkerboard(kernel="plain"))
    np.testing.assert_allclose(nb.beliefs(), plain.beliefs.probability, atol=1e-8)


def test_bench_grid_kinds():
    assert bench.bench_grid(32).shape == (32, 32)
    office = bench.bench_grid(64, kind="office")
    assert set(np.unique(office)) <= {0.2, 0.8}


def test_bad_bench_arguments_are_one_line_errors(capsys):
    assert main(["bench", "--sizes", "4"]) == 2
    assert "--sizes" in capsys.readouterr().err
    assert main(["bench", "--repeats", "0"]) == 2


# --- issue 13's rows: speed as users feel it ----------------------------------------------------------

def test_quick_bench_has_a_row_for_each_user_facing_goal(quick_records):
    rows = {}
    for r in quick_records:
        rows.setdefault(r["method"], []).append(r)
    assert {"infer-vs-kernel", "kernel-vs-bound", "start-cold", "start-warm", "start-env", "explorer-redraw", "explorer-scene-change",
            "reproduce", "converge-start", "preset-converge"} <= set(rows)
    # end to end against the same run's kernel, same size / dtype / threads
    (ratio,) = rows["infer-vs-kernel"]
    (kernel,) = [r for r in rows["crfmap-fast"] if r["dtype"] == "float32" and r["threads"] == ratio["threads"]]
    (end_to_end,) = rows["crfmap-infer"]
    assert ratio["kernel_mcells_per_second"] == kernel["mcells_per_second"]
    assert ratio["ratio"] == pytest.approx(end_to_end["mcells_per_second"] / kernel["mcells_per_second"])
    # each float32 kernel row against the bandwidth row with the same threads, from the same run
    bounds = {r["threads"]: r["bound_mcells_per_second"]["float32"] for r in rows["memory-bandwidth"]}
    against = rows["kernel-vs-bound"]
    assert {r["threads"] for r in against} == set(bounds)
    for r in against:
        (k,) = [f for f in rows["crfmap-fast"] if f["dtype"] == "float32" and f["threads"] == r["threads"]]
        assert r["kernel_mcells_per_second"] == k["mcells_per_second"]
        assert r["ratio_to_bound"] == pytest.approx(k["mcells_per_second"] / bounds[r["threads"]])
        assert r["goal_ratio"] == (2.0 if r["size"] == 2048 and r["threads"] > 1 else None)
    # quick: the empty-cache start is skipped, saying so; the warm ones are timed
    (cold,) = rows["start-cold"]
    assert cold["seconds"] is None and "quick" in cold["note"]
    assert rows["start-warm"][0]["seconds"] > 0 and rows["start-env"][0]["seconds"] > 0
    (redraw,) = rows["explorer-redraw"]
    assert redraw["changes"] == 6 and redraw["compiled_during_changes"] == 0
    assert 0 < redraw["draw_seconds"] <= redraw["max_seconds"] and redraw["seconds"] > 0
    (reproduce,) = rows["reproduce"]
    assert reproduce["seconds"] is None and reproduce["note"].startswith("no timing record") or reproduce["seconds"] > 0
    uniform = [r for r in rows["converge-start"] if r["start"] == "uniform"]
    assert uniform[0]["converged"] and uniform[0]["size"] == 256 and uniform[0]["max_belief_difference_vs_uniform"] == 0
    assert len(rows["converge-start"]) == 2  # the coarse start's row, measured or saying infer() has none
    # the default preset, converged, against 5 iterations of the baseline on the same shape
    (preset,) = rows["preset-converge"]
    assert preset["map"] == "office" and preset["shape"] == [256, 256] and preset["converged"]
    assert preset["goal_seconds"] == pytest.approx(5 * preset["baseline_seconds_per_iteration"])
    assert preset["ratio_to_goal"] == pytest.approx(preset["seconds"] / preset["goal_seconds"])


def test_preset_row_says_which_map_is_missing(monkeypatch, tmp_path):
    from crfstudy.bench.goals import preset_converge

    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path))  # no logs here
    (row,) = preset_converge(maps=("aces",))
    assert row["seconds"] is None and row["note"].startswith("skipped: ") and "aces-corrected.log.gz" in row["note"]


def test_reproduce_row_reads_the_last_runs_record(tmp_path):
    from crfstudy.bench.goals import reproduce_record

    path, wall = tmp_path / "reproduce_timings.json", tmp_path / "reproduce_wall.json"
    assert reproduce_record(path, wall)["seconds"] is None
    path.write_text(json.dumps({"seconds": {"01_a.ipynb": 12.0, "09_speed.ipynb": 150.0}, "total_seconds": 170.5,
                                "quick": False}))
    rec = reproduce_record(path, wall)  # no wall-clock record: the summed notebook times, said so
    assert rec["seconds"] == 170.5 and rec["slowest"] == "09_speed.ipynb" and rec["record_quick"] is False
    assert "summed" in rec["note"]


def test_reproduce_row_prefers_the_same_runs_wall_clock(tmp_path):
    import os

    from crfstudy.bench.goals import reproduce_record
    from crfstudy.repro.reproduce import write_wall_record

    path, wall = tmp_path / "reproduce_timings.json", tmp_path / "reproduce_wall.json"
    path.write_text(json.dumps({"seconds": {"01_a.ipynb": 12.0}, "total_seconds": 12.0}))
    write_wall_record(80.0, started_at=None, path=wall)
    os.utime(path, (1e9, 1e9))  # the timings are older than the wall record: the same run
    rec = reproduce_record(path, wall)
    assert rec["seconds"] == 80.0 and rec["workflow_seconds"] == 80.0 and "workflow" in rec["note"]
    import time

    before = time.time()
    write_wall_record(80.0, started_at=before - 200.0, path=wall)
    rec = reproduce_record(path, wall)
    elapsed = time.time() - before  # however busy the machine, the record lies within what passed here
    assert 200.0 - 1.0 <= rec["seconds"] <= 200.0 + elapsed + 1.0
    assert rec["notebook_seconds_total"] == 12.0 and "venv" in rec["note"]
    os.utime(wall, (1e9 - 10, 1e9 - 10))  # a wall record older than the timings belongs to another run
    assert reproduce_record(path, wall)["seconds"] == 12.0


def test_wall_record_keeps_every_run(tmp_path):
    from crfstudy.repro.reproduce import write_wall_record

    wall = tmp_path / "reproduce_wall.json"
    wall.write_text(json.dumps({"workflow_seconds": 300.0, "cores": 2, "finished": "x", "make_seconds": 400.0}))
    write_wall_record(90.0, started_at=None, path=wall, new_venv=True)  # a record of the old one-run form
    write_wall_record(12.0, started_at=None, path=wall)
    data = json.loads(wall.read_text())
    assert [r["workflow_seconds"] for r in data["runs"]] == [300.0, 90.0, 12.0]
    assert [r.get("new_venv") for r in data["runs"]] == [None, True, False]
    assert data["workflow_seconds"] == 12.0 and data["new_venv"] is False  # the top level is the last run
    wall.write_text("not json")
    write_wall_record(5.0, path=wall)  # an unreadable record is replaced, not kept half
    assert [r["workflow_seconds"] for r in json.loads(wall.read_text())["runs"]] == [5.0]


def test_reproduce_row_names_the_last_fresh_clone_run(tmp_path):
    from crfstudy.bench.goals import reproduce_record
    from crfstudy.repro.reproduce import write_wall_record

    path, wall = tmp_path / "reproduce_timings.json", tmp_path / "reproduce_wall.json"
    write_wall_record(150.0, started_at=0.0, path=wall, new_venv=True)
    write_wall_record(10.0, started_at=None, path=wall)
    path.write_text(json.dumps({"seconds": {"01_a.ipynb": 12.0}, "total_seconds": 12.0}))
    import os
    os.utime(path, (1e9, 1e9))
    rec = reproduce_record(path, wall)
    assert rec["runs_recorded"] == 2 and rec["last_fresh_clone_seconds"] > 1e9 and rec["seconds"] == 10.0


def test_coarse_start_option_is_one_that_changes_the_start():
    from crfstudy.bench.goals import COARSE_START_OPTIONS, coarse_start_option

    option = coarse_start_option()
    assert option == {"init": "coarse"} and option in COARSE_START_OPTIONS  # infer has one now
    if option is not None:
        obs = bench.bench_grid(256, kind="office")
        assert not np.array_equal(infer(obs, max_iter=1, tol=0.0, **option).beliefs.probability,
                                  infer(obs, max_iter=1, tol=0.0).beliefs.probability)


def test_the_reproductions_lighter_settings_reach_the_records():
    records = list(bench.run(sizes=(64,), quick=True, repeats=1, threads=(1,), progress=False, online=False,
                             memory=False, external=False, goals=False, work=4096 * 32, bandwidth_mbytes=8,
                             converge_runs=1, cold=False))
    assert {r["mbytes_per_array"] for r in records if r["method"] == "memory-bandwidth"} == {8}
    fast = [r for r in records if r["method"] == "crfmap-fast"]
    assert fast and all(r["iterations_timed"] == 32 for r in fast)  # work / cells, a multiple of the block
    assert [r["cache"] for r in records if r["method"] == "jit-compile"] == ["warm"]  # no empty-cache child


def test_only_runs_the_groups_asked_for_and_names_a_wrong_one(capsys):
    records = list(bench.run(quick=True, progress=False, only=["machine"], threads=(1,)))
    assert {r["method"] for r in records} == {"agreement", "memory-bandwidth", "division-throughput"}
    assert main(["bench", "--only", "node", "nope"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--only" in err and "nope" in err


def test_the_peers_and_node_rows_can_be_left_out(monkeypatch):
    """Notebook 09's reproduction leaves out rows no table of it shows; `crfmap bench` keeps them."""
    from crfstudy.bench import node, online, peers

    monkeypatch.setattr(online, "bench_online", lambda **kw: [{"method": "online-stub"}])
    monkeypatch.setattr(peers, "bench_peers", lambda **kw: [{"method": "peers-stub"}])
    monkeypatch.setattr(node, "bench_node_refine", lambda **kw: [{"method": "node-refine-stub"}])
    monkeypatch.setattr(node, "bench_node_map", lambda **kw: [{"method": "node-map-stub"}])
    monkeypatch.setattr(node, "bench_node_memory", lambda *a, **kw: [{"method": "node-memory-stub"}])
    from crfstudy.bench import closed_loop

    monkeypatch.setattr(closed_loop, "bench_closed_loop", lambda **kw: [{"method": "closed-loop-stub"}])

    def methods(**flags):
        return {r["method"] for r in bench.run(sizes=(64,), quick=True, repeats=1, threads=(1,), progress=False,
                                               memory=False, external=False, goals=False, cold=False, **flags)}

    every = methods()
    node_rows = {"node-refine-stub", "node-map-stub", "node-memory-stub"}
    assert {"online-stub", "peers-stub", "closed-loop-stub", "crfmap-fast"} | node_rows <= every
    fewer = methods(peers=False, node=False)
    assert {"online-stub", "closed-loop-stub"} <= fewer and not ({"peers-stub"} | node_rows) & fewer
    assert every - fewer == {"peers-stub"} | node_rows
