"""crfstudy.repro.sweep: folder labels are unique and reversible, values have the notebook's types, points are capped.

The hostile sweep files themselves are in the catalogue (tests/hostile/cases_batch.py, class "sweep").
"""
import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crfmap.errors import InputError
from crfstudy.repro import reproduce, sweep
from crfstudy.repro.sweep import MAX_POINTS, NAME_MAX, Sweep, label, load, parse_label, parse_point, sweep_files

SHIPPED = sweep_files()
# the values a notebook parameter can take from YAML: scalars and flat lists of them
SCALARS = (st.none() | st.booleans() | st.integers(-10**6, 10**6)
           | st.floats(allow_nan=False, allow_infinity=False) | st.text(max_size=12))
VALUES = SCALARS | st.lists(SCALARS, max_size=3)


def same(a, b) -> bool:
    """Equal as JSON values, types included (1 is not 1.0, not True)."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True) and type(a) is type(b)


def check_folders(points: dict, grid: dict, lengths=True):
    """Every point has its own folder (also ignoring case) and the folder name gives back its parameters."""
    folded = [p.casefold() for p in points]
    assert len(set(folded)) == len(folded) == math.prod(len(v) for v in grid.values())
    for folder, parameters in points.items():
        assert "/" not in folder and "\0" not in folder
        assert not lengths or len((folder + sweep.LOG_SUFFIX).encode()) <= NAME_MAX  # load() checks this
        back = parse_point(folder)
        assert list(back) == list(grid)
        assert all(same(back[n], parameters[n]) for n in grid), (folder, back, parameters)


def test_there_are_shipped_sweeps():
    assert [f.name for f in SHIPPED] and Path(SHIPPED[0]).parent.name == "sweeps"


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_no_two_points_of_a_shipped_sweep_share_a_folder(path):
    loaded = load(path)
    check_folders(loaded.points(), loaded.grid)


@settings(max_examples=150, deadline=None)
@given(st.dictionaries(st.sampled_from(["a", "b__c", "radius"]), st.lists(VALUES, min_size=1, max_size=4),
                       min_size=1, max_size=3))
def test_no_two_points_of_any_sweep_share_a_folder(grid):
    """Any grid: the points get folders of their own that read back, or the sweep is refused naming two points."""
    made = Sweep("s", Path("08_explorer.ipynb"), grid)
    try:
        points = made.points()
    except InputError as error:
        assert "two points would write to one folder, out/runs/s/" in str(error)
        return
    check_folders(points, grid, lengths=False)


@settings(max_examples=200, deadline=None)
@given(VALUES, VALUES)
def test_labels_differ_for_different_values_and_read_back(a, b):
    assert same(parse_label(label(a)), a)
    if not same(a, b):
        assert label(a) != label(b)
    assert set(label(a)) <= sweep._SAFE | set("%0123456789ABCDEF")  # no / _ = or space: one folder, one split


def test_values_the_issue_names_get_their_own_folders():
    made = Sweep("s", Path("08_explorer.ipynb"), {"radius": [0.3, "0.3"], "scene": ["a/b", "a-b"]})
    points = made.points()
    assert list(points) == ["radius=0.3__scene=a%2Fb", "radius=0.3__scene=a-b", "radius=%220.3%22__scene=a%2Fb",
                            "radius=%220.3%22__scene=a-b"]
    check_folders(points, made.grid)


def test_a_colliding_sweep_is_refused_naming_both_points(tmp_path):
    path = tmp_path / "twice.yaml"
    path.write_text("notebook: 04_denoising\nparameters:\n  noise: [0.5, 0.3, 0.30]\n")
    with pytest.raises(InputError, match=r"twice.yaml: two points would write to one folder, "
                       r"out/runs/twice/noise=0.3: \{noise: 0.3\} and \{noise: 0.3\}"):
        load(path)


def test_values_take_the_notebook_parameters_types(tmp_path):
    path = tmp_path / "typed.yaml"
    path.write_text("notebook: 04_denoising\nparameters:\n  noise: [1, 0.5]\n  seed: [3]\nfixed: {quick: true}\n")
    loaded = load(path)
    assert loaded.grid == {"noise": [1.0, 0.5], "seed": [3]} and type(loaded.grid["noise"][0]) is float
    assert list(loaded.points()) == ["noise=1.0__seed=3", "noise=0.5__seed=3"]
    path.write_text("notebook: 04_denoising\nparameters:\n  seed: [true]\n")
    with pytest.raises(InputError, match=r"seed: true is a boolean, but seed = 0 in 04_denoising.ipynb's parameters "
                       r"cell is an integer"):
        load(path)


def test_list_parameters_are_checked_element_by_element(tmp_path):
    path = tmp_path / "lists.yaml"
    path.write_text("notebook: 10_beyond\nparameters:\n  couplings: [[0, 0.5]]\n")
    assert load(path).grid == {"couplings": [[0.0, 0.5]]}
    path.write_text("notebook: 10_beyond\nparameters:\n  couplings: [[0, 'x']]\n")
    with pytest.raises(InputError, match="couplings: \"x\" is a string"):
        load(path)


def test_the_point_limit_is_documented_and_can_be_raised(tmp_path):
    path = tmp_path / "big.yaml"
    path.write_text(f"notebook: 04_denoising\nparameters:\n  seed: {list(range(MAX_POINTS + 1))}\n")
    with pytest.raises(InputError, match=f"{MAX_POINTS + 1:,} points .* exceed the limit of {MAX_POINTS}.*--max-points"):
        load(path)
    assert len(load(path, max_points=MAX_POINTS + 1).points()) == MAX_POINTS + 1
    readme = (Path(__file__).resolve().parents[3] / "README.md").read_text()
    assert f"at most {MAX_POINTS} points" in readme and "--max-points" in readme


def test_reproduce_says_points_and_time_then_passes_the_sweep_to_snakemake(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "toy.yaml").write_text("notebook: 04_denoising\nparameters:\n  noise: [0.3, 0.5, 0.7]\n"
                                     "  seed: [0, 1]\n")
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path / "out"))
    commands = []
    monkeypatch.setattr(reproduce.subprocess, "call", lambda command, env: commands.append(command) or 0)
    assert reproduce.main(["--sweep", str(folder / "toy.yaml"), "--max-points", "300", "--dry-run"]) == 0
    err = capsys.readouterr().err.splitlines()
    from crfstudy.repro.timings import EXPECTED_SECONDS, describe

    each = EXPECTED_SECONDS["04_denoising"]  # the table: no full run under this output root
    total = describe(each * 3)  # 6 points, 2 at a time
    assert err[0] == f"reproduce: sweep toy: 6 points of 04_denoising.ipynb, about {total} on 2 cores ({each} s per " \
                     "point at full settings)"
    (command,) = commands
    assert "out/runs/toy/collected.csv" in command
    config = command[command.index("--config") + 1:]
    assert config[:3] == ["sweep_names=[toy]", f"sweeps={folder}", "max_points=300"]
    assert not (tmp_path / "out").exists()  # the check that it can write there leaves nothing


def test_a_plain_reproduction_loads_no_sweep(monkeypatch, tmp_path):
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    commands = []
    monkeypatch.setattr(reproduce.subprocess, "call", lambda command, env: commands.append(command) or 0)
    assert reproduce.main(["--quick", "--only", "02", "--dry-run"]) == 0
    assert "sweep_names=[]" in commands[0]  # a broken or too-large sweep file cannot stop it
