"""Schedules own their settings: an option for one schedule or kernel only is refused elsewhere, in one line."""
import inspect

import numpy as np
import pytest

from crfmap.crf.inference.lbp import infer
from crfmap.crf.inference.schedules import SCHEDULES, Checkerboard, Flooding, Sweep, Thesis, schedule_settings
from crfmap.errors import InputError

GRID = np.random.default_rng(3).uniform(0.05, 0.95, (9, 11))


def test_infer_takes_at_most_twelve_parameters():
    assert len(inspect.signature(infer).parameters) <= 12


@pytest.mark.parametrize("make, word", [
    (lambda: Thesis(start="middle"), "start"),
    (lambda: Checkerboard(kernel="plain", block=4), "block"),
    (lambda: Checkerboard(kernel="plain", freeze=0.0), "freeze"),
    (lambda: Checkerboard(damping=0.3, block=4), "block"),
    (lambda: Checkerboard(kernel="fast", damping=0.3), "damping"),
    (lambda: Checkerboard(kernel="quick"), "kernel"),
    (lambda: Checkerboard(block=0), "block"),
    (lambda: Flooding(damping=1.0), "damping"),
    (lambda: Sweep(damping=-0.1), "damping"),
    (lambda: Thesis(damping=float("nan")), "damping"),
    (lambda: infer(GRID, schedule=Checkerboard(freeze=1e-3), tol=1e-5), "freeze"),
    (lambda: infer(GRID, schedule="random"), "schedule"),
    (lambda: infer(GRID, schedule=Thesis), "schedule"),
])
def test_an_option_that_does_not_apply_is_refused_in_one_line(make, word):
    with pytest.raises(InputError) as e:
        make()
    assert str(e.value).startswith(word) and "\n" not in str(e.value)


@pytest.mark.parametrize("option", ["start", "damping", "kernel", "block", "freeze"])
def test_mode_options_are_not_parameters_of_infer(option):
    with pytest.raises(TypeError):
        infer(GRID, **{option: None})


def test_a_name_means_its_settings_with_defaults():
    for name in SCHEDULES:
        assert schedule_settings(name) == type(schedule_settings(name))() and schedule_settings(name).name == name
    assert infer(GRID, schedule="thesis", max_iter=2).beliefs.probability.tolist() == \
        infer(GRID, schedule=Thesis(), max_iter=2).beliefs.probability.tolist()


def test_the_settings_reach_the_kernels():
    corners = {c: infer(GRID, schedule=Thesis(start=c), max_iter=1).beliefs.probability for c in
               ("lower-left", "upper-right")}
    assert not np.array_equal(corners["lower-left"], corners["upper-right"])
    assert infer(GRID, schedule=Checkerboard(damping=0.3), max_iter=3).kernel == "plain"
    assert infer(GRID, schedule=Checkerboard(kernel="plain"), max_iter=3).kernel == "plain"
    assert infer(GRID, max_iter=3).kernel == "fast"
    damped = infer(GRID, schedule=Flooding(damping=0.5), max_iter=3).beliefs.probability
    assert not np.array_equal(damped, infer(GRID, schedule="flooding", max_iter=3).beliefs.probability)


def test_every_schedule_has_one_registry_entry():
    """The settings registry and the plain runners' registry name the same schedules: the CLI's choices and the
    warm-up read them from here."""
    from crfmap.crf.inference.schedules import PLAIN_RUNNERS, SETTINGS

    assert list(SETTINGS) == list(PLAIN_RUNNERS)
    for name in SETTINGS:
        assert SETTINGS[name].name == name and callable(PLAIN_RUNNERS[name])
