"""Map files: map_server YAML + image (as nav2's map_io reads and writes them) and .npy grids."""
import doctest
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import crfmap.data
from crfmap.io import map_server as mapio
from crfmap.errors import InputError
from crfmap.grid import OccupancyGrid
from crfmap.io.grid_files import load_grid, save_grid
from crfmap.io.map_server import load_map, save_map

OLIN = "rosbags/olin_comprobo24_turtlebot4/mac_1st_floor_final.yaml"
have_olin = pytest.mark.skipif(not crfmap.data.have_data(OLIN), reason=f"public data {OLIN} not present")


def write_pgm(path, pixels):
    """A binary PGM, written by hand (top image row first)."""
    pixels = np.asarray(pixels, dtype=np.uint8)
    Path(path).write_bytes(b"P5\n%d %d\n255\n" % (pixels.shape[1], pixels.shape[0]) + pixels.tobytes())


def write_yaml(path, image, mode="trinary", negate=0, occ=0.65, free=0.196, resolution=0.05,
               origin="[0.0, 0.0, 0.0]"):
    Path(path).write_text(f"image: {image}\nmode: {mode}\nresolution: {resolution}\norigin: {origin}\n"
                          f"negate: {negate}\noccupied_thresh: {occ}\nfree_thresh: {free}\n")


def random_grid(seed, shape=(7, 9), origin=(1.5, -2.25, 0.7)):
    rng = np.random.default_rng(seed)
    p = rng.random(shape)
    p[rng.random(shape) < 0.2] = 0.5          # unknown cells
    p[0, 0], p[0, 1], p[1, 0] = 0.0, 1.0, 0.5  # the extremes, and unknown at row 0
    return OccupancyGrid(p, resolution=0.05, origin=origin)


def no_leftovers(folder):
    return sorted(os.listdir(folder))


# --- loading: every branch of the per-pixel rule, by hand ------------------------------------
# occ = 1 - pixel/255 (negate 0). Thresholds 0.65 / 0.196:
#   0 -> occ 1 -> 100;  89 -> 0.651 -> 100;  90 -> 0.647 -> -1;  205 -> 0.19608 -> -1;
#   206 -> 0.192 -> 0;  255 -> 0 -> 0.
TRINARY_PIXELS = [[0, 89, 90], [205, 206, 255]]
TRINARY_VALUES_TOP_FIRST = [[100, 100, -1], [-1, 0, 0]]


def test_trinary_thresholds_and_row_flip(tmp_path):
    write_pgm(tmp_path / "m.pgm", TRINARY_PIXELS)
    write_yaml(tmp_path / "m.yaml", "m.pgm")
    grid = load_map(tmp_path / "m.yaml")
    assert grid.shape == (2, 3)
    # row 0 of the grid is the lowest y = the bottom image row
    assert grid.to_int8().tolist() == TRINARY_VALUES_TOP_FIRST[::-1]
    assert grid.probability[1].tolist() == [1.0, 1.0, 0.5]


def test_pixels_exactly_at_a_threshold(tmp_path):
    # Thresholds that are multiples of 1/255; both comparisons are strict in Humble (Jazzy+: tests/io/test_nav2.py).
    # Pixel 51: occ = 1 - 0.2 = 0.8 exactly -> not occupied. Pixel 153: occ = 1 - 0.6 = 0.4 exactly
    # -> not free. Pixel 204: occ is 0.2 in exact arithmetic but 1.0 - 0.8 = 0.19999999999999996 in
    # doubles (nav2 computes the same double) -> free.
    write_pgm(tmp_path / "m.pgm", [[51, 153, 204]])
    write_yaml(tmp_path / "m.yaml", "m.pgm", occ=0.8, free=0.4)
    assert load_map(tmp_path / "m.yaml", loader="humble").to_int8().tolist() == [[-1, -1, 0]]
    write_yaml(tmp_path / "m.yaml", "m.pgm", occ=0.8, free=0.2)
    assert load_map(tmp_path / "m.yaml", loader="humble").to_int8().tolist() == [[-1, -1, 0]]
    write_yaml(tmp_path / "m.yaml", "m.pgm", occ=0.8, free=0.1999)
    assert load_map(tmp_path / "m.yaml", loader="humble").to_int8().tolist() == [[-1, -1, -1]]


def test_sixteen_bit_raw_image_rounds_like_std_round(tmp_path):
    # raw: round(shade * 255) with shade = value / 65535; 37*257 + 128 -> 37.498 -> 37, + 129 -> 37.502 -> 38
    Image.fromarray(np.array([[37 * 257 + 128, 37 * 257 + 129, 0, 65535]], dtype=np.uint16)).save(tmp_path / "m.png")
    write_yaml(tmp_path / "m.yaml", "m.png", mode="raw")
    assert load_map(tmp_path / "m.yaml", loader="humble").to_int8().tolist() == [[37, 38, 0, -1]]


def test_negate_reads_white_as_occupied(tmp_path):
    # negate 1: occ = pixel/255; 255 -> 100, 166 -> 0.651 -> 100, 165 -> 0.647 -> -1,
    # 51 -> 0.2 -> -1, 50 -> 0.19608 -> 0 (free 0.197), 0 -> 0
    write_pgm(tmp_path / "m.pgm", [[255, 166, 165, 51, 50, 0]])
    write_yaml(tmp_path / "m.yaml", "m.pgm", negate=1, free=0.197)
    assert load_map(tmp_path / "m.yaml").to_int8().tolist() == [[100, 100, -1, -1, 0, 0]]


def test_scale_mode_interpolates_and_alpha_marks_unknown(tmp_path):
    # thresholds 0.8 / 0.2. grey 120: occ = 135/255 = 0.52941 -> rint((0.52941-0.2)/0.6*100) = rint(54.90) = 55
    # grey 64: occ 0.74902 -> rint(91.50) = 92;  grey 200: occ 0.21569 -> rint(2.61) = 3
    # grey 10: occ 0.96 -> 100;  grey 250: occ 0.0196 -> 0;  grey 127 with alpha 254 -> unknown
    grey = np.array([[120, 64, 200, 10, 250, 127]], dtype=np.uint8)
    alpha = np.array([[255, 255, 255, 255, 255, 254]], dtype=np.uint8)
    Image.fromarray(np.stack([grey, grey, grey, alpha], -1), "RGBA").save(tmp_path / "m.png")
    write_yaml(tmp_path / "m.yaml", "m.png", mode="scale", occ=0.8, free=0.2)
    assert load_map(tmp_path / "m.yaml").to_int8().tolist() == [[55, 92, 3, 100, 0, -1]]


def test_raw_mode_takes_pixel_values(tmp_path):
    write_pgm(tmp_path / "m.pgm", [[0, 37, 100, 101, 255]])
    write_yaml(tmp_path / "m.yaml", "m.pgm", mode="raw", negate=1)  # nav2 ignores negate in raw mode
    assert load_map(tmp_path / "m.yaml").to_int8().tolist() == [[0, 37, 100, -1, -1]]


def test_colour_channels_are_averaged(tmp_path):
    # mean of R, G, B: (255, 0, 0) -> 85 -> occ 0.667 -> 100; (100, 150, 200) -> 150 -> occ 0.41 -> -1;
    # (254, 254, 254) -> occ 0.004 -> 0
    rgb = np.array([[[255, 0, 0], [100, 150, 200], [254, 254, 254]]], dtype=np.uint8)
    Image.fromarray(rgb, "RGB").save(tmp_path / "m.png")
    write_yaml(tmp_path / "m.yaml", "m.png")
    assert load_map(tmp_path / "m.yaml").to_int8().tolist() == [[100, -1, 0]]


def test_alpha_is_averaged_in_trinary_and_marks_unknown_in_scale(tmp_path):
    # trinary averages alpha in (nav2 and ROS 1 alike): (254, 254, 254, 0) -> 190.5 -> occ 0.253 -> -1,
    # (254, 254, 254, 255) -> 254.25 -> 0, (255, 0, 0, 255) -> 127.5 -> occ 0.5 -> -1,
    # (0, 0, 0, 255) -> 63.75 -> occ 0.75 -> 100.
    rgba = np.array([[[254, 254, 254, 0], [254, 254, 254, 255], [255, 0, 0, 255], [0, 0, 0, 255]]],
                    dtype=np.uint8)
    Image.fromarray(rgba, "RGBA").save(tmp_path / "m.png")
    write_yaml(tmp_path / "m.yaml", "m.png")
    assert load_map(tmp_path / "m.yaml", loader="humble").to_int8().tolist() == [[-1, 0, -1, 100]]
    # scale (thresholds 0.65 / 0.196) uses R, G, B only: 85 -> occ 0.667 -> 100; alpha 0 -> unknown
    write_yaml(tmp_path / "m.yaml", "m.png", mode="scale")
    assert load_map(tmp_path / "m.yaml", loader="humble").to_int8().tolist() == [[-1, 0, 100, 100]]


def test_image_path_relative_to_yaml_or_absolute(tmp_path):
    (tmp_path / "maps").mkdir()
    write_pgm(tmp_path / "maps" / "m.pgm", TRINARY_PIXELS)
    write_yaml(tmp_path / "maps" / "rel.yaml", "m.pgm")
    write_yaml(tmp_path / "abs.yaml", str(tmp_path / "maps" / "m.pgm"))
    assert load_map(tmp_path / "maps" / "rel.yaml").to_int8().tolist() == TRINARY_VALUES_TOP_FIRST[::-1]
    assert load_map(tmp_path / "abs.yaml").to_int8().tolist() == TRINARY_VALUES_TOP_FIRST[::-1]


def test_meta_keeps_the_yaml_values(tmp_path):
    write_pgm(tmp_path / "m.pgm", TRINARY_PIXELS)
    write_yaml(tmp_path / "m.yaml", "m.pgm", negate=0, occ=0.7, free=0.1, resolution=0.025,
               origin="[1.5, -2, 0.25]")
    grid = load_map(tmp_path / "m.yaml")
    assert grid.resolution == 0.025 and grid.origin == (1.5, -2.0, 0.25) and grid.frame_id == "map"
    for key, value in dict(image="m.pgm", mode="trinary", negate=0, occupied_thresh=0.7, free_thresh=0.1).items():
        assert grid.meta[key] == value


def test_threshold_override_applies_to_loading_only(tmp_path):
    write_pgm(tmp_path / "m.pgm", [[205, 254, 0]])
    write_yaml(tmp_path / "m.yaml", "m.pgm", free=0.25)
    assert load_map(tmp_path / "m.yaml").to_int8().tolist() == [[0, 0, 100]]  # nav2: 205 is free
    grid = load_map(tmp_path / "m.yaml", free_thresh=0.196)
    assert grid.to_int8().tolist() == [[-1, 0, 100]]
    assert grid.meta["free_thresh"] == 0.25


# --- saving: the pixels nav2's map_saver writes ----------------------------------------------
def read_pgm(path):
    data = Path(path).read_bytes()
    assert data.startswith(b"P5\n")
    header_end = data.index(b"\n255\n") + 5
    width, height = map(int, data[3:header_end - 5].split())
    return np.frombuffer(data[header_end:], np.uint8).reshape(height, width)


def test_trinary_save_writes_254_0_205(tmp_path):
    values = np.array([[0, 20, 21, 64], [65, 100, -1, 50]], dtype=np.int8)  # row 0 = lowest y
    grid = OccupancyGrid.from_int8(values)
    save_map(grid, tmp_path / "m.yaml", occupied_thresh=0.65, free_thresh=0.196)  # rint: 20 and 65
    pixels = read_pgm(tmp_path / "m.pgm")
    expected_map_order = np.where(values < 0, 205, np.where(values <= 20, 254, np.where(values >= 65, 0, 205)))
    assert pixels.tolist() == expected_map_order[::-1].tolist()


def test_scale_save_writes_nav2_grey_levels(tmp_path):
    values = np.array([[0, 10, 37, 100, -1]], dtype=np.int8)
    save_map(OccupancyGrid.from_int8(values), tmp_path / "m.yaml", mode="scale", occupied_thresh=0.65,
             free_thresh=0.25)
    rgba = np.asarray(Image.open(tmp_path / "m.png"))
    assert rgba.shape == (1, 5, 4)
    grey = rgba[0, :, 0].astype(int)
    assert abs(grey[:4] - 255 * (100 - values[0, :4].astype(float)) / 100).max() <= 0.5
    assert rgba[0, :, 3].tolist() == [255, 255, 255, 255, 0]
    assert "occupied_thresh: 0.65\nfree_thresh: 0.25" in (tmp_path / "m.yaml").read_text()


def test_yaml_text_matches_nav2_map_saver_layout(tmp_path):
    grid = OccupancyGrid(np.full((2, 2), 0.5), resolution=0.03, origin=(-1.12, -39.4, 0.0))
    save_map(grid, tmp_path / "m.yaml", occupied_thresh=0.65, free_thresh=0.25)
    assert (tmp_path / "m.yaml").read_text() == ("image: m.pgm\nmode: trinary\nresolution: 0.03\n"
                                                 "origin: [-1.12, -39.4, 0]\nnegate: 0\n"
                                                 "occupied_thresh: 0.65\nfree_thresh: 0.25")
    assert doctest.testmod(mapio).failed == 0


# --- round trips ----------------------------------------------------------------------------
def negate_copy(yaml_path, out_yaml):
    """The same map with inverted grey levels and ``negate: 1`` (alpha kept)."""
    text = Path(yaml_path).read_text()
    image = Path(yaml_path).with_suffix(".pgm" if "pgm" in text else ".png")
    out_image = Path(out_yaml).with_suffix(image.suffix)
    img = np.asarray(Image.open(image)).copy()
    if img.ndim == 3:
        img[..., :3] = 255 - img[..., :3]
    else:
        img = 255 - img
    Image.fromarray(img).save(out_image, format="PNG" if image.suffix == ".png" else "PPM")
    Path(out_yaml).write_text(text.replace(f"image: {image.name}", f"image: {out_image.name}")
                              .replace("negate: 0", "negate: 1"))


@pytest.mark.parametrize("negate", [0, 1])
@pytest.mark.parametrize("image_format", ["pgm", "png"])
def test_trinary_round_trip(tmp_path, image_format, negate):
    grid = random_grid(1)
    save_map(grid, tmp_path / "m.yaml", image_format=image_format)  # defaults 0.65 / 0.196
    path = tmp_path / "m.yaml"
    if negate:
        negate_copy(path, tmp_path / "n.yaml")
        path = tmp_path / "n.yaml"
    back = load_map(path)
    v = grid.to_int8()
    expected = np.where(v < 0, -1, np.where(v <= 20, 0, np.where(v >= 65, 100, -1)))
    assert back.to_int8().tolist() == expected.tolist()
    assert back.resolution == grid.resolution and back.origin == grid.origin
    assert back.meta["negate"] == negate
    # written back again (meta reused), it reloads to the same values
    save_map(back, tmp_path / "again.yaml")
    assert load_map(tmp_path / "again.yaml").to_int8().tolist() == expected.tolist()


@pytest.mark.parametrize("negate", [0, 1])
@pytest.mark.parametrize("image_format", ["png", "pgm"])
def test_scale_round_trip_within_half_a_percent(tmp_path, image_format, negate):
    grid = random_grid(2)
    save_map(grid, tmp_path / "m.yaml", mode="scale", image_format=image_format)
    path = tmp_path / "m.yaml"
    if negate:
        negate_copy(path, tmp_path / "n.yaml")
        path = tmp_path / "n.yaml"
    back = load_map(path)
    v = grid.to_int8()
    if image_format == "pgm":  # no alpha: unknown is grey 128, which map_server reads (and publishes) as 50
        pixels = read_pgm(path.with_suffix(".pgm"))[::-1]
        assert (pixels[v < 0] == (127 if negate else 128)).all()
        v = np.where(v < 0, 50, v)
    assert back.to_int8().tolist() == v.tolist()
    known = grid.known()
    assert np.abs(back.probability - grid.probability)[known].max() <= 0.005 + 1e-12
    assert np.allclose(back.probability[~known], 0.5)
    assert back.origin == grid.origin and back.resolution == grid.resolution


def test_exact_round_trip_of_odd_metadata(tmp_path):
    grid = random_grid(3, origin=(-12.345678901234, 1e-7, -3.0))
    grid.resolution = 0.0123456789
    save_map(grid, tmp_path / "m.yaml", mode="scale")
    back = load_map(tmp_path / "m.yaml")
    assert back.origin == grid.origin and back.resolution == grid.resolution


# --- the real Olin College map (written by nav2's map_saver) ----------------------------------
@have_olin
def test_olin_map_loads_like_map_server():
    path = crfmap.data.data_file(OLIN)
    data = path.with_suffix(".pgm").read_bytes()
    header = data[:16].split()
    assert header[0] == b"P5" and header[3] == b"255"
    width, height = int(header[1]), int(header[2])
    pixels = np.frombuffer(data[16:], np.uint8).reshape(height, width)
    grid = load_map(path)
    assert grid.shape == (height, width) == (1706, 903)
    assert grid.resolution == 0.03 and grid.origin == (-1.12, -39.4, 0.0)
    occ = 1.0 - pixels / 255.0
    expected = np.where(occ > 0.65, 100, np.where(occ < 0.25, 0, -1))[::-1]
    values = grid.to_int8()
    for value in (100, 0, -1):
        assert np.count_nonzero(values == value) == np.count_nonzero(expected == value)
    assert (values == expected).all()
    assert np.count_nonzero(values == -1) == 0  # free_thresh 0.25: 205 reads as free, as in nav2
    strict = load_map(path, free_thresh=0.196)
    assert np.count_nonzero(strict.to_int8() == -1) == np.count_nonzero(pixels == 205) > 0


@have_olin
def test_olin_map_writes_back(tmp_path):
    path = crfmap.data.data_file(OLIN)
    grid = load_map(path)
    save_map(grid, tmp_path / path.name)
    again = load_map(tmp_path / path.name)
    assert (again.to_int8() == grid.to_int8()).all()
    assert again.resolution == grid.resolution and again.origin == grid.origin
    assert (tmp_path / path.name).read_bytes() == path.read_bytes()  # same YAML, no final newline
    original = read_pgm(path.with_suffix(".pgm"))
    written = read_pgm(tmp_path / path.with_suffix(".pgm").name)
    assert ((written == original) | ((original == 205) & (written == 254))).all()  # unknown became free
    # loaded with ROS 1's free threshold, unknown stays unknown and the image is byte-identical
    strict = load_map(path, free_thresh=0.196)
    save_map(strict, tmp_path / "strict" / path.name)
    assert (tmp_path / "strict" / path.with_suffix(".pgm").name).read_bytes() == path.with_suffix(".pgm").read_bytes()
    assert (tmp_path / "strict" / path.name).read_bytes() == path.read_bytes()


# --- bad input ------------------------------------------------------------------------------
GOOD = {"image": "m.pgm", "mode": "trinary", "resolution": "0.05", "origin": "[0, 0, 0]", "negate": "0",
        "occupied_thresh": "0.65", "free_thresh": "0.196"}


def yaml_with(**changes):
    keys = dict(GOOD, **changes)
    return "".join(f"{k}: {v}\n" for k, v in keys.items() if v is not None)


@pytest.mark.parametrize("text, problem", [
    ("image: [unclosed\n", "not valid YAML"),
    ("- a\n- b\n", "expected a YAML mapping"),
    ("", "expected a YAML mapping"),
    (yaml_with(resolution=None), "missing key 'resolution'"),
    (yaml_with(image=None), "missing key 'image'"),
    (yaml_with(origin=None), "missing key 'origin'"),
    (yaml_with(negate=None), "missing key 'negate'"),
    (yaml_with(free_thresh=None), "missing key 'free_thresh'"),
    (yaml_with(occupied_thresh=None), "missing key 'occupied_thresh'"),
    (yaml_with(resolution="abc"), "'resolution' must be a number"),
    (yaml_with(resolution="-0.05"), "'resolution' must be positive"),
    (yaml_with(origin="[0, 0]"), "'origin' must be a list"),
    (yaml_with(origin="3"), "'origin' must be a list"),
    (yaml_with(origin="[0, zero, 0]"), "'origin' must be a number"),
    (yaml_with(negate="2"), "'negate' must be 0, 1"),
    (yaml_with(negate="maybe"), "'negate' must be 0, 1"),
    (yaml_with(occupied_thresh="1.5"), "'occupied_thresh' must lie in [0, 1]"),
    (yaml_with(free_thresh="-0.1"), "'free_thresh' must lie in [0, 1]"),
    (yaml_with(free_thresh="0.7"), "must be smaller than occupied_thresh"),
    (yaml_with(free_thresh="0.65"), "must be smaller than occupied_thresh"),
    (yaml_with(mode="binary"), "unknown mode 'binary'"),
    (yaml_with(image="''"), "key 'image' must be an image file name"),
])
def test_bad_yaml_is_an_input_error(tmp_path, text, problem):
    write_pgm(tmp_path / "m.pgm", TRINARY_PIXELS)
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(InputError) as err:
        load_map(tmp_path / "bad.yaml")
    assert "bad.yaml" in str(err.value) and problem in str(err.value)


def test_missing_yaml_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="nothere.yaml: map YAML file not found"):
        load_map(tmp_path / "nothere.yaml")


@pytest.mark.parametrize("content, problem", [
    (None, "image file not found"),
    (b"", "empty image file"),
    (b"this is not an image at all", "not an image Pillow can read"),
    (b"P5\n0 0\n255\n", "empty image (0 x 0 pixels)"),
    (b"P5\n4 3\n255\n" + bytes(5), "truncated image"),
    (b"\x89PNG\r\n\x1a\n" + bytes(30), "m.pgm"),
])
def test_bad_image_is_an_input_error(tmp_path, content, problem):
    if content is not None:
        (tmp_path / "m.pgm").write_bytes(content)
    (tmp_path / "map.yaml").write_text(yaml_with())
    with pytest.raises(InputError) as err:
        load_map(tmp_path / "map.yaml")
    message = str(err.value)
    assert "m.pgm" in message and "map.yaml" in message and problem in message


def test_truncated_png_is_an_input_error(tmp_path):
    Image.fromarray(np.random.default_rng(0).integers(0, 255, (64, 64), dtype=np.uint8)).save(tmp_path / "m.png")
    data = (tmp_path / "m.png").read_bytes()
    (tmp_path / "m.png").write_bytes(data[: len(data) // 2])
    (tmp_path / "map.yaml").write_text(yaml_with(image="m.png"))
    with pytest.raises(InputError, match="m.png: unreadable image"):
        load_map(tmp_path / "map.yaml")


@pytest.mark.parametrize("kwargs, problem", [({"mode": "binary"}, "unknown map mode"),
                                             ({"image_format": "jpg"}, "not supported"),
                                             ({"free_thresh": 0.7}, "must be smaller")])
def test_bad_save_options(tmp_path, kwargs, problem):
    with pytest.raises(InputError, match=problem):
        save_map(random_grid(0), tmp_path / "m.yaml", **kwargs)
    assert no_leftovers(tmp_path) == []


# --- atomic saving --------------------------------------------------------------------------
def _half_image(path, *args):
    Path(path).write_bytes(b"P5\n")  # half an image, then a crash
    raise OSError("disk full")


def _half_yaml(path, text):
    Path(path).write_text(text[:5])
    raise OSError("disk full")


@pytest.mark.parametrize("writer, broken", [("_write_image", _half_image), ("_write_text", _half_yaml)],
                         ids=["image write fails", "yaml write fails (the new image is removed)"])
def test_failed_write_leaves_nothing(tmp_path, monkeypatch, writer, broken):
    monkeypatch.setattr(mapio, writer, broken)
    with pytest.raises(OSError, match="disk full"):
        save_map(random_grid(0), tmp_path / "m.yaml")
    assert no_leftovers(tmp_path) == []


def test_failed_save_keeps_the_old_files(tmp_path, monkeypatch):
    save_map(random_grid(0), tmp_path / "m.yaml")
    before = {name: (tmp_path / name).read_bytes() for name in no_leftovers(tmp_path)}
    monkeypatch.setattr(mapio, "_write_image", lambda *a: (_ for _ in ()).throw(OSError("disk full")))
    with pytest.raises(OSError):
        save_map(random_grid(1), tmp_path / "m.yaml")
    assert {name: (tmp_path / name).read_bytes() for name in no_leftovers(tmp_path)} == before


# --- by suffix ------------------------------------------------------------------------------
def test_grid_files_by_suffix(tmp_path):
    grid = random_grid(5)
    save_grid(grid, tmp_path / "a.npy")
    save_grid(grid, tmp_path / "b.yml", mode="scale")
    assert np.array_equal(load_grid(tmp_path / "a.npy").probability, grid.probability)
    assert np.array_equal(load_grid(tmp_path / "b.yml").to_int8(), grid.to_int8())
    for bad in ("c.txt", "noext"):
        with pytest.raises(InputError, match=f"{bad}: unsupported grid file type"):
            load_grid(tmp_path / bad)
        with pytest.raises(InputError, match=f"{bad}: unsupported grid file type"):
            save_grid(grid, tmp_path / bad)
    with pytest.raises(InputError, match="only apply to map_server maps"):
        save_grid(grid, tmp_path / "d.npy", mode="scale")
