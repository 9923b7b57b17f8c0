"""Ground-truth scenes: shapes, polarity, seeds, and the enclosed parts no robot reaches."""
import numpy as np
import pytest

from crfmap.data import data_file, have_data
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.world.scenes import SCENES, enclosed_boxes, make_scene, noisy_image, occluded_walls, x_image
from crfmap.world.scene import Scene
from crfmap.world.reachability import reachable


@pytest.mark.parametrize("name", list(SCENES))
def test_every_scene_is_a_01_grid_with_a_free_reachable_start(name):
    scene = make_scene(name)
    assert isinstance(scene, Scene) and scene.name == name
    p = scene.truth.probability
    assert np.isin(p, (0.0, 1.0)).all() and p.max() == 1.0 and p.min() == 0.0
    assert scene.truth.known().all()  # nothing unknown
    ix, iy = scene.start_cell()
    mask = reachable(scene.truth, scene.start, scene.robot_radius)
    assert mask.shape == p.shape and mask[iy, ix] and p[iy, ix] == 0.0
    assert not (mask & (p > 0.5)).any()


def test_thesis_scene_sizes():
    for name in ("occluded-train", "occluded-test", "enclosed-train", "enclosed-test", "hollow-train", "hollow-test"):
        s = make_scene(name)
        assert s.truth.shape == (40, 40) and s.truth.resolution == 0.1
    assert make_scene("x").truth.shape == (32, 32)
    assert occluded_walls("train", resolution=1.0).truth.resolution == 1.0


@pytest.mark.skipif(not have_data("images/ugm_X_32x32.csv"), reason="UGM X image not downloaded")
def test_x_image_polarity_and_orientation():
    csv = np.loadtxt(data_file("images/ugm_X_32x32.csv"), delimiter=",")
    truth = x_image().truth.probability
    assert truth.sum() == np.count_nonzero(csv == 0)  # the stroke (CSV 0) is occupied
    assert np.array_equal(truth, np.flipud(1 - csv))  # CSV row 0 is the image top = highest y
    assert "UGM" in x_image().truth.meta["source"]


def test_x_image_falls_back_to_a_drawn_x(monkeypatch, tmp_path):
    monkeypatch.setenv("CRFMAP_DATA", str(tmp_path))  # no data here
    for shape in (32, (20, 28)):
        scene = x_image(shape)
        p = scene.truth.probability
        assert "procedural" in scene.truth.meta["source"]
        assert 0.12 < p.mean() < 0.4  # a stroke, not a blank or a full image
        h, w = p.shape
        assert p[h // 2, w // 2] == 1.0 and p[0, 0] == 0.0  # crossing occupied, corner free
        assert np.array_equal(p, p[:, ::-1])  # an X is mirror symmetric


def test_x_image_resizes():
    assert x_image(64).truth.shape == (64, 64)
    with pytest.raises(InputError):
        x_image(2)


def test_noisy_image_gaussian_reproducible_and_calibrated():
    truth = x_image().truth
    a, b, c = noisy_image(truth, 0.4, seed=1), noisy_image(truth, 0.4, seed=1), noisy_image(truth, 0.4, seed=2)
    assert np.array_equal(a.probability, b.probability) and not np.array_equal(a.probability, c.probability)
    big = OccupancyGrid(np.tile(truth.probability, (8, 8)))
    mse = np.mean((noisy_image(big, 0.4, seed=3).probability - big.probability) ** 2)
    assert 0.07 < mse < 0.086  # E[clip(N(0, 0.4))^2 on the inward side] = 0.078
    assert np.array_equal(noisy_image(truth, 0.0).probability, truth.probability)


def test_noisy_image_flip():
    truth = OccupancyGrid(np.tile([[0.0, 1.0]], (200, 100)))
    q = 0.1
    noisy = noisy_image(truth, q, seed=0, model="flip").probability
    assert set(np.unique(noisy)) == {q, 1 - q}
    flipped = np.mean((noisy > 0.5) != (truth.probability > 0.5))
    assert abs(flipped - q) < 4 * np.sqrt(q * (1 - q) / noisy.size)
    with pytest.raises(InputError):
        noisy_image(truth, 0.7, model="flip")
    with pytest.raises(InputError):
        noisy_image(OccupancyGrid(np.full((3, 3), 0.5)), 0.1)


@pytest.mark.parametrize("variant", ["train", "test"])
def test_occluded_walls_layout(variant):
    s = occluded_walls(variant)
    ix, iy = s.start_cell()
    assert ix < 10 and iy > 30  # robot upper left
    assert s.default_mode == "look"
    jitter1, jitter2 = occluded_walls(variant, seed=5), occluded_walls(variant, seed=5)
    assert np.array_equal(jitter1.truth.probability, jitter2.truth.probability)
    assert not np.array_equal(jitter1.truth.probability, occluded_walls(variant, seed=6).truth.probability)
    assert np.array_equal(s.truth.probability, occluded_walls(variant).truth.probability)
    assert occluded_walls(variant, size=80).truth.shape == (80, 80)


def test_train_and_test_layouts_differ():
    for make in (occluded_walls, enclosed_boxes):
        assert not np.array_equal(make("train").truth.probability, make("test").truth.probability)
    with pytest.raises(InputError):
        occluded_walls("validation")


@pytest.mark.parametrize("variant", ["train", "test"])
@pytest.mark.parametrize("hollow", [False, True])
@pytest.mark.parametrize("seed", [None, 11])
def test_enclosed_boxes_interiors_unreachable(variant, hollow, seed):
    s = enclosed_boxes(variant, hollow=hollow, seed=seed)
    p = s.truth.probability
    mask = reachable(s.truth, s.start)
    boxes = s.truth.meta["boxes"]
    assert len(boxes) >= 5
    inside_any = np.zeros_like(mask)
    for x0, y0, x1, y1 in boxes:
        assert not mask[y0 : y1 + 1, x0 : x1 + 1].any()
        inside_any[y0 : y1 + 1, x0 : x1 + 1] = True
        interior = p[y0 + 1 : y1, x0 + 1 : x1]
        assert (interior == (0.0 if hollow else 1.0)).all()
        assert (p[y0, x0 : x1 + 1] == 1).all() and (p[y0 : y1 + 1, x0] == 1).all()
    # everything free outside the boxes is one connected room the robot reaches
    assert np.array_equal(mask, (p == 0) & ~inside_any)


def test_make_scene_rejects_unknown_names_and_arguments():
    with pytest.raises(InputError, match="unknown scene"):
        make_scene("garage")
    with pytest.raises(InputError, match="seed"):
        make_scene("x", seed=3)
    assert make_scene("office", seed=2, width_m=8.0, height_m=6.0).truth.shape == (120, 160)
