"""Issue 38's goal table: the goal rules on hand-made summaries (met / missed at the edges), and a tiny run end to end."""
import ast
import copy
import json
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest

from crfmap.assess.peers import PEERS
from crfmap.crf.presets import DEFAULT_PRESET as D
from crfmap.errors import InputError
from crfstudy.experiments import goal_rules as gr
from crfstudy.experiments import nav_goals as ng

ROOT = Path(__file__).resolve().parents[3]
NOTEBOOK = ROOT / "notebooks" / "12_navigation_goals.ipynb"


def _status(summary, goal):
    return {v.goal: v.status for v in gr.recording_goals(summary)}[goal]


def test_the_example_summary_gives_the_verdicts_worked_out_by_hand():
    got = {v.goal: v.status for v in gr.recording_goals(gr.example_summary())}
    assert got == {"1a": "met*", "1b": "met", "1c": "missed", "2a": "met", "2b": "met", "3": "met", "4a": "met",
                   "4b": "met", "5a": "met", "5b": "met", "5c": "met", "6": "met*", "8a": "missed", "8b": "met", "8c": "met",
                   "8d": "met*"}


@pytest.mark.parametrize("diff, ci, lower, expected", [
    (0.01, (0.0, 0.02), True, (True, True)),  # the interval touches 0: not shown worse
    (0.01, (1e-9, 0.02), True, (False, False)),  # just above 0: worse
    (-0.01, (-0.02, 0.0), True, (True, False)),
    (-0.01, (-0.02, -1e-9), False, (False, False)),  # higher is better: the interval below 0 is worse
    (0.0, (0.0, 0.0), True, (True, False)),
    (0.02, None, True, (False, False)),  # no interval: the point estimate decides
    (float("nan"), (0.0, 0.1), True, (None, False)),
])
def test_no_worse_at_its_edges(diff, ci, lower, expected):
    assert gr.no_worse(diff, ci, lower_is_better=lower) == expected


@pytest.mark.parametrize("diff, ci, lower, expected", [
    (-0.01, (-0.02, 0.0), True, False),  # touching 0 is not better
    (-0.01, (-0.02, -1e-9), True, True),
    (0.01, (0.0, 0.02), False, False),
    (0.01, (1e-9, 0.02), False, True),
    (-0.01, None, True, True),
    (0.0, None, True, False),
    (float("nan"), None, True, None),
])
def test_better_at_its_edges(diff, ci, lower, expected):
    assert gr.better(diff, ci, lower_is_better=lower) is expected


def _with(path, value):
    s = copy.deepcopy(gr.example_summary())
    target = s
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return s


@pytest.mark.parametrize("path, value, goal, expected", [
    (("brier_vs_certainty",), {"diff": 0.0004, "ci": [0.0001, 0.0007]}, "1a", "missed"),
    (("brier_vs_certainty",), {"diff": -0.0004, "ci": [-0.0007, 0.0]}, "1a", "met"),
    (("ece_vs_certainty", "ci"), [-0.004, 0.0], "1b", "met"),  # the paired interval reaches no difference
    (("ece_vs_certainty", "ci"), [0.0001, 0.004], "1b", "missed"),  # shown worse
    (("ece_vs_certainty", "diff"), 0.001, "1b", "met*"),  # worse point estimate, not shown worse
    (("harder", "temporal halves", "ci"), [-0.003, -1e-9], "1c", "met"),  # every harder split won
    (("harder", "temporal halves", "ci"), [-0.003, 0.0], "1c", "missed"),
    (("nav", D, "seen", "miss_rate_diff_ci"), [1e-9, 0.01], "2a", "missed"),
    (("nav", D, "unseen", "miss_rate_diff_ci"), [0.0, 0.01], "2b", "met"),
    (("nav", D, "all", "ghost_rate_diff_ci"), [-0.01, 0.0], "3", "missed"),  # "fewer" needs the interval below 0
    (("nav", D, "all", "lethal_precision_diff_ci"), [-0.01, 0.0], "4a", "met"),
    (("nav", D, "all", "lethal_precision_diff_ci"), [-0.01, -1e-9], "4a", "missed"),
    (("nav", D, "all", "lethal_recall_diff_ci"), [0.0, 0.1], "4b", "missed"),  # "above" needs it above 0
    (("nav", D, "map", "thickness"), 2.2, "5a", "met"),  # raw 1.2 + 1 exactly
    (("nav", D, "map", "thickness"), 2.2001, "5a", "missed"),
    (("nav", D, "map", "components_per_10m"), 9.0, "5b", "missed"),  # as many as raw is not fewer
    (("nav", D, "map", "components_per_10m"), float("nan"), "5b", "n/a"),
    (("nav", D, "all", "face_offset_diff_ci"), [1e-9, 0.2], "5c", "missed"),  # the face moved back, shown
    (("nav", D, "all", "face_offset_diff"), 0.1, "5c", "met*"),  # worse point, interval [0, 0] reaches no difference
    (("localisation", D, "rotation_error_diff_ci"), [1e-9, 0.2], "6", "missed"),  # worse on one measure
    (("localisation", D, "found_diff_ci"), [0.0, 0.05], "6", "met*"),
    (("nav", D, "all", "miss_rate"), 0.03, "8a", "met"),  # a tie with the best peer is best
    (("nav", D, "all", "ghost_rate"), 0.0201, "8b", "missed"),
    (("nav", D, "all", "lethal_precision"), 0.80, "8c", "met"),
    (("nav_vs_default", "octomap", "lethal_recall_diff_ci"), [1e-9, 0.09], "8d", "missed"),
    (("nav", D, "all", "lethal_recall"), 0.70, "8d", "met"),  # as good as the best: no interval needed
])
def test_each_goal_flips_at_its_edge(path, value, goal, expected):
    assert _status(_with(path, value), goal) == expected


def test_a_no_worse_goal_met_only_by_its_interval_is_marked():
    s = _with(("nav", D, "all", "lethal_precision_diff"), -0.005)
    s["nav"][D]["all"]["lethal_precision_diff_ci"] = [-0.01, 0.0]
    assert _status(s, "4a") == "met*"


def test_goal_1c_without_harder_splits_is_not_scored():
    assert _status(_with(("harder",), {}), "1c") == "n/a"


def _records(scans_crf, walls_crf=(1, 1, 1)):
    rows = []
    for i, scene in enumerate(("a", "b", "c")):
        for kind, scans, walls in (("raw", 50, 2), ("octomap", 60, 0), ("online-crf", scans_crf[i], walls_crf[i])):
            rows.append({"scene": scene, "kind": kind, "scans": scans, "collisions": 0, "plans_into_walls": walls})
    return rows


def test_closed_loop_goal_7_on_hand_made_records():
    v = {x.goal: x for x in gr.closed_loop_goals(_records((50, 50, 50)), n_boot=200)}
    assert [v[g].status for g in ("7a", "7b")] == ["met", "met"]
    assert v["7c"].status == "missed"  # 1 plan into a wall against octomap's 0 in every scene: the interval is 1, 1
    v = {x.goal: x for x in gr.closed_loop_goals(_records((51, 51, 51), (0, 0, 0)), n_boot=200)}
    assert v["7a"].status == "missed" and "+1.00 [+1.00, +1.00]" in v["7a"].evidence
    assert v["7c"].status == "met"
    v = {x.goal: x for x in gr.closed_loop_goals(_records((40, 60, 50), (0, 0, 0)), n_boot=200)}
    assert v["7a"].status == "met"  # against raw: +0 on average, the interval spans 0
    with pytest.raises(InputError, match="octomap"):
        gr.closed_loop_goals([r for r in _records((50, 50, 50)) if r["kind"] != "octomap"])


def test_the_matrix_names_what_was_missed_and_marks_interval_only_goals():
    columns = {"x": gr.recording_goals(gr.example_summary()), "loop": gr.closed_loop_goals(_records((50, 50, 50)))}
    header, rows = gr.goal_matrix(columns)
    by_goal = {row[0].split()[0]: row[1:] for row in rows}
    assert header == ["goal", "x", "loop"] and len(rows) == 8
    assert by_goal["1"] == ["missed: 1c", "n/a"] and by_goal["6"] == ["met*", "n/a"]
    assert by_goal["5"] == ["met", "n/a"] and by_goal["7"] == ["n/a", "missed: 7c"]
    assert by_goal["8"] == ["missed: 8a", "n/a"]
    _, details = gr.goal_details(columns)
    assert len(details) == 16 + 3 and details[0][:4] == ["x", "1a", details[0][2], "met*"]


def test_harder_matrix_names_the_split_and_sub_goal_missed():
    summary = gr.example_summary()
    header, rows = gr.harder_matrix({"x": summary})
    assert header == ["goal (harder splits)", "x"] and [r[1] for r in rows] == ["met", "met", "met", "met"]
    blocks = summary["harder"]["scan blocks"]["nav"][D]["all"]
    blocks["ghost_rate_diff_ci"] = [0.001, 0.02]  # more ghosts than raw there, shown
    _, rows = gr.harder_matrix({"x": summary})
    assert rows[1] == [f"3 {gr.GOALS['3']}", "missed: scan blocks 3"] and rows[0][1] == "met"
    del summary["harder"]  # a summary without harder splits: nothing scored
    assert gr.harder_matrix({"x": summary})[1][0][1] == gr.NOT_SCORED


def _line_log(path, n_scans=24, seed=0):
    """A CARMEN log of a laser driving along a 3 m x 2 m room while turning (181 beams over 180 degrees)."""
    rng = np.random.default_rng(seed)
    angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
    lines = []
    for i in range(n_scans):
        x, y, yaw = 0.6 + 1.8 * i / (n_scans - 1), 1.0 + 0.05 * rng.standard_normal(), 2 * np.pi * i / 8
        a = angles + yaw
        with np.errstate(divide="ignore"):
            tx = np.where(np.cos(a) > 0, (2.95 - x) / np.cos(a), (0.05 - x) / np.cos(a))
            ty = np.where(np.sin(a) > 0, (1.95 - y) / np.sin(a), (0.05 - y) / np.sin(a))
        r = np.minimum(np.abs(tx), np.abs(ty)) + 0.01 * rng.standard_normal(181)
        ranges = " ".join(f"{v:.3f}" for v in r)
        lines.append(f"FLASER 181 {ranges} {x:.4f} {y:.4f} {yaw:.4f} {x:.4f} {y:.4f} {yaw:.4f} {i:.1f} host {i:.1f}")
    path.write_text("\n".join(lines) + "\n")
    return path


TINY = ng.GoalSettings(resolution=0.1, n_boot=10, peers=("octomap",), split_block=4, split_tile=0.5, loc_scans=8,
                       n_floors=0, thesis_scenes=("enclosed-train",), max_scans=40, loop_boot=50)


def test_a_tiny_run_end_to_end_agrees_with_the_library(tmp_path):
    from crfmap.assess.navigation import nav2_classes, wall_shape
    from crfmap.assess.scansplit import scan_split, score
    from crfstudy.splits import harder_splits
    from crfmap.crf.presets import get_preset
    from crfmap.io.carmen import read_carmen

    log = _line_log(tmp_path / "room.log")
    summaries, records, columns = ng.run({"room": log}, TINY, progress=False)
    assert list(columns) == ["room", "closed loop", "closed loop (refined on arrival)"]
    assert [v.goal for v in columns["room"]] == ["1a", "1b", "1c", "2a", "2b", "3", "4a", "4b", "5a", "5b", "5c", "6",
                                                "8a", "8b", "8c", "8d"]
    assert [v.goal for v in columns["closed loop"]] == ["7a", "7b", "7c"] and {r["scene"] for r in records} == {
        "enclosed-train"}
    s = summaries["room"]
    json.dumps(s)  # plain numbers: save_numbers and the goal rules read it
    scans = read_carmen(log).scans
    split = scan_split(scans, TINY.resolution)
    maps = {name: get_preset(name).refine(hits=split.first_hits, passes=split.first_passes).beliefs.probability
            for name in (D, gr.OLD_DEFAULT)}
    brier = score(split, maps, n_boot=0, groups=("all",), metrics=("brier",))
    assert s["brier_vs_certainty"]["diff"] == pytest.approx(brier[D]["all"]["brier"] - brier[gr.OLD_DEFAULT]["all"]["brier"])
    lo, hi = s["brier_vs_certainty"]["ci"]
    assert lo <= hi
    for name, p in (("raw", split.raw_probability()), (D, maps[D])):
        assert s["nav"][name]["map"]["thickness"] == pytest.approx(wall_shape(nav2_classes(p)[0], 0.1)["thickness"],
                                                                   nan_ok=True)
    # the harder split's opponent is the better calibrated model there, and the difference is the default minus it
    calibrators = ng.fit_calibrators(split)
    temporal = harder_splits(scans, TINY.resolution, block=TINY.split_block, tile=TINY.split_tile)["temporal halves"]
    h = s["harder"]["temporal halves"]
    mine = get_preset(D).refine(hits=temporal.first_hits, passes=temporal.first_passes).beliefs.probability
    model = calibrators[h["opponent"]]
    theirs = model.predict_split(temporal) if h["opponent"] == ng.CALIBRATED[0] else model.predict(temporal.raw_probability())
    b = score(temporal, {"d": mine, "o": theirs}, n_boot=0, groups=("all",), metrics=("brier",))
    assert h["diff"] == pytest.approx(b["d"]["all"]["brier"] - b["o"]["all"]["brier"])
    assert h["brier"][h["opponent"]] == min(h["brier"][c] for c in ng.CALIBRATED)
    assert set(s["localisation"]) == {"raw", D, gr.OLD_DEFAULT} and set(s["nav"]) == {"raw", D, gr.OLD_DEFAULT, "octomap"}


def test_the_command_refuses_an_unknown_recording_in_one_line(capsys):
    assert ng.main(["--quick", "nowhere"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nowhere" in err[0] and "intel" in err[0]


def _parameters():
    cells = json.loads(NOTEBOOK.read_text())["cells"]
    source = "".join(next(c for c in cells if "parameters" in c["metadata"].get("tags", []))["source"])
    return {node.targets[0].id: ast.literal_eval(node.value) for node in ast.parse(source).body}


def test_the_notebook_reads_the_registry_s_recordings_and_the_command_s_settings():
    from crfstudy.repro.dependencies import data_needed

    assert data_needed(NOTEBOOK) == sorted(ng.RECORDINGS.values())
    p = _parameters()
    assert p["quick"] is False
    full = ng.GoalSettings(resolution=p["resolution"], n_boot=p["n_boot"], block=p["block"], seed=p["seed"],
                           peers=tuple(x for x in PEERS if p["hilbert"] or x != "hilbert"),
                           split_block=p["split_block"], split_tile=p["split_tile"], loc_scans=p["loc_scans"],
                           n_floors=p["n_floors"], floor_size=(p["floor_width"], p["floor_height"]),
                           max_scans=p["max_scans"], loop_boot=p["loop_boot"])
    assert asdict(full) == asdict(ng.GoalSettings())  # the notebook's full run prints what the command prints


# ---- what notebook 12 reads from its helper ------------------------------------------------------------------------


def test_peer_rows_leave_out_only_the_hilbert_map_when_asked():
    assert ng.peer_rows() == PEERS and "hilbert" in PEERS
    assert ng.peer_rows(hilbert=False) == tuple(p for p in PEERS if p != "hilbert")
    assert ng.QUICK.peers == ng.peer_rows(hilbert=False)


def test_verdict_numbers_are_the_verdicts_as_plain_data_and_the_misses_named():
    columns = {"x": gr.recording_goals(gr.example_summary()), "loop": gr.closed_loop_goals(_records((50, 50, 50)))}
    verdicts, missed = ng.verdict_numbers(columns)
    json.dumps(verdicts)  # save_numbers writes them
    assert missed == {"x": ["1c", "8a"], "loop": ["7c"]}
    first = columns["x"][0]
    assert verdicts["x"][first.goal] == {"what": first.what, "verdict": first.status, "numbers": first.evidence}


def test_tradeoff_tables_caption_each_setting_with_what_it_moves():
    from crfstudy.analysis import tradeoff

    entry = {"value": 0.1, "diff": -0.01, "ci": [-0.02, 0.0], "interval_only": False, "met": True}
    scores = {r: {"v": dict({g: entry for g, *_ in tradeoff.SUBGOALS}, iterations=10, free_vs_raw=0.9)}
              for r in ("ros2", "ros1")}
    tables = ng.tradeoff_tables({"J": scores, "free_evidence": scores}, ng.QUICK)
    assert list(tables) == ["J", "free_evidence"]
    header, rows = tradeoff.tradeoff_table(scores)
    assert tables["J"]["header"] == header and tables["J"]["rows"] == rows
    assert "with the coupling J moved" in tables["J"]["caption"] and "(ros2, ros1)" in tables["J"]["caption"]
    assert f"({ng.QUICK.n_boot} resamples)" in tables["free_evidence"]["caption"]
    assert ng.TRADEOFF_MOVED["free_evidence"] in tables["free_evidence"]["caption"]


def test_the_tradeoff_loop_table_uses_the_goal_table_s_resamples_and_seed():
    from crfstudy.analysis import tradeoff

    records = [{"scene": s, "kind": k, "scans": scans + (k == "crf") * (i % 2), "plans_into_walls": 1,
                "dangerous_miss_rate": 0.01, "ghosts": 2}
               for i, (s, scans) in enumerate((("s1", 50), ("s2", 70), ("s3", 90))) for k in ("raw", "crf")]
    assert ng.tradeoff_loop_table(records, TINY) == tradeoff.closed_loop_table(records, n_boot=TINY.loop_boot,
                                                                                seed=TINY.seed)
