"""Ground-truth scenes: shapes, polarity, seeds, and reachability against a brute-force reference."""
from collections import deque

import numpy as np
import pytest

from crfmap import paths
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.scenes import (
    SCENES, Scene, enclosed_boxes, make_scene, noisy_image, occluded_walls, office_floor, reachable, traversable,
    x_image,
)


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


@pytest.mark.skipif(not paths.have_data("images/ugm_X_32x32.csv"), reason="UGM X image not downloaded")
def test_x_image_polarity_and_orientation():
    csv = np.loadtxt(paths.data_file("images/ugm_X_32x32.csv"), delimiter=",")
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


def naive_traversable(occ, radius_cells):
    """Cell i is free when no occupied cell's square, nor the outside of the grid, comes nearer than the radius."""
    h, w = occ.shape
    ys, xs = np.nonzero(occ)
    out = np.zeros((h, w), bool)
    for y in range(h):
        for x in range(w):
            if occ[y, x]:
                continue
            gaps = np.hypot(np.maximum(np.abs(xs - x) - 0.5, 0), np.maximum(np.abs(ys - y) - 0.5, 0))
            border = min(x + 0.5, w - x - 0.5, y + 0.5, h - y - 0.5)
            out[y, x] = gaps.min(initial=np.inf) >= radius_cells and (radius_cells == 0 or border >= radius_cells)
    return out


def naive_flood(free, start):
    h, w = free.shape
    seen = np.zeros_like(free)
    seen[start[1], start[0]] = True
    queue = deque([start])
    while queue:
        x, y = queue.popleft()
        for nx, ny in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
            if 0 <= nx < w and 0 <= ny < h and free[ny, nx] and not seen[ny, nx]:
                seen[ny, nx] = True
                queue.append((nx, ny))
    return seen


@pytest.mark.parametrize("radius", [0.0, 0.05, 0.1, 0.149, 0.15, 0.23, 0.4])
def test_reachable_matches_brute_force_with_footprint(radius):
    rng = np.random.default_rng(7)
    for _ in range(6):
        occ = rng.random((17, 23)) < 0.12
        grid = OccupancyGrid(occ.astype(float), resolution=0.1)
        free = naive_traversable(occ, radius / 0.1)
        assert np.array_equal(traversable(grid, radius), free)
        starts = np.argwhere(free)
        if len(starts) == 0:
            continue
        iy, ix = starts[rng.integers(len(starts))]
        got = reachable(grid, ((ix + 0.5) * 0.1, (iy + 0.5) * 0.1, 0.0), radius)
        assert np.array_equal(got, naive_flood(free, (ix, iy)))


def test_reachable_footprint_closes_narrow_gaps():
    cells = np.zeros((9, 15))
    cells[:, 7] = 1
    cells[4, 7] = 0  # a one-cell door in a wall
    grid = OccupancyGrid(cells, resolution=0.1)
    start = (0.25, 0.45, 0.0)
    assert reachable(grid, start, 0.0)[4, 12]  # a point robot passes
    assert not reachable(grid, start, 0.08)[4, 12]  # a 16 cm robot does not fit a 10 cm door
    with pytest.raises(InputError):
        reachable(grid, (0.75, 0.15, 0.0))  # start inside the wall
    with pytest.raises(InputError):
        reachable(grid, (5.0, 0.15, 0.0))  # outside the grid


def test_office_floor():
    a, b = office_floor(12.0, 10.0, 0.1, seed=4), office_floor(12.0, 10.0, 0.1, seed=4)
    assert np.array_equal(a.truth.probability, b.truth.probability) and np.array_equal(a.waypoints, b.waypoints)
    assert not np.array_equal(a.truth.probability, office_floor(12.0, 10.0, 0.1, seed=5).truth.probability)
    for w, h, res, seed in ((6.0, 5.0, 0.1, 0), (20.0, 15.0, 0.05, 1), (31.0, 9.0, 0.1, 2), (9.0, 33.0, 0.1, 3)):
        s = office_floor(w, h, res, seed)
        assert s.truth.shape == (round(h / res), round(w / res))
        mask = reachable(s.truth, s.start, s.robot_radius)
        assert len(s.waypoints) >= 1
        for x, y in s.waypoints:
            assert mask[int(y / res), int(x / res)]
        p = s.truth.probability
        assert (p[0] == 1).all() and (p[-1] == 1).all() and (p[:, 0] == 1).all() and (p[:, -1] == 1).all()
        assert mask.sum() > 0.3 * (p == 0).sum()  # most of the floor is reachable
    with pytest.raises(InputError):
        office_floor(2.0, 10.0)
    with pytest.raises(InputError):
        office_floor(10.0, 10.0, resolution=0.0)


def test_make_scene_rejects_unknown_names_and_arguments():
    with pytest.raises(InputError, match="unknown scene"):
        make_scene("garage")
    with pytest.raises(InputError, match="seed"):
        make_scene("x", seed=3)
    assert make_scene("office", seed=2, width_m=8.0, height_m=6.0).truth.shape == (120, 160)
