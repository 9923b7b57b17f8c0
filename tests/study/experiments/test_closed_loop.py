"""Notebook 11's helper: scenes, runs, the paired and per-scene tables, the two figures, the warm-up."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from crfmap.errors import InputError  # noqa: E402
from crfstudy.experiments.closed_loop import (METRICS, ExploreSettings, closed_loop_scenes,  # noqa: E402
                                              coverage_figure, paired_table, per_scene_table, run_closed_loop,
                                              run_figure, warm_up)

KINDS = ("raw", "online-crf")


@pytest.fixture(scope="module")
def runs():
    """Two thesis scenes (a point robot), two kinds, a short budget: enough for pairs over scenes."""
    scenes = closed_loop_scenes(n_floors=0, thesis_scenes=("enclosed-train", "enclosed-test"))
    settings = ExploreSettings(max_scans=30)
    records, kept = run_closed_loop(scenes, kinds=KINDS, settings=settings, seed=0, n_pairs=3)
    return scenes, records, kept


def test_scenes_are_floors_then_thesis_scenes_and_a_bad_count_is_named():
    scenes = closed_loop_scenes(n_floors=1, floor_size=(6.0, 5.0), thesis_scenes=("enclosed-train",))
    assert [label for label, _ in scenes] == ["office-0", "enclosed-train"]
    with pytest.raises(InputError, match="n_floors"):
        closed_loop_scenes(n_floors=-1)


def test_every_scene_runs_every_kind_and_the_first_is_kept(runs):
    _, records, kept = runs
    assert [(r["scene"], r["kind"]) for r in records] == [(s, k) for s in ("enclosed-train", "enclosed-test")
                                                          for k in KINDS]
    assert list(kept) == ["enclosed-train"] and list(kept["enclosed-train"]) == list(KINDS)
    for r in records:  # a run that never reached the goal counts the budget as its scans
        assert r["scans"] == (r["scans_to_goal"] if r["reached"] else 30)
        assert set(METRICS) <= set(r)


def test_the_paired_table_has_a_row_per_metric_and_the_reference_first(runs):
    _, records, _ = runs
    header, rows = paired_table(records, n_boot=50, seed=0)
    assert header[:2] == ["metric", "raw"] and header[2].startswith("online-crf (diff to raw")
    assert len(rows) == len(METRICS) and all(len(row) == 3 for row in rows)
    assert paired_table(records, n_boot=50, seed=0) == (header, rows)  # seeded
    with pytest.raises(InputError, match="reference"):
        paired_table(records, reference="octomap")


def test_the_per_scene_table_has_a_row_per_run(runs):
    _, records, _ = runs
    header, rows = per_scene_table(records, metrics=("scans", "collisions"))
    assert header == ["scene", "kind", "stop", METRICS["scans"][0], METRICS["collisions"][0]]
    assert [row[:2] for row in rows] == [[r["scene"], r["kind"]] for r in records]


def test_the_figures_have_a_panel_per_map_and_a_curve_per_run(runs):
    scenes, _, kept = runs
    fig = run_figure(dict(scenes)["enclosed-train"], kept["enclosed-train"], "enclosed-train")
    assert len(fig.axes) == 3  # the truth with the paths, then one map per kind
    assert [ax.get_title().split(":")[0] for ax in fig.axes[1:]] == list(KINDS)
    plt.close(fig)
    fig = coverage_figure(kept)
    assert len(fig.axes) == 1 and len(fig.axes[0].get_lines()) == len(KINDS) + 1  # + the 95 % line
    plt.close(fig)


def test_the_warm_up_runs_every_kind_named():
    scene = closed_loop_scenes(n_floors=0, thesis_scenes=("enclosed-train",))[0][1]
    assert warm_up(scene, kinds=["raw"]) == ["raw"]
    with pytest.raises(InputError):
        warm_up(scene, kinds=["no-such-map"])
