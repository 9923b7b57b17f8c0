"""crfstudy.experiments.beyond (notebook 10): its tables and goals from the scores they report, the peers' rows
scored and calibrated (no NaN ECE), the cached peers, and its figures (a metric (J, K) diagram, before/after maps)."""
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

from crfmap.assess.baselines import all_baselines
from crfmap.assess.calibration import expected_calibration_error
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfstudy.experiments import beyond

from box_scans import scans_in_a_box

matplotlib.use("Agg")


def _split(seed=0, shape=(24, 24)):
    rng = np.random.default_rng(seed)
    walls = np.zeros(shape, bool)
    walls[:, 8] = walls[12, :] = True
    first_hits = np.where(walls, rng.integers(0, 4, shape), rng.integers(0, 2, shape) * (rng.random(shape) < 0.1))
    first_passes = np.where(walls, rng.integers(0, 2, shape), rng.integers(0, 4, shape))
    second_hits = np.where(walls, rng.integers(0, 4, shape), (rng.random(shape) < 0.05).astype(int))
    second_passes = np.where(walls, rng.integers(0, 2, shape), rng.integers(0, 4, shape))
    return ScanSplit(first_hits, first_passes, second_hits, second_passes, resolution=0.1)


def test_score_all_calibrates_every_row_of_the_table():
    sp = _split()
    preds = all_baselines(sp, names=["raw", "mean3x3", "thesis", "graphcut"])
    preds.update(beyond.preset_rows(sp))  # the analysed model and the default preset
    preds["octomap"] = np.clip(sp.raw_probability() * 0.9 + 0.05, 0, 1)  # stands in for a peer's map
    # the log-odds row needs scans: any grid of P stands in for it here
    preds["logodds"] = np.where(sp.first_hits > sp.first_passes, 0.8, np.where(sp.first_passes > 0, 0.2, 0.5))
    result = beyond.score_all(sp, preds, n_boot=10, block=4, seed=0, temperature=0.8)
    rows = set(preds) - {"mean3x3"} | {f"{beyond.ANALYSED}-T"}  # mean3x3 is no table row
    assert set(result["scores"]) == rows and set(result["calibration"]) == rows
    mask, labels = sp.group("all"), sp.labels()[sp.group("all")]
    for name in ("logodds", "thesis", "graphcut", "raw"):
        assert result["calibration"][name]["ece"] == pytest.approx(expected_calibration_error(preds[name][mask], labels))
    table = beyond.peer_table("synthetic", result, {"octomap": 1.0})
    ece_column = table["header"].index("ECE")
    eces = {row[0]: row[ece_column] for row in table["rows"]}
    assert set(eces) == rows and all(np.isfinite(v) and 0 <= v <= 1 for v in eces.values()), eces


def test_the_table_pairs_every_row_with_each_preset_row():
    sp = _split(seed=3)
    preds = all_baselines(sp, names=["raw", "thesis"])
    presets = beyond.preset_rows(sp)
    assert set(presets) == {"certainty", DEFAULT_PRESET} and beyond.ANALYSED == "certainty"
    for name, p in presets.items():  # each row is the preset as users run it
        np.testing.assert_array_equal(p, get_preset(name).refine(hits=sp.first_hits, passes=sp.first_passes)
                                      .beliefs.probability)
    preds.update(presets)
    preds["octomap"] = np.clip(sp.raw_probability() * 0.8 + 0.1, 0, 1)
    result = beyond.score_all(sp, preds, n_boot=10, block=4, seed=1)
    assert list(result["versus"]) == list(beyond.PRESET_ROWS) and result["scores"] is result["versus"]["certainty"]
    table = beyond.peer_table("synthetic", result, {})
    header = table["header"]
    brier = {row[0]: row[1] for row in table["rows"]}
    for ref in beyond.PRESET_ROWS:
        column = header.index(f"minus {ref}, 95% CI")
        for row in table["rows"]:
            diff = float(row[column].split(" ")[0])
            assert diff == pytest.approx(brier[row[0]] - brier[ref], abs=6e-5), (ref, row[0])
    sentence = beyond.peer_sentence("synthetic", result, "octomap", preset=DEFAULT_PRESET)
    assert sentence.startswith(f"synthetic, octomap vs {DEFAULT_PRESET} (Brier): all observed cells: "
                               f"{brier['octomap']:.4f} vs {brier[DEFAULT_PRESET]:.4f}")


def _room_split(n_scans=16):
    """The scan split of a laser turning in a 3 m x 2 m room (CARMEN-free: a ScanSet made here)."""
    from crfmap.assess.scansplit import scan_split
    from crfmap.recording import ScanSet

    angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
    poses = np.array([[1.5, 1.0, 2 * np.pi * i / n_scans] for i in range(n_scans)])
    ranges = []
    for x, y, yaw in poses:
        a = angles + yaw
        with np.errstate(divide="ignore"):
            tx = np.where(np.cos(a) > 0, (2.95 - x) / np.cos(a), (0.05 - x) / np.cos(a))
            ty = np.where(np.sin(a) > 0, (1.95 - y) / np.sin(a), (0.05 - y) / np.sin(a))
        ranges.append(np.minimum(np.abs(tx), np.abs(ty)))
    scans = ScanSet(np.array(ranges, np.float32), -np.pi / 2, np.pi / 180, 0.05, 8.0, poses, np.arange(n_scans, dtype=float))
    return scan_split(scans, 0.1)


def test_quick_peer_settings_are_lighter_and_cached_apart_from_the_full_ones(tmp_path, monkeypatch):
    from crfstudy import paths
    from crfmap.assess.peers import peer_rows
    from crfmap.mapping.hilbert import hilbert_grid

    monkeypatch.setattr(paths, "OUT", tmp_path)
    sp = _room_split()
    full, _ = beyond.cached_peer_rows("room", sp)
    expected, _ = peer_rows(sp, ["octomap", "hilbert"])
    for name in ("octomap", "hilbert"):  # the full settings are the peers as they were
        np.testing.assert_array_equal(full[name], expected[name])
    quick, _ = beyond.cached_peer_rows("room", sp, quick=True)
    np.testing.assert_array_equal(quick["octomap"], full["octomap"])  # OctoMap is cheap: every scan in both
    q = beyond.QUICK
    light = hilbert_grid(sp.first_scans.every(q.hilbert_scan_step), sp.resolution, sp.bounds, **q.hilbert_options())
    assert light.meta["scans"] == len(sp.first_scans) // q.hilbert_scan_step < len(sp.first_scans)
    np.testing.assert_array_equal(quick["hilbert"], light.probability)
    assert not np.array_equal(quick["hilbert"], full["hilbert"])
    assert len(list((tmp_path / "cache" / "peers").glob("room-hilbert-*.npz"))) == 2  # one file per setting
    again, _ = beyond.cached_peer_rows("room", sp, quick=True)  # read back from the cache
    np.testing.assert_array_equal(again["hilbert"], quick["hilbert"])


def test_phase_diagram_draws_unevenly_spaced_couplings_where_they_lie():
    couplings, strengths = [0.0, 0.1, 0.44, 1.15], [0.5, 2.0]
    d = {"intel": {"brier": np.arange(8.0).reshape(4, 2), "wall_recall": np.ones((4, 2))}}
    fig = beyond.phase_diagram_figure(d, couplings, strengths, critical=0.4407)
    ax = fig.axes[0]
    assert [t for t in ax.get_xticks()] == couplings  # ticks at the values, not at their indices
    assert np.allclose(ax.get_xlim(), (-0.05, 1.505))  # half a step beyond the first and last samples
    (line,) = ax.get_lines()
    assert line.get_xdata()[0] == 0.4407
    mesh = ax.collections[0]
    assert np.array_equal(np.asarray(mesh.get_array()).reshape(2, 4), d["intel"]["brier"].T)


def test_before_after_has_one_colour_bar_and_the_zoomed_square_below_each_map():
    p = np.full((500, 600), 0.5)
    p[200, 100:500] = 0.9
    fig = beyond.before_after_figure({"raw": p, "refined": p}, "intel", (150, 250, 200, 300))
    maps = [ax for ax in fig.axes if ax.get_title().startswith("intel: ")]
    zooms = [ax for ax in fig.axes if ax.get_title() == "the outlined square, every cell"]
    assert len(maps) == 2 and len(zooms) == 2
    assert len([ax for ax in fig.axes if ax.get_xlabel() == "P(occupied)"]) == 1
    for ax, zoom in zip(maps, zooms):
        (outline,) = ax.patches
        assert outline.get_xy() == (199.5, 149.5) and (outline.get_width(), outline.get_height()) == (100, 100)
        (image,) = zoom.get_images()
        assert image.get_array().shape == (100, 100)  # every cell of the window, not pooled
        assert image.get_extent() == [199.5, 299.5, 149.5, 249.5]


def test_densest_window_finds_the_walls():
    walls = np.zeros((300, 400), bool)
    walls[250:260, 330:390] = True
    y0, y1, x0, x1 = beyond.densest_window(walls, 80)
    assert y0 <= 250 and y1 >= 260 and x0 <= 330 and x1 >= 390 and (y1 - y0, x1 - x0) == (80, 80)


# ---- the study's tables and goals --------------------------------------------------------------------------------------
def _corridor_recording(n_scans=12, length=3.0):
    """A laser walking along a corridor ``length`` m x 1 m (a recording as load_recording gives: ``.scans``)."""
    poses = np.column_stack([np.linspace(0.3, length - 0.3, n_scans), np.full(n_scans, 0.5), np.zeros(n_scans)])
    return SimpleNamespace(scans=scans_in_a_box(poses, (0.05, 0.05, length - 0.05, 0.95), 60))


def _results(splits, n_boot=10):
    from crfmap.assess import compare

    rows = ["raw", "logodds", "thesis", "certainty"]
    return {name: compare(sp, "certainty", n_boot=n_boot, block=4, seed=0, methods=rows, keep_beliefs=True, nav=False)
            for name, sp in splits.items()}


def test_phase_diagrams_run_the_training_recording_first_and_keep_its_best_table_everywhere():
    splits = {"a": _split(1), "train": _split(2), "b": _split(3)}
    diagrams = beyond.phase_diagrams(splits, "train", [0.1, 0.6], [0.5, 2.0], tol=1e-4)
    assert list(diagrams) == ["a", "train", "b"]  # the recordings' order, training run first
    best = diagrams["train"]["best"]
    for name, d in diagrams.items():
        assert best in d["beliefs"] and d["best"] in d["beliefs"]
        assert d["brier"][[0.1, 0.6].index(d["best"][0]), [0.5, 2.0].index(d["best"][1])] == np.nanmin(d["brier"])


def test_scansplit_tables_hold_every_scored_row_and_say_where_a_recording_was_not_run():
    splits = {"ros2": _split(4), "ros1": _split(5)}
    results = _results(splits)
    tables = beyond.scansplit_tables(results, ("intel", "ros2", "ros1"), {"ros2": "confirmation", "ros1": "x"},
                                     resolution=0.1, n_boot=10, block=4, seed=0)
    assert tables["intel"]["rows"][0][0] == "(not run in quick mode)" and "intel" in tables["intel"]["caption"]
    for name in splits:
        rows = {r[0]: r for r in tables[name]["rows"]}
        assert set(rows) == {m for m in results[name] if not m.startswith("_")}  # kept grids are no rows
        for method, row in rows.items():
            g = results[name][method]
            lo, hi = g["all"]["brier_ci"]
            assert row[1] == g["all"]["brier"] and row[2] == f"[{lo:.4f}, {hi:.4f}]"
            assert float(row[4].split(" ")[0]) == pytest.approx(g["seen"]["brier_diff"], abs=5e-5)
        assert rows["raw"][4].startswith("+0.0000")  # the raw grid against itself
        summary = beyond.table_summary(tables[name])
        assert len(summary.splitlines()) == len(rows) and "certainty" in summary


def _entry(brier, diff, ci=None, **more):
    return {"brier": brier, "brier_diff": diff, "brier_diff_ci": ci, "wall_recall": more.get("recall", 0.5),
            "logloss": more.get("logloss", 0.3)}


def _goal_result(certainty_all, ci):
    raw = {g: _entry(0.10, 0.0, (0.0, 0.0), recall=0.6) for g in ("all", "seen", "unseen")}
    certainty = {"all": _entry(certainty_all, certainty_all - 0.10, ci, recall=0.7),
                 "seen": _entry(0.09, -0.01, (-0.02, 0.001)), "unseen": _entry(0.2, 0.0)}
    better = {g: _entry(0.05, -0.05) for g in ("all", "seen", "unseen")}  # a row better everywhere
    worse = {g: _entry(0.5, 0.4) for g in ("all", "seen", "unseen")}
    return {"raw": raw, "certainty": certainty, "certainty-MAP": better, "gated": worse, "mean3x3": better,
            "_beliefs": {}}


def test_recording_goals_read_the_interval_and_every_other_row():
    goals = beyond.recording_goals(_goal_result(0.08, (-0.03, -0.01)), "training", n_boot=10, default="gated")
    assert goals["role"] == "training" and goals["lower_brier_all"] and goals["walls_kept"]
    assert goals["baselines_better_all"] == ["mean3x3"]  # the preset's own MAP decoding is no competitor
    assert not goals["beats_every_baseline_all"] and goals["not_worse_seen"]
    assert not goals["lower_brier_unseen"]  # 0.2 against the raw grid's 0.1
    assert goals["default"]["preset"] == "gated" and goals["default"]["brier_all"] == 0.5
    straddles = beyond.recording_goals(_goal_result(0.08, (-0.03, 0.01)), "x", n_boot=10, default="gated")
    assert not straddles["lower_brier_all"]  # the point estimate is lower, the interval is not below zero
    unresampled = beyond.recording_goals(_goal_result(0.08, None), "x", n_boot=0, default="gated")
    assert unresampled["lower_brier_all"]  # without resamples: the point estimate


def test_transfer_tables_read_each_learned_pair_on_every_recording():
    from crfmap.crf import get_preset
    from crfstudy.analysis import modelspace

    splits = {"a": _split(6), "b": _split(7)}
    results = _results(splits, n_boot=0)
    rows_scaled, rows_pl, learned = beyond.transfer_tables(splits, results, get_preset("certainty"), [0.2, 0.4],
                                                           [1.0], steps=5)
    assert [len(r) for r in rows_scaled] == [3] * 4 and [len(r) for r in rows_pl] == [3] * 2
    for row, train in zip(rows_scaled, splits):
        J, s = learned[train]
        assert row[0] == f"{train} (J={J:g}, scale={s:g})"
        assert row[1:] == [modelspace.scaled_scores(sp, [J], [s])[(J, s)] for sp in splits.values()]
    assert rows_scaled[-1] == ["raw grid"] + [results[n]["raw"]["all"]["brier"] for n in splits]
    assert rows_scaled[-2][1:] == [results[n]["certainty"]["all"]["brier"] for n in splits]
    assert all(0 <= v <= 1 for row in rows_pl for v in row[1:])


def _fake_search():
    return {"best": {"coupling": 0.35, "margin": 5}, "best_brier": 0.0421, "rounds": 2, "converged": True,
            "configurations": 3, "grid": {"coupling": [0.3, 0.35], "margin": [5]}, "start": {"coupling": 0.3},
            "order": ["coupling", "margin"], "recording": "intel", "resolution_m": 0.05,
            "trace": [{"round": 1, "coordinate": "coupling", "coupling": 0.3, "margin": 5, "brier": 0.05},
                      {"round": 1, "coordinate": "coupling", "coupling": 0.35, "margin": 5, "brier": 0.0421}]}


def test_the_preset_search_report_checks_the_cache_against_todays_code(monkeypatch):
    from crfstudy.analysis import preset_search

    monkeypatch.setattr(preset_search, "load_cached", _fake_search)
    monkeypatch.setattr(preset_search, "preset_constants", lambda preset: {"coupling": 0.35, "margin": 4})
    results = {"intel": {"certainty": {"all": {"brier": 0.0425}}}}
    report = beyond.preset_search_report(None, {}, results, resolution=0.05)  # Intel not run: nothing to check
    assert report["numbers"]["check"] == {} and report["numbers"]["differs"] == {"margin": {"preset": 4, "search": 5}}
    assert report["table"]["rows"] == [[1, "coupling", 0.3, 5, 0.05], [1, "coupling", 0.35, 5, 0.0421]]
    monkeypatch.setattr(preset_search, "search_brier", lambda split, best: 0.0421)
    checked = beyond.preset_search_report(None, {"intel": "split"}, results, resolution=0.05)["numbers"]["check"]
    assert checked["preset_minus_search_best"] == pytest.approx(0.0004)
    assert beyond.preset_search_report(None, {"intel": "split"}, results, resolution=0.1)["numbers"]["check"] == {}
    monkeypatch.setattr(preset_search, "search_brier", lambda split, best: 0.0500)  # the code moved on
    with pytest.raises(AssertionError, match="stale preset search cache"):
        beyond.preset_search_report(None, {"intel": "split"}, results, resolution=0.05)


def test_ablations_and_harder_splits_are_tabled_from_their_scores():
    from crfmap.assess import scan_split
    from crfmap.crf import get_preset

    recordings = {"long": _corridor_recording(16, 4.0), "short": _corridor_recording(12, 3.0)}
    splits = {name: scan_split(rec.scans, 0.1) for name, rec in recordings.items()}
    results = _results(splits)
    study = beyond.ablation_study(splits, results, "long", n_boot=10, block=4, seed=0)
    assert study["calibration"]["fitted_on"] == "long" and set(study["logodds_parameters"]) == {
        "p_hit", "p_miss", "logodds_limit"}
    table, numbers = beyond.ablation_table(study, "long", 0.1, 10, 4)
    assert len(table["rows"]) == sum(len(p) for p in study["predictions"].values())
    for name, per_method in numbers.items():
        assert per_method["raw"]["all"]["minus_raw"] == 0 and per_method["certainty"]["all"]["minus_certainty"] == 0
        assert per_method["certainty"]["all"]["minus_raw"] == pytest.approx(
            per_method["certainty"]["all"]["brier"] - per_method["raw"]["all"]["brier"])
    harder = beyond.harder_split_scores(recordings, study, get_preset("certainty"), 0.1, n_boot=10, block=4, seed=0,
                                        split_block=3, split_tile=1.0)
    assert all(list(kinds)[0] == "even/odd" and len(kinds) == 4 for kinds in harder.values())
    block_check = beyond.block_sensitivity(splits, study, (4, 8), n_boot=10, seed=0)
    splits_table, blocks_table = beyond.split_tables(harder, block_check, 10, 4, 0, 3, 1.0)
    assert len(splits_table["rows"]) == 2 * 4 * 3 and len(blocks_table["rows"]) == 2 * 2
    counts = beyond.split_counts(harder)
    assert counts["cases"] == 2 * 3
    seen = [kinds[k]["certainty"]["vs_raw"]["seen"]["diff"] for kinds in harder.values() for k in kinds
            if k != "even/odd"]
    assert counts["certainty_vs_raw_seen"]["lower"] == sum(d < 0 for d in seen)


def test_split_counts_count_lower_and_significant_cases_apart_from_even_odd():
    def case(diff, ci):
        head = {"diff": diff, "ci": ci}
        groups = {"all": head, "seen": head, "unseen": head}
        return {"certainty": {"vs_raw": groups}, "isotonic on x": {"vs_certainty": groups}}

    harder = {"r": {"even/odd": case(-1.0, (-2.0, -0.5)), "temporal": case(-0.1, (-0.2, 0.1)),
                    "tiles": case(-0.1, (-0.2, -0.05)), "blocks": case(0.2, None)}}
    counts = beyond.split_counts(harder)
    assert counts["cases"] == 3
    assert counts["certainty_vs_raw_all"] == {"lower": 2, "significant": 1}


def test_peer_recordings_in_quick_mode_add_the_peers_to_the_kept_rows(tmp_path, monkeypatch):
    from crfstudy import paths

    monkeypatch.setattr(paths, "OUT", tmp_path)
    splits = {"room": _room_split()}
    results = _results(splits, n_boot=0)
    peer_splits, roles, beliefs, seconds = beyond.peer_recordings(splits, {"room": "training"}, results, 0.1,
                                                                  quick=True)
    assert list(peer_splits) == ["room"] and roles == {"room": "training"}  # quick: no more buildings
    assert {"raw", "certainty", "octomap", "hilbert"} <= set(beliefs["room"]) and set(seconds["room"]) == {
        "octomap", "hilbert"}
    result = beyond.score_all(splits["room"], beliefs["room"], n_boot=0, block=4, seed=0)
    table = beyond.peers_table({"room": beyond.peer_table("room", result, seconds["room"])}, "room")
    assert table["header"][0] == "recording" and all(row[0] == "room" for row in table["rows"])
    numbers = beyond.peer_numbers({"room": result}, default="certainty")
    assert set(numbers["ece"]["room"]) == set(result["calibration"])
    assert numbers["versus_default"]["room"]["octomap"]["all"]["brier_diff"] == result["scores"]["octomap"]["all"][
        "brier_diff"]
