"""The infer and metrics commands: results, one-line errors with exit status 2, nothing half-written."""
import json
from dataclasses import replace

import numpy as np
import pytest

from crfmap.cli import main
from crfmap.io.grid_files import load_grid, save_grid
from crfmap.grid import OccupancyGrid
from crfmap.crf.inference.lbp import infer
from crfmap.data import data_file, have_data
from crfmap.crf.presets import DEFAULT_PRESET, get_preset
from crfmap.io.map_server import load_map

OLIN = "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml"


def noisy_grid(seed=0):
    rng = np.random.default_rng(seed)
    truth = np.zeros((24, 30))
    truth[5:19, 10] = 1
    truth[12, 3:27] = 1
    obs = np.clip(truth + rng.normal(0, 0.3, truth.shape), 0, 1)
    return OccupancyGrid(obs, resolution=0.05, origin=(1.0, 2.0, 0.0)), OccupancyGrid(truth, resolution=0.05)


def test_infer_npy_matches_library_and_keeps_metadata(tmp_path, capsys):
    grid, _ = noisy_grid()
    save_grid(grid, tmp_path / "in.npy")
    rc = main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy"), "--hidden", "5,1,1,5", "--tol", "1e-9"])
    assert rc == 0
    line = capsys.readouterr().out
    assert "converged" in line and "iterations" in line
    out = load_grid(tmp_path / "out.npy")
    expected = infer(grid, [[5, 1], [1, 5]], tol=1e-9).beliefs.probability
    np.testing.assert_allclose(out.probability, expected)
    assert out.resolution == 0.05 and out.origin == (1.0, 2.0, 0.0)


def test_infer_thesis_two_iterations(tmp_path, capsys):
    grid, _ = noisy_grid(1)
    save_grid(grid, tmp_path / "in.npy")
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy"), "--schedule", "thesis",
                 "--max-iter", "2", "--preset", "thesis"]) == 0
    assert "2 iterations" in capsys.readouterr().out
    expected = infer(grid, schedule="thesis", max_iter=2).beliefs.probability
    np.testing.assert_allclose(load_grid(tmp_path / "out.npy").probability, expected)


def test_infer_margin_keeps_far_unknown_cells(tmp_path):
    p = np.full((20, 40), 0.5)
    p[8:12, 2:6] = 0.9
    save_grid(OccupancyGrid(p), tmp_path / "in.npy")
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy"), "--margin", "3"]) == 0
    out = load_grid(tmp_path / "out.npy").probability
    # never observed, near or far: the default's beliefs give them the building's rate (its prior) ...
    prior = get_preset().gate.unobserved_prior
    np.testing.assert_allclose(out[:, 12:], prior, rtol=1e-9)
    # ... and its map for nav2 reads them unknown (-1), near the observed block or far from it
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.yaml"), "--margin", "3"]) == 0
    seen_by_nav2 = load_map(tmp_path / "out.yaml").to_int8()
    assert np.all(seen_by_nav2[:, 12:] == -1) and seen_by_nav2[10, 7] == -1
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "c.npy"), "--margin", "3", "--preset",
                 "certainty"]) == 0
    certainty = load_grid(tmp_path / "c.npy").probability
    assert np.all(certainty[:, 12:] == 0.5) and certainty[10, 7] > 0.5  # the ungated model fills it from the neighbours


def test_infer_default_is_the_default_preset(tmp_path):
    from crfmap.crf.presets import DEFAULT_PRESET, get_preset

    grid, _ = noisy_grid(3)
    save_grid(grid, tmp_path / "in.npy")
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy")]) == 0
    expected = get_preset(DEFAULT_PRESET).refine(grid, max_iter=1000).beliefs.probability
    np.testing.assert_array_equal(load_grid(tmp_path / "out.npy").probability, expected)


@pytest.mark.parametrize("argv, preset", [
    (["--preset", "thesis"], lambda P: P.get_preset("thesis")),
    (["--preset", "thesis", "--margin", "2"], lambda P: replace(P.get_preset("thesis"), margin=2)),
    (["--hidden", "4,1,1,4", "--margin", "2"], lambda P: P.custom_preset([[4, 1], [1, 4]], margin=2)),
    (["--hidden", "10,1,2,10", "--pairing", "oriented"], lambda P: P.custom_preset([[10, 1], [2, 10]], pairing="oriented")),
])
def test_infer_runs_a_preset_named_or_made_from_the_tables(tmp_path, argv, preset):
    from crfmap.crf import presets

    grid, _ = noisy_grid(4)
    save_grid(grid, tmp_path / "in.npy")
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy"), *argv]) == 0
    expected = preset(presets).refine(grid).beliefs.probability
    np.testing.assert_array_equal(load_grid(tmp_path / "out.npy").probability, expected)


def test_metrics_json(tmp_path, capsys):
    grid, truth = noisy_grid(2)
    save_grid(grid, tmp_path / "p.npy")
    save_grid(truth, tmp_path / "t.npy")
    assert main(["metrics", str(tmp_path / "p.npy"), str(tmp_path / "t.npy"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert set(d) >= {"mse", "precision", "recall", "accuracy", "auc"}
    assert d["mse"] == pytest.approx(float(np.mean((grid.probability - truth.probability) ** 2)))


@pytest.mark.skipif(not have_data(OLIN), reason="Olin map not in the data folder")
def test_infer_refines_the_real_olin_map(tmp_path, capsys):
    out = tmp_path / "refined.yaml"
    rc = main(["infer", str(data_file(OLIN)), str(out), "--free-thresh", "0.196", "--margin", "5",
               "--max-iter", "30", "--float32"])
    assert rc == 0
    refined = load_grid(out)
    original = load_grid(data_file(OLIN))
    assert refined.shape == original.shape and refined.origin == original.origin
    assert refined.resolution == original.resolution
    # it reloads identically when written again
    save_grid(refined, tmp_path / "again.yaml")
    np.testing.assert_array_equal(load_grid(tmp_path / "again.yaml").probability, refined.probability)


def _bad(tmp_path):
    good = tmp_path / "good.npy"
    save_grid(OccupancyGrid(np.full((4, 4), 0.5)), good)
    np.save(tmp_path / "nan.npy", np.array([[0.5, np.nan]]))
    np.save(tmp_path / "range.npy", np.array([[0.5, 2.0]]))
    np.save(tmp_path / "three_d.npy", np.zeros((2, 2, 2)))
    np.save(tmp_path / "ints.npy", np.zeros((2, 2), dtype=np.int64))
    np.save(tmp_path / "other.npy", np.full((3, 3), 0.5))
    (tmp_path / "broken.yaml").write_text("image: x.pgm\nresolution: [\n")
    (tmp_path / "nokey.yaml").write_text("image: x.pgm\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.2\n")
    return good


@pytest.mark.parametrize("args, words", [
    (["infer", "{d}/missing.npy", "{d}/o.npy"], ["missing.npy"]),
    (["infer", "{d}/nan.npy", "{d}/o.npy"], ["nan.npy", "NaN"]),
    (["infer", "{d}/range.npy", "{d}/o.npy"], ["range.npy"]),
    (["infer", "{d}/three_d.npy", "{d}/o.npy"], ["three_d.npy", "2-D"]),
    (["infer", "{d}/ints.npy", "{d}/o.npy"], ["ints.npy", "float"]),
    (["infer", "{d}/broken.yaml", "{d}/o.npy"], ["broken.yaml"]),
    (["infer", "{d}/nokey.yaml", "{d}/o.npy"], ["nokey.yaml", "resolution"]),
    (["infer", "{d}/good.npy", "{d}/o.npy", "--hidden", "1,-2,1,1"], ["--hidden", "non-negative"]),
    (["infer", "{d}/good.npy", "{d}/o.npy", "--link", "0,0,1,1"], ["--link", "all zero"]),
    (["infer", "{d}/good.npy", "{d}/o.txt"], ["o.txt"]),
    (["infer", "{d}/good.npy", "{d}/o.npy", "--pairing", "oriented"], ["--pairing", f"{DEFAULT_PRESET} preset"]),
    (["infer", "{d}/good.npy", "{d}/o.npy", "--preset", "thesis", "--pairing", "receiver"], ["--pairing", "thesis"]),
    (["infer", "{d}/good.npy", "{d}/o.npy", "--preset", "thesis", "--hidden", "4,1,1,4"], ["--preset", "custom"]),
    (["metrics", "{d}/good.npy", "{d}/other.npy"], ["shape"]),
])
def test_bad_input_is_one_line_exit_2_and_no_output(tmp_path, capsys, args, words):
    _bad(tmp_path)
    rc = main([a.format(d=tmp_path) for a in args])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for w in words:
        assert w in err
    assert not (tmp_path / "o.npy").exists() and not (tmp_path / "o.txt").exists()
    assert not list(tmp_path.glob(".*tmp"))


@pytest.mark.parametrize("argv", [["simulate", "nope", "out"], ["infer"], [], ["infer", "a.npy", "b.npy", "--max-iter", "x"],
                                  ["infer", "a.npy", "b.npy", "--preset", "nope"]])
def test_usage_errors_are_one_line(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "error" in err


def test_choices_and_help_come_from_the_registries(capsys):
    """The CLI lists what the registries hold (a new preset, schedule, baseline or peer appears without a CLI edit)."""
    from crfmap.assess.baselines import BASELINES
    from crfmap.assess.peers import PEERS
    from crfmap.cli import build_parser
    from crfmap.crf.inference.schedules import SETTINGS
    from crfmap.crf.presets import PRESETS

    sub = next(a for a in build_parser()._actions if a.dest == "command").choices
    infer = {a.dest: a for a in sub["infer"]._actions}
    assert list(infer["preset"].choices) == list(PRESETS) and list(infer["schedule"].choices) == list(SETTINGS)
    assert all(p.purpose in infer["preset"].help for p in PRESETS.values())
    evaluate = {a.dest: a for a in sub["evaluate"]._actions}
    assert list(evaluate["preset"].choices) == list(PRESETS)
    assert all(name in evaluate["methods"].help for name in list(BASELINES) + list(PEERS))


def _humble_map(folder, free_thresh="0.25"):
    """A trinary map as Humble's map_saver writes it: 254 free, 0 occupied, 205 unknown, free_thresh 0.25."""
    from PIL import Image

    grey = np.full((12, 16), 205, np.uint8)
    grey[3:9, 3:13] = 254
    grey[3, 3:13] = 0
    Image.fromarray(grey).save(folder / "humble.pgm")
    (folder / "humble.yaml").write_text("image: humble.pgm\nmode: trinary\nresolution: 0.05\norigin: [0, 0, 0]\n"
                                        f"negate: 0\noccupied_thresh: 0.65\nfree_thresh: {free_thresh}\n")
    return folder / "humble.yaml", int((grey == 205).sum())


def _unknown(path):
    return int((load_grid(path).to_int8() == -1).sum())


def test_infer_keeps_a_humble_maps_unknown_cells_unknown_and_says_so(tmp_path, capsys):
    path, grey = _humble_map(tmp_path)
    assert _unknown(path) == 0  # nav2's reading of the file: every unknown grey is free
    assert main(["infer", str(path), str(tmp_path / "kept.yaml")]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("compiling")]  # cold cache
    assert len(err) == 1 and f"free_thresh 0.25 would read {grey} unknown cells as free" in err[0]
    assert "--free-thresh 0.25 gives nav2's reading" in err[0] and "np." not in err[0]
    assert _unknown(tmp_path / "kept.yaml") >= grey - 2 * 16 * 5  # the unexplored outside stays unknown
    # the other reading, asked for: no unknown cell in, none out, no warning
    assert main(["infer", str(path), str(tmp_path / "free.yaml"), "--free-thresh", "0.25"]) == 0
    assert capsys.readouterr().err == "" and _unknown(tmp_path / "free.yaml") == 0
    # a map whose thresholds already keep 205 unknown: no warning
    path, _ = _humble_map(tmp_path, free_thresh="0.196")
    assert main(["infer", str(path), str(tmp_path / "jazzy.yaml")]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.skipif(not have_data(OLIN), reason="Olin map not in the data folder")
def test_infer_keeps_the_olin_maps_unknown_space(tmp_path, capsys):
    """The shipped Olin map (Humble map_saver, free_thresh 0.25): 0 unknown cells as nav2 reads it, 1,220,114 kept."""
    assert _unknown(data_file(OLIN)) == 0
    kept = load_grid(data_file(OLIN), free_thresh=0.196)
    unknown_in = int((kept.to_int8() == -1).sum())
    out = tmp_path / "refined.yaml"
    assert main(["infer", str(data_file(OLIN)), str(out), "--max-iter", "30", "--float32"]) == 0
    err = capsys.readouterr().err
    assert f"free_thresh 0.25 would read {unknown_in} unknown cells as free" in err
    unknown_out = _unknown(out)
    # the certainty preset infers within 5 cells of an observation: the rest of the unknown space stays unknown
    assert unknown_in > 1_000_000 and 0.9 * unknown_in < unknown_out <= unknown_in


@pytest.mark.slow
def test_first_infer_on_an_empty_cache_reports_the_compile_apart_from_lbp(tmp_path):
    """With an empty numba cache the first `crfmap infer` compiles; its line gives the LBP time without it."""
    import os
    import re
    import subprocess
    import sys

    grid, _ = noisy_grid()
    save_grid(grid, tmp_path / "in.npy")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    run = subprocess.run([sys.executable, "-m", "crfmap", "infer", str(tmp_path / "in.npy"), str(tmp_path / "o.npy")],
                         env=env, capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    assert run.stderr.startswith("compiling LBP kernels (first run only)")
    found = re.search(r"LBP ([0-9.]+) s \(\+ ([0-9.]+) s compiling kernels, first run only\)", run.stdout)
    assert found, run.stdout
    lbp, compiling = float(found[1]), float(found[2])
    assert lbp < 1.0 < compiling  # 720 cells: milliseconds of LBP, seconds of compiling
