"""The explorer's pure functions (notebook 08 wires widgets to them)."""
import numpy as np
import pytest

from crfstudy.experiments import explorer
from crfmap.errors import InputError
from crfmap.crf.engine.messages import MESSAGE_FLOOR
from crfmap.assess.metrics import mse
from crfmap.crf.presets import DEFAULT_PRESET, get_preset


def test_observe_x_is_the_noisy_image_and_reproducible():
    a = explorer.observe("x", 0.42, seed=3)
    b = explorer.observe("x", 0.42, seed=3)
    c = explorer.observe("x", 0.42, seed=4)
    truth = a.scene.truth.probability
    assert a.observed.shape == truth.shape
    assert np.array_equal(a.observed.probability, b.observed.probability)
    assert not np.array_equal(a.observed.probability, c.observed.probability)
    assert 0.05 < mse(a.observed, truth) < 0.12  # sigma 0.42: near the thesis's 0.0825
    assert np.array_equal(explorer.observe("x", 0.0).observed.probability, truth)


def test_observe_simulated_scene_leaves_unseen_cells_unknown():
    ob = explorer.observe("enclosed-train", 0.0)
    p = ob.observed.probability
    assert p.shape == ob.scene.truth.shape
    assert ob.noise_kind.startswith("range")
    # the filled boxes' insides are never seen by the robot
    assert np.any(p == 0.5) and np.any(p > 0.5) and np.any(p < 0.5)


def test_run_denoises_the_x():
    ex = explorer.run("x", 0.42, seed=0, preset="certainty")
    assert ex.result.converged
    assert ex.after.mse < 0.5 * ex.before.mse
    assert ex.after.accuracy > ex.before.accuracy
    default = explorer.run("x", 0.42, seed=0)  # the gated default: its gate keeps repeated evidence, still denoises
    assert default.result.converged and default.after.mse < default.before.mse


def test_the_explorer_starts_from_the_default_preset():
    ex = explorer.run("x", 0.42, iterations=3)
    crf = get_preset(DEFAULT_PRESET)
    assert ex.settings["preset"] == DEFAULT_PRESET and ex.settings["hidden"] == crf.hidden.tolist()
    same = crf.refine(ex.observation.observed, max_iter=3, tol=explorer.TOLERANCE, threads=explorer.THREADS)
    assert np.array_equal(ex.result.beliefs.probability, same.beliefs.probability)
    thesis = explorer.run("x", 0.42, iterations=3, preset="thesis")
    assert not np.allclose(thesis.result.beliefs.probability, ex.result.beliefs.probability)
    # given tables are run exactly as given, on the grid's P (what the preset "thesis" does with its own)
    tables = explorer.run("x", 0.42, iterations=3, hidden=get_preset("thesis").hidden)
    assert tables.settings["preset"] == "custom"
    assert np.array_equal(tables.result.beliefs.probability, thesis.result.beliefs.probability)


def test_iterations_and_schedule_are_passed_on():
    ex = explorer.run("x", 0.42, schedule="thesis", iterations=2)
    assert ex.result.iterations == 2 and ex.result.schedule == "thesis"
    none = explorer.run("x", 0.42, iterations=0, preset="thesis")
    # no LBP: the beliefs are the observations (clipped to the message floor; hard evidence, P = 0 or 1, exact)
    p = none.observation.observed.probability
    expected = np.where((p == 0) | (p == 1), p, np.clip(p, MESSAGE_FLOOR, 1 - MESSAGE_FLOOR))
    assert np.allclose(none.result.beliefs.probability, expected, atol=1e-12)


def test_tables_change_the_result():
    weak = explorer.run("x", 0.42, hidden=[[1.0, 1.0], [1.0, 1.0]])  # no coupling: LBP changes nothing
    p = weak.observation.observed.probability  # hard evidence (P = 0 or 1) stays exact
    assert np.allclose(weak.result.beliefs.probability,
                       np.where((p == 0) | (p == 1), p, np.clip(p, MESSAGE_FLOOR, 1 - MESSAGE_FLOOR)))
    strong = explorer.run("x", 0.42, hidden=[[10.0, 1.0], [1.0, 10.0]])
    assert not np.allclose(strong.result.beliefs.probability, weak.result.beliefs.probability)


def test_bounded_run_leaves_far_cells_alone():
    ex = explorer.run("x", 0.42, radius=1.0, preset="thesis")
    region = ex.region
    assert region is not None and 0 < region.sum() < region.size
    # cells neither in the bound nor next to it receive no message: their belief is their observation
    near = region.copy()
    near[1:, :] |= region[:-1, :]
    near[:-1, :] |= region[1:, :]
    near[:, 1:] |= region[:, :-1]
    near[:, :-1] |= region[:, 1:]
    far = ~near
    p = ex.observation.observed.probability  # hard evidence (P = 0 or 1) stays exact
    obs = np.where((p == 0) | (p == 1), p, np.clip(p, MESSAGE_FLOOR, 1 - MESSAGE_FLOOR))
    assert np.allclose(ex.result.beliefs.probability[far], obs[far], atol=1e-12)
    assert not np.allclose(ex.result.beliefs.probability[region], obs[region])


@pytest.mark.parametrize("scene", explorer.EXPLORER_SCENES)
def test_every_scene_runs(scene):
    ex = explorer.run(scene, 0.42 if scene == "x" else 0.05, iterations=3)
    assert ex.result.beliefs.shape == ex.truth.shape
    assert 0.0 <= ex.after.mse <= 1.0 and ex.result.iterations <= 3


@pytest.mark.parametrize("scene", ["x", "office"])
def test_explore_draws_a_figure(scene):
    fig = explorer.explore(scene, 0.42 if scene == "x" else 0.05, iterations=3, radius=1.5)
    assert len([a for a in fig.axes if a.get_label() != "<colorbar>"]) == 4  # plus a colour bar per grid
    assert explorer.to_png(fig)[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("kwargs, name", [
    ({"scene": "moon"}, "scene"),
    ({"noise": -0.1}, "noise"),
    ({"noise": float("nan")}, "noise"),
    ({"seed": -1}, "seed"),
    ({"iterations": -2}, "iterations"),
    ({"iterations": 2.5}, "iterations"),
    ({"radius": 0.0}, "radius"),
    ({"schedule": "random"}, "schedule"),
    ({"hidden": [[1, 2, 3]]}, "hidden"),
    ({"link": [[-1, 0], [0, 1]]}, "link"),
])
def test_bad_settings_name_the_argument(kwargs, name):
    with pytest.raises(InputError) as err:
        explorer.run(**kwargs)
    assert str(err.value).startswith(f"{name}:")


# --- the live panel: one figure updated in place, kernels compiled up front -------------------------

def _pixels(png):
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def test_view_updated_in_place_shows_what_a_fresh_figure_shows():
    from crfstudy.experiments.explorer_view import ExplorerView

    first = explorer.run("x", 0.42, iterations=2)
    second = explorer.run("office", 0.05, schedule="thesis", radius=2.0, hidden=[[6.0, 1.0], [1.0, 6.0]])
    third = explorer.run("office", 0.05, iterations=3)
    view = ExplorerView()
    for ex in (first, second, third, second):  # scene change, then in-place updates
        live = _pixels(view.update(ex).png())
        fresh = _pixels(ExplorerView(live=False).update(ex).png())
        assert live.shape == fresh.shape
        differ = np.any(live != fresh, axis=2).mean()
        assert differ < 1e-4, differ  # a few anti-aliased pixels where a line meets the frame
    stale = _pixels(ExplorerView(live=False).update(third).png())
    assert np.any(live != stale, axis=2).mean() > 1e-3  # the comparison can fail


@pytest.mark.parametrize("live", [True, False])
def test_a_switch_between_scenes_of_the_same_extent_shows_the_new_truth(live):
    """occluded-train -> hollow-test (both 4 m x 4 m at 0.1 m): the figure equals a fresh one of hollow-test."""
    from crfstudy.experiments.explorer_view import ExplorerView

    before, after = explorer.run("occluded-train", iterations=2), explorer.run("hollow-test", iterations=2)
    assert before.truth.shape == after.truth.shape and before.truth.origin == after.truth.origin
    assert not np.array_equal(before.truth.probability, after.truth.probability)
    view = ExplorerView(live=live)
    view.update(before).png()
    switched = _pixels(view.update(after).png())
    fresh = _pixels(ExplorerView(live=live).update(after).png())
    assert np.any(switched != fresh, axis=2).sum() == 0
    stale = _pixels(ExplorerView(live=live).update(before).png())
    assert np.any(switched != stale, axis=2).sum() > 1000  # the scenes' panels differ: the comparison can fail


def _signatures():
    import sys

    from numba.core.registry import CPUDispatcher

    return {f"{m}.{k}": len(v.signatures) for m, mod in list(sys.modules.items()) if m.startswith("crfmap")
            for k, v in vars(mod).items() if isinstance(v, CPUDispatcher)}


def test_warm_up_compiles_every_kernel_the_explorer_calls():
    seconds = explorer.warm_up()
    assert set(seconds) == set(explorer.SCHEDULES)
    before = _signatures()
    assert sum(before.values()) > 0
    for schedule in explorer.SCHEDULES:
        for radius in (None, 1.5):
            for hidden in ([[10.0, 1.0], [1.0, 10.0]], [[3.0, 0.7], [1.3, 2.5]], [[1.0, 0.0], [0.0, 1.0]]):
                for iterations in (None, 2):
                    try:
                        explorer.run("x", 0.42, hidden=hidden, schedule=schedule, iterations=iterations, radius=radius)
                    except InputError as error:  # a zero-entry table against the noisy X's exact 0/1 cells
                        assert hidden[0][1] == 0 and "contradictory hard evidence" in str(error)
        explorer.run("office", 0.05, schedule=schedule, radius=2.0, iterations=3)
    assert _signatures() == before


def test_panel_redraws_on_each_widget_change():
    from crfstudy.experiments.explorer_panel import ExplorerPanel

    panel = ExplorerPanel(iterations=2)
    assert panel.settings()["preset"] == DEFAULT_PRESET and panel.settings()["hidden"] is None
    assert panel.controls["h_oo"].value == get_preset(DEFAULT_PRESET).hidden[0, 0]
    panel.warm_up()
    assert panel.status.value.startswith("LBP kernels ready")
    panel.redraw()
    first = panel.image.value
    panel.controls["schedule"].value = "thesis"
    assert panel.timings[-1]["change"] == "schedule" and not panel.timings[-1]["compiled"]
    assert "thesis: 2 iterations" in panel.status.value and "drawing" in panel.status.value
    assert panel.image.value != first
    n = len(panel.timings)
    panel.controls["preset"].value = "thesis"  # its tables on the sliders, one redraw
    assert len(panel.timings) == n + 1 and panel.controls["h_oo"].value == 10.0
    panel.controls["h_oo"].value = 3.0  # a slider moved: exactly the sliders' tables
    assert panel.controls["preset"].value == "custom tables"
    assert panel.settings()["hidden"] == [[3.0, 1.0], [1.0, 10.0]]
    n = len(panel.timings)
    panel.reset_tables()  # back to the default preset: one redraw, not one per slider
    assert len(panel.timings) == n + 1 and panel.settings()["preset"] == DEFAULT_PRESET
    assert panel.controls["h_oo"].value == get_preset(DEFAULT_PRESET).hidden[0, 0]
    panel.controls["preset"].value = "thesis"
    n = len(panel.timings)
    panel.controls["l_oo"].value = 0.0  # link row C1 is [0, 0]: the error in the status line, not a crash
    assert panel.status.value.startswith("<span") and "link" in panel.status.value and len(panel.timings) == n


def test_panel_is_built_for_the_setting_asked_for():
    from crfstudy.experiments.explorer_panel import ExplorerPanel

    panel = explorer.panel("enclosed-test", image_noise=0.3, range_noise=0.02, schedule="thesis", iterations=5,
                           radius=2.0, seed=3)
    assert isinstance(panel, ExplorerPanel)
    settings = panel.settings()
    assert (settings["scene"], settings["schedule"], settings["iterations"], settings["seed"]) == \
        ("enclosed-test", "thesis", 5, 3)
    assert settings["radius"] == 2.0
    assert panel.controls["image_noise"].value == 0.3 and panel.controls["range_noise"].value == 0.02
