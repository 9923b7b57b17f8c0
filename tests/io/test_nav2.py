"""Maps as nav2 sees them: Humble's and Jazzy+'s loaders (map_io.cpp), the costmap static layer.

Each rule is checked three ways: hand-computed pixels of every image kind, a per-pixel
transcription of the C++ (slow, obvious) against the vectorised loader on random images,
and crfmap's own outputs loaded back and counted against the probabilities they came from.
"""
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import crfmap.data
from crfmap.grid import OccupancyGrid
from crfmap.io.map_server import load_map, save_map
from crfmap.io.nav2_costmap import nav2_counts, static_layer_costs
from crfmap.io.nav2_loader import Pixels, occupancy

OLIN = "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml"


def write_pgm(path, pixels, maxval=255):
    pixels = np.asarray(pixels)
    data = pixels.astype(">u2" if maxval > 255 else np.uint8).tobytes()
    Path(path).write_bytes(b"P5\n%d %d\n%d\n" % (pixels.shape[1], pixels.shape[0], maxval) + data)


def write_yaml(path, image, mode="trinary", negate=0, occ=0.65, free=0.196):
    Path(path).write_text(f"image: {image}\nmode: {mode}\nresolution: 0.05\norigin: [0, 0, 0]\n"
                          f"negate: {negate}\noccupied_thresh: {occ}\nfree_thresh: {free}\n")


def load_both(tmp_path, image, **yaml):
    write_yaml(tmp_path / "m.yaml", image, **yaml)
    return [load_map(tmp_path / "m.yaml", loader=loader).to_int8()[::-1].tolist() for loader in ("humble", "jazzy")]


# --- per-pixel transcriptions of map_io.cpp (the slow reference) -------------------------------
def humble_pixel(r, g, b, alpha, mode, negate, occ_t, free_t):
    """Humble's loop body; r, g, b, alpha are Q16 quanta, alpha None without a matte channel."""
    channels = [r, g, b]
    if mode == "trinary" and alpha is not None:
        channels.append(alpha)  # MaxRGB - opacity
    shade = (sum(channels) / len(channels)) / 65535.0
    occ = shade if negate else 1.0 - shade
    if mode == "trinary":
        return 100 if occ_t < occ else 0 if occ < free_t else -1
    if mode == "scale":
        if alpha is not None and alpha != 65535:
            return -1
        if occ_t < occ:
            return 100
        if occ < free_t:
            return 0
        return int(np.rint((occ - free_t) / (occ_t - free_t) * 100.0))
    percent = math.floor(shade * 255 + 0.5)
    return percent if 0 <= percent <= 100 else -1


def jazzy_pixel(r, g, b, alpha, mode, negate, occ_t, free_t):
    """Jazzy+'s Eigen code, one pixel: GraphicsMagick grey (Rec. 601, Q16 -> 8 bit), float32 maths."""
    grey = ((306 * r + 601 * g + 117 * b) >> 10) // 257
    if mode == "raw":
        signed = grey - 256 if grey > 127 else grey  # cast<int8_t>
        return signed if 0 <= signed <= 100 else -1
    f = np.float32
    normalized = f(grey) / f(255.0)
    if not negate:
        normalized = f(1.0) - normalized
    value = -1
    if normalized >= f(occ_t):
        value = 100
    if normalized <= f(free_t):
        value = 0
    if mode == "scale" and f(free_t) < normalized < f(occ_t):
        scaled = (normalized - f(free_t)) / f(occ_t - free_t) * f(100.0)
        value = int(math.copysign(math.floor(abs(float(scaled)) + 0.5), float(scaled)))
    if alpha is not None and alpha // 257 < 255:
        value = -1
    return value


def random_pixels(rng, kind, shape=(6, 7)):
    if kind == "grey":
        return Pixels.from_grey8(rng.integers(0, 256, shape))
    if kind == "grey16":
        g = rng.integers(0, 65536, shape)
        return Pixels(g, g, g, None)
    rgb = rng.integers(0, 256, shape + (3,)) * 257
    alpha = rng.choice([0, 128, 254, 255, 255, 255], shape) * 257 if kind == "rgba" else None
    return Pixels(rgb[..., 0], rgb[..., 1], rgb[..., 2], alpha)


@pytest.mark.parametrize("loader, reference", [("humble", humble_pixel), ("jazzy", jazzy_pixel)])
@pytest.mark.parametrize("kind", ["grey", "grey16", "rgb", "rgba"])
@pytest.mark.parametrize("mode", ["trinary", "scale", "raw"])
def test_vectorised_loader_matches_the_per_pixel_transcription(loader, reference, kind, mode):
    rng = np.random.default_rng(hash((loader, kind, mode)) % 2**32)
    for negate, occ_t, free_t in [(0, 0.65, 0.196), (1, 0.65, 0.25), (0, 0.8, 0.2), (0, 1.0, 0.0),
                                  (0, 0.65098039, 0.19607843)]:
        px = random_pixels(rng, kind)
        fast = occupancy(px, mode, negate, occ_t, free_t, loader=loader)
        for (i, j), value in np.ndenumerate(fast):
            alpha = None if px.alpha is None else int(px.alpha[i, j])
            expected = reference(int(px.red[i, j]), int(px.green[i, j]), int(px.blue[i, j]), alpha,
                                 mode, negate, occ_t, free_t)
            assert value == expected, (i, j, negate, occ_t, free_t)


# --- every kind of image, by hand --------------------------------------------------------------
def test_thresholds_on_a_grey_level_are_strict_in_humble_inclusive_in_jazzy(tmp_path):
    # pixel 0: occ exactly 1; pixel 255: occ exactly 0. Thresholds 1 and 0 sit on those levels.
    write_pgm(tmp_path / "m.pgm", [[0, 255, 128]])
    humble, jazzy = load_both(tmp_path, "m.pgm", occ=1.0, free=0.0)
    assert humble == [[-1, -1, -1]]  # 1 < 1 and 0 < 0 are false
    assert jazzy == [[100, 0, -1]]    # 1 >= 1 and 0 <= 0
    # map_saver's trinary pixels read the same under both, with its thresholds
    write_pgm(tmp_path / "m.pgm", [[0, 205, 254]])
    assert load_both(tmp_path, "m.pgm") == [[[100, -1, 0]]] * 2


def test_colour_is_a_channel_mean_in_humble_and_rec601_luma_in_jazzy(tmp_path):
    # green: mean 85 -> occ 0.667 -> 100; luma (601 * 65535) >> 10 = 38463 -> 8 bits 149 -> occ 0.416 -> -1.
    # red: mean -> 100; luma 19583 -> 76 -> occ 0.702 -> 100. blue: luma 7487 -> 29 -> occ 0.886 -> 100.
    rgb = np.array([[[0, 255, 0], [255, 0, 0], [0, 0, 255], [255, 255, 255]]], np.uint8)
    Image.fromarray(rgb, "RGB").save(tmp_path / "m.png")
    humble, jazzy = load_both(tmp_path, "m.png")
    assert humble == [[100, 100, 100, 0]]
    assert jazzy == [[-1, 100, 100, 0]]


def test_alpha_below_255_is_unknown_in_jazzy_in_both_modes(tmp_path):
    # black with alpha 254: Humble trinary averages it in: (0 + 0 + 0 + 254)/4 -> occ 0.75 -> 100;
    # white with alpha 0: (3 * 255 + 0)/4 -> occ 0.25 -> -1. Jazzy: any alpha < 255 -> -1.
    rgba = np.array([[[0, 0, 0, 254], [255, 255, 255, 0], [255, 255, 255, 255], [0, 0, 0, 255]]], np.uint8)
    Image.fromarray(rgba, "RGBA").save(tmp_path / "m.png")
    humble, jazzy = load_both(tmp_path, "m.png")
    assert humble == [[100, -1, 0, 100]]
    assert jazzy == [[-1, -1, 0, 100]]
    humble, jazzy = load_both(tmp_path, "m.png", mode="scale")
    assert humble == jazzy == [[-1, -1, 0, 100]]


def test_palette_png_with_a_transparent_entry(tmp_path):
    # palette: 0 black (transparent), 1 white, 2 grey 205. Humble trinary averages alpha in: transparent
    # black -> shade 0 -> occupied, opaque 205 -> (3 * 205 + 255)/4 = 217.5 -> occ 0.147 -> free.
    # Jazzy: transparent -> unknown, 205 -> occ 0.196 -> unknown.
    img = Image.fromarray(np.array([[0, 1, 2]], np.uint8), "P")
    img.putpalette([0, 0, 0, 255, 255, 255, 205, 205, 205])
    img.save(tmp_path / "m.png", transparency=0)
    assert Image.open(tmp_path / "m.png").mode == "P"
    humble, jazzy = load_both(tmp_path, "m.png")
    assert humble == [[100, 0, 0]]
    assert jazzy == [[-1, 0, -1]]


def test_sixteen_bit_pgm(tmp_path):
    # 23000: Humble occ = 1 - 23000/65535 = 0.6490 -> -1; Jazzy exports 23000 // 257 = 89 -> occ 0.65098 -> 100.
    write_pgm(tmp_path / "m.pgm", [[23000, 0, 65535]], maxval=65535)
    humble, jazzy = load_both(tmp_path, "m.pgm")
    assert humble == [[-1, 100, 0]]
    assert jazzy == [[100, 100, 0]]


def test_mode_is_case_insensitive_and_50_stays_50(tmp_path):
    write_pgm(tmp_path / "m.pgm", [[50, 0, 100, 101]])
    humble, jazzy = load_both(tmp_path, "m.pgm", mode="Raw")
    assert humble == jazzy == [[50, 0, 100, -1]]
    grid = load_map(tmp_path / "m.yaml")
    assert grid.known()[0, 0] and grid.meta["mode"] == "raw"
    save_map(grid, tmp_path / "again.yaml")
    assert (tmp_path / "again.pgm").read_bytes()[-4:] == bytes([50, 0, 100, 255])
    write_pgm(tmp_path / "t.pgm", [[0, 205, 254]])
    write_yaml(tmp_path / "t.yaml", "t.pgm", mode="TRINARY")
    assert load_map(tmp_path / "t.yaml").to_int8().tolist() == [[100, -1, 0]]


# --- the costmap static layer --------------------------------------------------------------------
def interpret_value(value, lethal=100, trinary=True, unknown=255, track_unknown=True):
    """static_layer.cpp interpretValue, one value (an unsigned char)."""
    value &= 0xFF
    if track_unknown and value == unknown:
        return 255
    if not track_unknown and value == unknown:
        return 0
    if value >= lethal:
        return 254
    if trinary:
        return 0
    return int(value / lethal * 254)


@pytest.mark.parametrize("options", [{}, {"trinary": False}, {"track_unknown": False}, {"lethal": 65}])
def test_static_layer_matches_interpret_value(options):
    values = np.arange(-1, 101, dtype=np.int8)
    names = {"lethal": "lethal_threshold", "trinary": "trinary", "track_unknown": "track_unknown"}
    fast = static_layer_costs(values, **{names[k]: v for k, v in options.items()})
    assert fast.tolist() == [interpret_value(int(v), **options) for v in values]


# --- crfmap's maps, loaded as nav2 loads them ----------------------------------------------------
def probabilities(seed, shape=(40, 50)):
    rng = np.random.default_rng(seed)
    p = rng.random(shape)
    p[rng.random(shape) < 0.2] = 0.5
    p[0, :6] = [0.6451, 0.6449, 0.65, 0.2049, 0.2051, 0.5]  # the rounding edges of 65 and 20
    return p


@pytest.mark.parametrize("loader", ["humble", "jazzy"])
def test_default_trinary_output_is_lethal_exactly_where_crfmap_meant(tmp_path, loader):
    from types import SimpleNamespace

    from crfmap.commands.build import save_map_output

    p = probabilities(3)
    args = SimpleNamespace(mode="trinary", save_occupied_thresh=None, save_free_thresh=None, loader=loader)
    line = save_map_output(OccupancyGrid(p, resolution=0.05), tmp_path / "m.yaml", args)
    percent = np.rint(p * 100)  # the OccupancyGrid crfmap publishes; map_saver thresholds these
    meant_lethal, meant_free = (percent >= 65).sum(), ((percent <= 20) & (p != 0.5)).sum()
    counts = nav2_counts(load_map(tmp_path / "m.yaml", loader=loader).to_int8())
    assert counts == {"occupied": meant_lethal, "free": meant_free, "unknown": p.size - meant_lethal - meant_free}
    assert line.startswith(f"{meant_lethal} occupied, {meant_free} free")
    # the YAML is map_saver's (Jazzy+) and its pixels are map_saver's three
    text = (tmp_path / "m.yaml").read_text()
    assert "mode: trinary" in text and "occupied_thresh: 0.65\nfree_thresh: 0.196" in text
    grey = np.asarray(Image.open(tmp_path / "m.pgm")).astype(float)
    assert set(np.unique(grey)) <= {0, 205, 254}
    # ROS 1's map_server (image_loader.cpp) on the same pixels: occ = (255 - grey) / 255, strict thresholds
    occ = (255 - grey) / 255.0
    ros1 = np.where(occ > 0.65, 100, np.where(occ < 0.196, 0, -1))[::-1]
    np.testing.assert_array_equal(ros1, load_map(tmp_path / "m.yaml", loader=loader).to_int8())
    # 0.6451 rounds to 65: lethal, as map_saver would make it from the published grid; 0.6449 is not
    assert static_layer_costs(load_map(tmp_path / "m.yaml", loader=loader).to_int8()[0, :3]).tolist() == [
        254, 255, 254]


def test_scale_with_thresholds_one_and_zero_is_not_for_navigation(tmp_path):
    p = probabilities(4)
    save_map(OccupancyGrid(p), tmp_path / "m.yaml", mode="scale")
    counts = nav2_counts(load_map(tmp_path / "m.yaml").to_int8())
    assert counts["occupied"] == (np.rint(p * 100) == 100).sum() < (p >= 0.65).sum() / 10
    # with map_saver's thresholds, scale marks the same cells lethal as trinary
    save_map(OccupancyGrid(p), tmp_path / "s.yaml", mode="scale", occupied_thresh=0.65, free_thresh=0.196)
    assert nav2_counts(load_map(tmp_path / "s.yaml").to_int8())["occupied"] == (np.rint(p * 100) >= 65).sum()


def test_infer_and_build_print_what_nav2_will_see(tmp_path, capsys):
    from crfmap.cli import main
    from crfmap.io.grid_files import save_grid

    save_grid(OccupancyGrid(probabilities(5), resolution=0.05), tmp_path / "in.npy")
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.yaml"), "--max-iter", "5"]) == 0
    out = capsys.readouterr().out
    counts = nav2_counts(load_map(tmp_path / "out.yaml").to_int8())
    assert f"{counts['occupied']} occupied, {counts['free']} free, {counts['unknown']} unknown cells " \
           "under nav2's defaults" in out
    assert main(["infer", str(tmp_path / "in.npy"), str(tmp_path / "out.npy"), "--max-iter", "5",
                 "--save-free-thresh", "0.1"]) == 2


@pytest.mark.skipif(not crfmap.data.have_data(OLIN), reason=f"public data {OLIN} not present")
def test_olin_map_reads_the_same_under_both_loaders():
    humble = load_map(crfmap.data.data_file(OLIN), loader="humble").to_int8()
    jazzy = load_map(crfmap.data.data_file(OLIN), loader="jazzy").to_int8()
    np.testing.assert_array_equal(humble, jazzy)  # 8-bit grey 0 / 205 / 254: no rule differs there
    assert nav2_counts(jazzy)["occupied"] == (jazzy == 100).sum() > 1000
