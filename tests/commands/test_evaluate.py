"""``crfmap evaluate``: the scan-split table of a recording, and one-line errors."""
import json
import re

import numpy as np
import pytest

from crfmap.cli import main
from crfmap.crf.presets import DEFAULT_PRESET as D  # the row of the default preset


def _room_log(path, n_scans=8, seed=0):
    """A CARMEN log of a laser turning in a 3 m x 2 m room with a pillar (181 beams over 180 degrees)."""
    rng = np.random.default_rng(seed)
    angles = np.linspace(-np.pi / 2, np.pi / 2, 181)
    lines = []
    for i in range(n_scans):
        x, y, yaw = 1.5 + 0.1 * rng.standard_normal(), 1.0 + 0.1 * rng.standard_normal(), 2 * np.pi * i / n_scans
        a = angles + yaw
        with np.errstate(divide="ignore"):
            tx = np.where(np.cos(a) > 0, (2.95 - x) / np.cos(a), (0.05 - x) / np.cos(a))
            ty = np.where(np.sin(a) > 0, (1.95 - y) / np.sin(a), (0.05 - y) / np.sin(a))
        r = np.minimum(np.abs(tx), np.abs(ty))
        ranges = " ".join(f"{v:.3f}" for v in r)
        lines.append(f"FLASER 181 {ranges} {x:.4f} {y:.4f} {yaw:.4f} {x:.4f} {y:.4f} {yaw:.4f} {i:.1f} host {i:.1f}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_evaluate_table_and_json_match_the_library(tmp_path, capsys):
    from crfmap.assess.baselines import BASELINES
    from crfmap.assess.comparison import compare
    from crfmap.assess.scansplit import scan_split
    from crfmap.io.carmen import read_carmen

    log = _room_log(tmp_path / "room.log")
    assert main(["evaluate", str(log), "--resolution", "0.1", "--boot", "5"]) == 0
    out = capsys.readouterr().out
    for name in (*BASELINES, D):  # every registered baseline row, then the default preset
        assert re.search(rf"^\| {name} +\|", out, re.M)
    assert main(["evaluate", str(log), "--resolution", "0.1", "--boot", "5", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    expected = compare(scan_split(read_carmen(log).scans, 0.1), n_boot=5)
    assert got[D]["all"]["brier"] == pytest.approx(expected[D]["all"]["brier"])
    assert got["raw"]["unseen"]["cells"] == expected["raw"]["unseen"]["cells"]


def test_evaluate_methods_select_rows_and_peers_are_in_the_json(tmp_path, capsys):
    log = _room_log(tmp_path / "room.log")
    common = [str(log), "--resolution", "0.1", "--boot", "5"]
    assert main(["evaluate", *common, "--methods", f"{D},octomap,hilbert"]) == 0
    out = capsys.readouterr().out
    for name in ("raw", D, "octomap", "hilbert"):
        assert re.search(rf"^\| {name} +\|", out, re.M)
    assert not re.search(r"^\| thesis +\|", out, re.M) and "peer wall time: octomap" in out
    assert main(["evaluate", *common, "--methods", "octomap,hilbert", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert set(got) == {"raw", "octomap", "hilbert", "_seconds", "_ece", "_nav", "_localisation"}
    assert got["_localisation"]["octomap"]["found_diff_ci"][0] <= got["_localisation"]["octomap"]["found_diff"] + 1e-12
    assert set(got["_nav"]) == {"raw", "octomap", "hilbert"}
    assert got["octomap"]["all"]["brier_ci"][0] <= got["octomap"]["all"]["brier"] <= got["octomap"]["all"]["brier_ci"][1]
    assert 0 <= got["_ece"]["hilbert"] <= 1
    assert main(["evaluate", *common, "--methods", f"{D},octomap", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    vs = got["_vs_preset"]["octomap"]["all"]
    assert vs["brier_diff"] == pytest.approx(got["octomap"]["all"]["brier"] - got[D]["all"]["brier"])
    assert main(["evaluate", *common, "--methods", "octomap,nope"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--methods" in err and "nope" in err


@pytest.mark.parametrize("args, words", [
    (["--boot", "-1"], ["--boot"]),
    (["--resolution", "0"], ["--resolution"]),
])
def test_evaluate_bad_options_one_line(tmp_path, capsys, args, words):
    log = _room_log(tmp_path / "room.log", n_scans=2)
    assert main(["evaluate", str(log)] + args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and all(w in err for w in words)


def test_evaluate_missing_file(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path / "nope.log")]) == 2
    assert "nope.log" in capsys.readouterr().err


def test_evaluate_prints_the_navigation_tables_from_the_json_numbers(tmp_path, capsys):
    log = _room_log(tmp_path / "room.log")
    common = [str(log), "--resolution", "0.1", "--boot", "5", "--methods", f"{D},mean3x3", "--group", "seen"]
    assert main(["evaluate", *common, "--json"]) == 0
    nav = json.loads(capsys.readouterr().out)["_nav"]
    assert main(["evaluate", *common]) == 0
    out = capsys.readouterr().out
    assert "nav2's reading of the written trinary map, seen cells" in out and re.search(r"\| dangerous misses % +\|", out)
    nav_part = out[out.index("nav2's reading"):]
    assert max(len(line) for line in nav_part.splitlines()) <= 120  # the localisation table too
    first_table = nav_part[:nav_part.index("walls of")]
    rows = {line.split("|")[1].strip(): line for line in first_table.splitlines() if line.startswith("| ")}
    entry = nav[D]["seen"]
    recall = f"{100 * entry['lethal_recall']:.2f} {100 * entry['lethal_recall_diff_ci'][0]:+.1f}.."
    assert recall in rows[D]
    assert re.search(rf"^\| raw +\| {100 * nav['raw']['seen']['lethal_recall']:.2f} +\| ", out, re.M)
    assert re.search(rf"\| {nav[D]['map']['thickness']:.2f} +\|", out)
    assert main(["evaluate", *common, "--json", "--no-nav"]) == 0
    assert "_nav" not in json.loads(capsys.readouterr().out)
