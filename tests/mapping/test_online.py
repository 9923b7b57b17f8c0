"""Online mapping: the same grid as the builder, bounded LBP around the robot, the offline fixed point."""
import numpy as np
import pytest

from crfmap.data import data_file, have_data
from crfmap.mapping import builder
from crfmap.errors import InputError
from crfmap.crf.inference.lbp import infer
from crfmap.crf.presets import CRITICAL_COUPLING, DEFAULT_PRESET, PRESETS, custom_preset, get_preset
from crfmap.mapping.online import OnlineMapper
from crfmap.recording import ScanSet

ROOM = (0.0, 0.0, 4.0, 3.0)  # [m] walls of a box room
WEAK = [[1.5, 1.0], [1.0, 1.5]]  # LBP has one fixed point with it (no ordered phase)


def box_ranges(pose, angles, room=ROOM):
    """Distance from ``pose`` along each beam to the walls of the box room (analytic ray casting)."""
    x, y, yaw = pose
    xmin, ymin, xmax, ymax = room
    a = yaw + angles
    c, s = np.cos(a), np.sin(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(c > 0, (xmax - x) / c, np.where(c < 0, (xmin - x) / c, np.inf))
        ty = np.where(s > 0, (ymax - y) / s, np.where(s < 0, (ymin - y) / s, np.inf))
    return np.minimum(tx, ty)


def room_scans(n=12, beams=61, seed=0):
    rng = np.random.default_rng(seed)
    angles = np.linspace(-np.pi / 2, np.pi / 2, beams)
    poses = np.column_stack([rng.uniform(0.8, 3.2, n), rng.uniform(0.8, 2.2, n), rng.uniform(-np.pi, np.pi, n)])
    ranges = np.array([box_ranges(p, angles) for p in poses], np.float32)
    ranges[0, :5] = np.inf  # REP 117: no return
    ranges[1, 3] = np.nan  # invalid
    return ScanSet(ranges, float(angles[0]), float(angles[1] - angles[0]), 0.05, 8.0, poses,
                   np.arange(n, dtype=float), source="room")


def test_counts_and_observations_equal_the_builder():
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1)
    mapper.run(scans)
    occupied, empty = builder.count_hits(scans, 0.1)
    np.testing.assert_array_equal(mapper.hits.occupied, occupied)
    np.testing.assert_array_equal(mapper.hits.empty, empty)
    offline = builder.build_grid(scans, 0.1)
    got = mapper.observations()
    np.testing.assert_array_equal(got.probability, offline.probability)
    assert got.origin == offline.origin and got.resolution == offline.resolution


def test_final_map_equals_offline_converged_lbp():
    """Online (bounded LBP per scan, then finish) reaches the offline fixed point: tolerance 1e-6."""
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1, hidden=WEAK, dtype=np.float64, radius=1.0, max_iter=4)
    mapper.run(scans)
    before = mapper.beliefs().probability
    final = mapper.finish(tol=1e-10, max_iter=5000)
    offline = infer(builder.build_grid(scans, 0.1), WEAK, tol=1e-10, max_iter=5000, dtype=np.float64)
    assert final.converged and offline.converged
    np.testing.assert_allclose(final.beliefs.probability, offline.beliefs.probability, atol=1e-6)
    # the bounded per-scan LBP alone had not got there: finish() did something
    assert np.abs(before - offline.beliefs.probability).max() > 1e-3


def test_lbp_runs_only_within_the_radius():
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1, radius=0.5)
    mapper.integrate(scans.ranges[0], scans.laser_poses[0])
    before = mapper.messages()
    pose = scans.laser_poses[1]
    mapper.integrate(scans.ranges[1], pose)
    changed = np.any(mapper.messages() != before, axis=0)
    # a changed message was sent by a neighbour of its receiver within the radius (+ one cell)
    ys, xs = np.nonzero(changed)
    cx, cy = mapper.origin[0] + (xs + 0.5) * 0.1, mapper.origin[1] + (ys + 0.5) * 0.1
    assert changed.any()
    assert np.hypot(cx - pose[0], cy - pose[1]).max() <= 0.5 + 0.1 + 1e-9


def test_warm_start_settles_at_once_when_nothing_new_arrives():
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1, max_iter=500, tol=1e-6)
    mapper.integrate(scans.ranges[2], scans.laser_poses[2])
    nothing = np.full(scans.ranges.shape[1], np.nan, np.float32)
    update = mapper.integrate(nothing, scans.laser_poses[2])
    assert update.iterations == 1 and update.converged


def test_for_sensor_builds_an_empty_mapper():
    mapper = OnlineMapper.for_sensor(ROOM, 0.1, -1.0, 0.1, 21, 0.05, 5.0)
    assert mapper.width == 40 and mapper.height == 30
    assert np.all(mapper.observations().probability == 0.5)


@pytest.mark.parametrize("ranges, pose, word", [
    (np.ones(3, np.float32), (1.0, 1.0, 0.0), "ranges"),
    (None, (np.nan, 1.0, 0.0), "laser_pose"),
    (None, (40.0, 1.0, 0.0), "outside"),
])
def test_bad_scans_are_named(ranges, pose, word):
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1)
    with pytest.raises(InputError, match=word):
        mapper.integrate(scans.ranges[0] if ranges is None else ranges, pose)


def test_bad_options_are_named():
    scans = room_scans()
    with pytest.raises(InputError, match="radius"):
        OnlineMapper.for_scans(scans, 0.1, radius=0.0)
    with pytest.raises(InputError, match="max_iter"):
        OnlineMapper.for_scans(scans, 0.1, max_iter=0)
    with pytest.raises(InputError, match="margin"):
        OnlineMapper.for_scans(scans, 0.1, margin=-1)
    with pytest.raises(InputError, match="hits"):
        OnlineMapper(object())


def observed_within(mapper, margin):
    """Cells within ``margin`` (Chebyshev) of a cell some beam passed: a slow, obvious dilation."""
    seen = (mapper.hits.occupied + mapper.hits.empty) > 0
    out = np.zeros_like(seen)
    for y, x in zip(*np.nonzero(seen)):
        out[max(y - margin, 0):y + margin + 1, max(x - margin, 0):x + margin + 1] = True
    return out


def sent_by(changed):
    """Cells that sent a changed message: slot d of (y, x) comes from its neighbour in direction d."""
    senders = np.zeros(changed.shape[1:], bool)
    senders[:, 1:] |= changed[1, :, :-1]  # slot 1 (from the east) of x came from x + 1
    senders[:, :-1] |= changed[0, :, 1:]  # slot 0 (from the west) of x came from x - 1
    senders[1:, :] |= changed[3, :-1, :]  # slot 3 (from the north) of row y came from row y + 1
    senders[:-1, :] |= changed[2, 1:, :]  # slot 2 (from the south) of row y came from row y - 1
    return senders


def test_margin_keeps_messages_from_unobserved_cells_still():
    scans = room_scans(n=3)
    mapper = OnlineMapper.for_scans(scans, 0.1, margin=2, radius=10.0, max_iter=50)
    start = mapper.messages()
    mapper.run(scans)
    changed = mapper.messages() != start
    near = observed_within(mapper, 2)
    assert changed.any() and not near.all()
    # a message moved only if a cell near an observation could have sent it
    assert not np.any(sent_by(changed) & ~near)
    far = ~observed_within(mapper, 3)
    gate = mapper.preset.gate  # no LBP there: the observation (0.5), and the gate's prior if the preset has one
    np.testing.assert_allclose(mapper.beliefs().probability[far], 0.5 if gate is None else gate.unobserved_prior,
                               rtol=1e-12)  # the prior goes through logit and back


def test_margin_final_map_equals_offline_bounded_lbp():
    """With a margin, finish() reaches the preset's refinement (LBP near observations, 0.5 beyond): tolerance 1e-6."""
    scans = room_scans(n=4)
    mapper = OnlineMapper.for_scans(scans, 0.1, hidden=WEAK, dtype=np.float64, radius=1.0, max_iter=4, margin=1)
    mapper.run(scans)
    final = mapper.finish(tol=1e-10, max_iter=5000)
    np.testing.assert_array_equal(mapper.region(), observed_within(mapper, 1))
    offline = infer(builder.build_grid(scans, 0.1), WEAK, tol=1e-10, max_iter=5000, dtype=np.float64,
                    region=mapper.region())
    assert final.converged and offline.converged
    inside = mapper.region()
    np.testing.assert_allclose(final.beliefs.probability[inside], offline.beliefs.probability[inside], atol=1e-6)
    # outside the region nothing was inferred: unknown, as Preset.refine leaves it (infer reports received messages)
    assert np.all(final.beliefs.probability[~inside] == 0.5)
    occupied, empty = builder.count_hits(scans, 0.1)
    refined = custom_preset(WEAK, margin=1).refine(hits=occupied, passes=empty, tol=1e-10, max_iter=5000,
                                                   dtype=np.float64)
    np.testing.assert_allclose(final.beliefs.probability, refined.beliefs.probability, atol=1e-6)


# Presets whose coupling is below the lattice's critical one: LBP has one fixed point, which online and offline
# runs share. The thesis preset is in its ordered phase: on this room the online run ends all-empty and the
# offline one all-occupied (two fixed points), so no equality can hold for it.
SINGLE_FIXED_POINT = sorted(name for name, p in PRESETS.items() if p.coupling < CRITICAL_COUPLING)


def test_the_default_preset_has_one_fixed_point():
    assert DEFAULT_PRESET in SINGLE_FIXED_POINT and "thesis" not in SINGLE_FIXED_POINT


@pytest.mark.parametrize("name", SINGLE_FIXED_POINT)
def test_finish_equals_the_presets_offline_refinement(name):
    """finish() after per-scan bounded LBP is the preset's refinement of the same counts: tolerance 1e-6 in P
    (both float64, tol 1e-10)."""
    scans = room_scans()
    mapper = OnlineMapper.for_scans(scans, 0.1, preset=name, dtype=np.float64, radius=1.0, max_iter=4)
    mapper.run(scans)
    assert mapper.preset is get_preset(name) and mapper.margin == get_preset(name).margin
    final = mapper.finish(tol=1e-10, max_iter=5000)
    occupied, empty = builder.count_hits(scans, 0.1)
    offline = get_preset(name).refine(hits=occupied, passes=empty, tol=1e-10, max_iter=5000, dtype=np.float64)
    assert final.converged and offline.converged
    np.testing.assert_allclose(final.beliefs.probability, offline.beliefs.probability, atol=1e-6)


def test_the_default_is_the_default_preset_and_tables_make_a_custom_one():
    scans = room_scans(n=2)
    assert OnlineMapper.for_scans(scans, 0.1).preset is get_preset(DEFAULT_PRESET)
    custom = OnlineMapper.for_scans(scans, 0.1, hidden=WEAK, margin=2).preset
    assert custom.name == "custom" and custom.margin == 2 and not custom.scaled
    with pytest.raises(InputError, match="preset"):
        OnlineMapper.for_scans(scans, 0.1, preset="thesis", hidden=WEAK)
    with pytest.raises(InputError, match="preset"):
        OnlineMapper.for_scans(scans, 0.1, preset="no-such-preset")


@pytest.mark.skipif(not have_data("carmen/intel-corrected.log.gz"), reason="Intel lab log not present")
def test_intel_log_first_scans_match_the_builder():
    from dataclasses import replace

    from crfmap.io.carmen import read_carmen

    scans = read_carmen(data_file("carmen/intel-corrected.log.gz")).scans
    scans = replace(scans, ranges=scans.ranges[:60], laser_poses=scans.laser_poses[:60], stamps=scans.stamps[:60])
    mapper = OnlineMapper.for_scans(scans, 0.05)
    seconds = mapper.run(scans)
    assert seconds.shape == (60,) and np.all(seconds > 0)
    np.testing.assert_array_equal(mapper.observations().probability, builder.build_grid(scans, 0.05).probability)
