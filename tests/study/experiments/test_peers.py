"""Notebook 10's peers report: every row of the table is scored and calibrated (no NaN ECE)."""
import numpy as np
import pytest

from crfmap.assess.baselines import all_baselines
from crfmap.assess.calibration import expected_calibration_error
from crfmap.assess.scansplit import ScanSplit
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfstudy.experiments import peers as peer_report


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
    preds.update(peer_report.preset_rows(sp))  # the analysed model and the default preset
    preds["octomap"] = np.clip(sp.raw_probability() * 0.9 + 0.05, 0, 1)  # stands in for a peer's map
    # the log-odds row needs scans: any grid of P stands in for it here
    preds["logodds"] = np.where(sp.first_hits > sp.first_passes, 0.8, np.where(sp.first_passes > 0, 0.2, 0.5))
    result = peer_report.score_all(sp, preds, n_boot=10, block=4, seed=0, temperature=0.8)
    rows = set(preds) - {"mean3x3"} | {f"{peer_report.ANALYSED}-T"}  # mean3x3 is no table row
    assert set(result["scores"]) == rows and set(result["calibration"]) == rows
    mask, labels = sp.group("all"), sp.labels()[sp.group("all")]
    for name in ("logodds", "thesis", "graphcut", "raw"):
        assert result["calibration"][name]["ece"] == pytest.approx(expected_calibration_error(preds[name][mask], labels))
    table = peer_report.peer_table("synthetic", result, {"octomap": 1.0})
    ece_column = table["header"].index("ECE")
    eces = {row[0]: row[ece_column] for row in table["rows"]}
    assert set(eces) == rows and all(np.isfinite(v) and 0 <= v <= 1 for v in eces.values()), eces


def test_the_table_pairs_every_row_with_each_preset_row():
    sp = _split(seed=3)
    preds = all_baselines(sp, names=["raw", "thesis"])
    presets = peer_report.preset_rows(sp)
    assert set(presets) == {"certainty", DEFAULT_PRESET} and peer_report.ANALYSED == "certainty"
    for name, p in presets.items():  # each row is the preset as users run it
        np.testing.assert_array_equal(p, get_preset(name).refine(hits=sp.first_hits, passes=sp.first_passes)
                                      .beliefs.probability)
    preds.update(presets)
    preds["octomap"] = np.clip(sp.raw_probability() * 0.8 + 0.1, 0, 1)
    result = peer_report.score_all(sp, preds, n_boot=10, block=4, seed=1)
    assert list(result["versus"]) == list(peer_report.PRESET_ROWS) and result["scores"] is result["versus"]["certainty"]
    table = peer_report.peer_table("synthetic", result, {})
    header = table["header"]
    brier = {row[0]: row[1] for row in table["rows"]}
    for ref in peer_report.PRESET_ROWS:
        column = header.index(f"minus {ref}, 95% CI")
        for row in table["rows"]:
            diff = float(row[column].split(" ")[0])
            assert diff == pytest.approx(brier[row[0]] - brier[ref], abs=6e-5), (ref, row[0])
    sentence = peer_report.peer_sentence("synthetic", result, "octomap", preset=DEFAULT_PRESET)
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
    full, _ = peer_report.cached_peer_rows("room", sp)
    expected, _ = peer_rows(sp, ["octomap", "hilbert"])
    for name in ("octomap", "hilbert"):  # the full settings are the peers as they were
        np.testing.assert_array_equal(full[name], expected[name])
    quick, _ = peer_report.cached_peer_rows("room", sp, quick=True)
    np.testing.assert_array_equal(quick["octomap"], full["octomap"])  # OctoMap is cheap: every scan in both
    q = peer_report.QUICK
    light = hilbert_grid(sp.first_scans.every(q.hilbert_scan_step), sp.resolution, sp.bounds, **q.hilbert_options())
    assert light.meta["scans"] == len(sp.first_scans) // q.hilbert_scan_step < len(sp.first_scans)
    np.testing.assert_array_equal(quick["hilbert"], light.probability)
    assert not np.array_equal(quick["hilbert"], full["hilbert"])
    assert len(list((tmp_path / "cache" / "peers").glob("room-hilbert-*.npz"))) == 2  # one file per setting
    again, _ = peer_report.cached_peer_rows("room", sp, quick=True)  # read back from the cache
    np.testing.assert_array_equal(again["hilbert"], quick["hilbert"])
