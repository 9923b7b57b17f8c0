"""The catalogue, continued: what a hostile-input and fault campaign found (issue 40), one class per kind.

- ``misread``: a command that would replace its input through a file the input names (a map YAML's
  ``image:``), grids whose cells are not what they say (a masked array, NaN written in after the grid
  was made) -- refused, not silently read or written;
- ``concurrency``: a second writer of the same new bag folder (the ``rival`` fault): refused, the
  first writer's folder intact;
- ``unbounded``: the live node's map over the CLI's cell limit (refused, logged once);
- ``api``: library calls with arguments of the wrong kind: one InputError naming the argument.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cases import CASES, Case, case, cli
from fixtures import GOOD_YAML, carmen_log, good_bag, good_grid, good_npy, tf_bag


# --- misread: data lost or misread ------------------------------------------------------------------
def _input_names_output_image(image):
    def setup(d):
        (Path(d) / image).write_bytes(b"P5\n8 6\n255\n" + bytes([254]) * 48)  # the input's image ...
        (Path(d) / "in.yaml").write_text(GOOD_YAML.replace("img.pgm", image))
        return cli("infer", Path(d) / "in.yaml", Path(d) / "out.yaml", names=["out.yaml"])  # ... is out.yaml's
    return setup


CASES.append(Case("misread", "infer-input-image-is-the-output-pgm", _input_names_output_image("out.pgm")))
CASES.append(Case("misread", "infer-input-image-is-the-output-png", _input_names_output_image("out.png")))


@case("misread", "infer-input-image-by-absolute-path-is-the-output")
def _(d):
    (Path(d) / "out.pgm").write_bytes(b"P5\n8 6\n255\n" + bytes([254]) * 48)
    (Path(d) / "in.yaml").write_text(GOOD_YAML.replace("img.pgm", str(Path(d) / "out.pgm")))
    return cli("infer", Path(d) / "in.yaml", Path(d) / "out.yaml", names=["out.yaml"])


def _grid_call(name, call, names):
    def setup(d):
        return dict(call=lambda: call(Path(d)), names=names)
    CASES.append(Case("misread", name, setup))


def _masked(d, fully):
    from crfmap.crf import infer

    values = np.ma.masked_all((4, 5)) if fully else np.ma.masked_greater(np.full((4, 5), 0.5), 0.4)
    infer(values)


def _nan_written_in(d, name):
    from crfmap.io.grid_files import save_grid

    grid = good_grid()
    grid.probability[2, 3] = np.nan  # after the grid was checked
    save_grid(grid, d / name)


_grid_call("infer-fully-masked-array", lambda d: _masked(d, True), ["grid"])
_grid_call("infer-masked-array", lambda d: _masked(d, False), ["grid"])
_grid_call("save-npy-nan-written-in", lambda d: _nan_written_in(d, "o.npy"), ["o.npy"])
_grid_call("save-map-nan-written-in", lambda d: _nan_written_in(d, "o.yaml"), ["o.yaml"])


# --- concurrency: a rival writer of the same new bag folder ------------------------------------------
@case("concurrency", "simulate-into-a-folder-a-rival-creates", fault="rival")
def _(d):
    return dict(cli("simulate", "x", Path(d) / "sim", "--quiet", "--beams", "8", names=["sim"]), rival="sim")


@case("concurrency", "convert-into-a-bag-folder-a-rival-creates", fault="rival")
def _(d):
    return dict(cli("convert", carmen_log(d), Path(d) / "out", names=["out"]), rival="out")


# --- unbounded: the live node refuses what the command line refuses -----------------------------------
@case("unbounded", "node-map-over-max-cells")
def _(d):
    def call():
        from types import SimpleNamespace as NS

        from crfmap.errors import InputError
        from crfmap.ros.messages import BadMessage, grid_message, occupancy_grid

        stamp = NS(sec=1, nanosec=0)
        native = NS(header=NS(stamp=stamp, frame_id="map"),  # a 10001 x 10001 map, one byte a cell
                    info=NS(map_load_time=stamp, resolution=0.05, width=10001, height=10001,
                            origin=NS(position=NS(x=0.0, y=0.0, z=0.0), orientation=NS(x=0.0, y=0.0, z=0.0, w=1.0))),
                    data=bytes(10001 * 10001))
        try:
            occupancy_grid(grid_message(native))
        except BadMessage as exc:  # what the node logs (once) before it goes on
            raise InputError("/map", f"{exc.reason} [{exc.kind}]") from None
    return dict(call=call, names=["/map"], env={"CRFMAP_MAX_CELLS": None})


# --- api: library calls with arguments of the wrong kind -----------------------------------------------
def _api(name, call, names, prep=None):
    def setup(d):
        made = prep(Path(d)) if prep else None
        return dict(call=lambda: call(Path(d), made), names=names)
    CASES.append(Case("api", name, setup))


def _infer(**kw):
    from crfmap.crf import infer

    return infer(np.full((4, 4), 0.5), **kw)


def _imp(module, attr):
    import importlib

    return getattr(importlib.import_module(module), attr)


def _mapper():
    from crfmap.mapping import OnlineMapper

    return OnlineMapper.for_sensor((0.0, 0.0, 4.0, 4.0), 0.1, -1.0, 0.5, 5, 0.1, 3.0)


_api("infer-tol-text", lambda d, m: _infer(tol="abc"), ["tol"])
_api("infer-tol-None", lambda d, m: _infer(tol=None), ["tol"])
_api("infer-dtype-text", lambda d, m: _infer(dtype="abc"), ["dtype"])
_api("infer-dtype-None", lambda d, m: _infer(dtype=None), ["dtype"])
_api("infer-dtype-int", lambda d, m: _infer(dtype=np.int32), ["dtype"])
_api("infer-max-iter-True", lambda d, m: _infer(max_iter=True), ["max_iter"])
_api("flooding-damping-text", lambda d, m: _imp("crfmap.crf.inference.schedules", "Flooding")(damping="0.5"),
     ["damping"])
_api("load-map-occupied-thresh-2", lambda d, m: _imp("crfmap.io.map_server", "load_map")(m, occupied_thresh=2.0),
     ["occupied_thresh"], prep=lambda d: good_npy(d) and _good_map(d))
_api("load-map-free-thresh-text", lambda d, m: _imp("crfmap.io.map_server", "load_map")(m, free_thresh="low"),
     ["free_thresh"], prep=lambda d: _good_map(d))
_api("save-map-occupied-thresh-text",
     lambda d, m: _imp("crfmap.io.map_server", "save_map")(good_grid(), d / "o.yaml", occupied_thresh="x"),
     ["occupied_thresh"])
_api("grid-origin-1.7e308", lambda d, m: _imp("crfmap.grid", "OccupancyGrid")(np.full((2, 2), 0.5), 0.05,
                                                                             origin=(1.7e308, 0.0, 0.0)), ["origin"])
_api("grid-origin-text", lambda d, m: _imp("crfmap.grid", "OccupancyGrid")(np.full((2, 2), 0.5), 0.05,
                                                                          origin="abc"), ["origin"])
_api("grid-resolution-True", lambda d, m: _imp("crfmap.grid", "OccupancyGrid")(np.full((2, 2), 0.5), True),
     ["resolution"])
_api("online-integrate-pose-text", lambda d, m: _mapper().integrate(np.ones(5, np.float32), "abc"), ["laser_pose"])
_api("online-integrate-pose-column", lambda d, m: _mapper().integrate(np.ones(5, np.float32), np.ones((3, 1))),
     ["laser_pose"])
_api("online-mapper-tol-text", lambda d, m: _imp("crfmap.mapping", "OnlineMapper").for_sensor(
    (0.0, 0.0, 4.0, 4.0), 0.1, -1.0, 0.5, 5, 0.1, 3.0, tol="abc"), ["tol"])


def _good_map(d):
    from fixtures import good_map

    return good_map(d)


# --- ros2: what the bag-reading libraries raise on a lying or empty bag ---------------------------------
def _claims_zstd(mode):
    def setup(d):
        bag = good_bag(d)  # uncompressed
        meta = bag / "metadata.yaml"
        text = meta.read_text()
        text = text.replace("compression_format: ''", "compression_format: zstd")
        meta.write_text(text.replace("compression_mode: ''", f"compression_mode: {mode}"))
        return cli("build", bag, Path(d) / "out.yaml", names=["bag"])
    return setup


CASES.append(Case("ros2", "metadata-claims-zstd-file-compression", _claims_zstd("FILE")))
CASES.append(Case("ros2", "metadata-claims-zstd-message-compression", _claims_zstd("MESSAGE")))


@case("ros2", "mcap-of-its-magic-alone")
def _(d):
    (Path(d) / "m.mcap").write_bytes(b"\x89MCAP0\r\n")
    return cli("build", Path(d) / "m.mcap", Path(d) / "out.yaml", names=["m.mcap"])


@case("ros2", "mcap-of-its-magic-alone-in-a-bag-folder")
def _(d):
    bag = good_bag(d)
    for f in bag.glob("*.mcap"):
        f.write_bytes(b"\x89MCAP0\r\n")
    return cli("build", bag, Path(d) / "out.yaml", names=["bag"])


# --- environment: the middleware's configuration, thread counts, the kernel cache ------------------------
def _node_refine_with(uri):
    def setup(d):
        return dict(cli("node", "refine", names=["CYCLONEDDS_URI"]),
                    env={"CYCLONEDDS_URI": uri.format(d=d), "ROS_DOMAIN_ID": "0"})
    return setup


CASES.append(Case("environment", "CYCLONEDDS_URI-missing-file", _node_refine_with("{d}/cyclonedds.xml")))
CASES.append(Case("environment", "CYCLONEDDS_URI-file-uri-missing", _node_refine_with("file://{d}/none.xml")))
CASES.append(Case("environment", "CYCLONEDDS_URI-not-xml", _node_refine_with("<CycloneDDS><Domain")))
CASES.append(Case("environment", "CYCLONEDDS_URI-unknown-interface", _node_refine_with(
    "<CycloneDDS><Domain><General><Interfaces><NetworkInterface name='nosuch0'/></Interfaces></General></Domain>"
    "</CycloneDDS>")))
CASES.append(Case("environment", "CYCLONEDDS_URI-http", _node_refine_with("http://example.com/dds.xml")))


@case("environment", "NUMBA_NUM_THREADS=1000-under-a-memory-limit", subprocess=True)
def _(d):  # numba would start 1000 OpenMP threads at its first parallel loop: libgomp aborts under RLIMIT_AS
    good_npy(d)
    return dict(cli("infer", Path(d) / "in.npy", Path(d) / "out.npy", names=["NUMBA_NUM_THREADS"]),
                env={"NUMBA_NUM_THREADS": "1000"})


@case("environment", "NUMBA_CACHE_DIR-unwritable-usage-error-named-first")
def _(d):  # a user who cannot write the venv's cache still reads the command line's own error (and --help)
    good_npy(d)
    return dict(cli("infer", Path(d) / "in.npy", names=["output"]), env={"NUMBA_CACHE_DIR": "/proc/crfmap-numba"})


# --- output: standard output on a full disk --------------------------------------------------------------
def _whole_npy(d):
    from crfmap.io.grid_files import load_grid

    try:
        grid = load_grid(Path(d) / "out.npy")
    except Exception as exc:  # noqa: BLE001  (any failure to read it back is the finding)
        return f"out.npy not whole: {exc}"
    return None if grid.shape == good_grid().shape else f"out.npy has shape {grid.shape}"


@case("output", "infer-stdout-on-a-full-disk")
def _(d):  # the outputs are complete before the report fails: the line says so (it used to say nothing was written)
    return dict(cli("infer", good_npy(d), Path(d) / "out.npy", names=["standard output"]), stdout="full",
                written=["out.npy", "out.npy.yaml"], whole=_whole_npy)


@case("output", "infer-stdout-on-a-full-disk-child", subprocess=True)
def _(d):
    return dict(cli("infer", good_npy(d), Path(d) / "out.npy", names=["standard output"]), stdout="full",
                written=["out.npy", "out.npy.yaml"], whole=_whole_npy)


# --- api: the learning functions (crfmap.assess.learning) with arguments of the wrong shape or kind --------
def _learning(function, *args, **kw):
    from crfmap.assess import learning

    observed = np.full((6, 6), 0.5)
    truth = np.zeros((6, 6))
    truth[2:4] = 1.0
    if function.startswith("learn_"):
        kw.setdefault("progress", False)
    return getattr(learning, function)(observed, truth, *args, **kw)


_HIDDEN, _LINK = [[10.0, 1.0], [1.0, 10.0]], [[1.0, 0.0], [0.0, 1.0]]
_api("learning-pseudolikelihood-mask-of-another-shape",
     lambda d, m: _learning("pseudolikelihood", _HIDDEN, _LINK, mask=np.ones((5, 5), bool)), ["mask"])
_api("learning-pseudolikelihood-mask-of-floats",
     lambda d, m: _learning("pseudolikelihood", _HIDDEN, _LINK, mask=np.full((6, 6), 0.3)), ["mask"])
_api("learning-pseudolikelihood-mask-empty",
     lambda d, m: _learning("pseudolikelihood", _HIDDEN, _LINK, mask=np.zeros((6, 6), bool)), ["mask"])
_api("learning-fit-mask-a-row", lambda d, m: _learning("learn_pseudolikelihood", mask=np.ones(6, bool)), ["mask"])
_api("learning-hidden-3x3", lambda d, m: _learning("learn_gradient", np.ones((3, 3))), ["hidden"])
_api("learning-link-a-pair", lambda d, m: _learning("learn_thesis", _HIDDEN, np.ones(2)), ["link"])
_api("learning-rescale-3x3", lambda d, m: _imp("crfmap.assess.learning", "rescale")(np.ones((3, 3)), _LINK),
     ["hidden"])
_api("learning-lbp-options-a-list", lambda d, m: _learning("learn_thesis", lbp_options=[("max_iter", 2)]),
     ["lbp_options"])
_api("learning-lbp-options-unknown-key", lambda d, m: _learning("lbp_mse", _HIDDEN, _LINK, {"iterations": 2}),
     ["lbp_options"])
_api("learning-thesis-alpha-text", lambda d, m: _learning("learn_thesis", alpha="0.1"), ["alpha"])
_api("learning-thesis-max-rounds-text", lambda d, m: _learning("learn_thesis", max_rounds="3"), ["max_rounds"])
_api("learning-gradient-steps-text", lambda d, m: _learning("learn_gradient", steps="3"), ["steps"])
_api("learning-gradient-delta-zero", lambda d, m: _learning("learn_gradient", delta=0.0), ["delta"])
_api("learning-pl-learning-rate-text", lambda d, m: _learning("learn_pseudolikelihood", learning_rate="a"),
     ["learning_rate"])
_api("learning-pl-tol-nan", lambda d, m: _learning("learn_pseudolikelihood", tol=float("nan")), ["tol"])


# --- ros1 / ros2: fields that lie about sizes and places ------------------------------------------------
def _patched_chunk(d, patch):
    """A good ROS 1 bag whose first chunk record is changed by ``patch(data, pos, header_length, header)``."""
    import struct

    from crfmap.io.rosbag1_files import BAG_MAGIC, OP_CHUNK, parse_header_fields

    path = good_bag(d, "b.bag", fmt="ros1")
    data = bytearray(path.read_bytes())
    pos = len(BAG_MAGIC)
    while pos < len(data):
        (header_length,) = struct.unpack_from("<I", data, pos)
        header = bytes(data[pos + 4: pos + 4 + header_length])
        if parse_header_fields(header)["op"] == bytes([OP_CHUNK]):
            patch(data, pos, header_length, header)
            break
        pos += 8 + header_length + struct.unpack_from("<I", data, pos + 4 + header_length)[0]
    path.write_bytes(bytes(data))
    return path


def _chunk_case(name, patch):
    CASES.append(Case("ros1", name, lambda d: cli("build", _patched_chunk(d, patch), Path(d) / "out.yaml",
                                                   names=["b.bag"])))


def _stated_size(value=None):
    """The chunk's ``size`` field set to ``value`` (None: one byte more than it stores)."""
    def patch(data, pos, header_length, header):
        import struct

        stored = struct.unpack_from("<I", data, pos + 4 + header_length)[0]
        at = pos + 4 + header.index(b"size=") + len(b"size=")
        data[at: at + 4] = (stored + 1 if value is None else value).to_bytes(4, "little")
    return patch


def _data_length(value):
    def patch(data, pos, header_length, header):
        data[pos + 4 + header_length: pos + 8 + header_length] = value.to_bytes(4, "little")
    return patch


def _compression(name):
    def patch(data, pos, header_length, header):
        at = pos + 4 + header.index(b"compression=none") + len(b"compression=")
        data[at: at + 4] = name
    return patch


_chunk_case("chunk-states-0xFFFFFFFF-bytes", _stated_size(0xFFFFFFFF))
_chunk_case("chunk-states-one-byte-more", _stated_size())
_chunk_case("chunk-data-length-0xFFFFFFFF", _data_length(0xFFFFFFFF))
_chunk_case("chunk-compression-unknown", _compression(b"zzzz"))


@case("ros2", "tf-translation-1e300")
def _(d):
    return cli("build", tf_bag(d, (0.0, 0.0, 0.0, 1.0), x0=1e300), Path(d) / "out.yaml", names=["tfbag"])


@case("ros1", "tf-translation-2e8")
def _(d):  # beyond crfmap.grid.MAX_EXTENT_M (1e8 m); UTM's 1e7 m northings stay accepted
    return cli("build", tf_bag(d, (0.0, 0.0, 0.0, 1.0), fmt="ros1", x0=2e8), Path(d) / "out.yaml",
               names=["tfbag.bag"])


@case("unbounded", "node-transform-1e300")
def _(d):
    def call():
        from types import SimpleNamespace as NS

        from crfmap.errors import InputError
        from crfmap.ros.messages import transforms_of

        header = NS(stamp=NS(sec=1, nanosec=0), frame_id="odom")
        far = NS(header=header, child_frame_id="base_link",
                 transform=NS(translation=NS(x=1e300, y=0.0, z=0.0), rotation=NS(x=0.0, y=0.0, z=0.0, w=1.0)))
        transforms, faults = transforms_of(NS(transforms=[far]))
        if faults:  # what the node logs (once a kind) before it goes on without the transform
            raise InputError("/tf", f"{faults[0].reason} [{faults[0].kind}]")
    return dict(call=call, names=["/tf"])


# --- api: garbage once accepted: float masks, preset fields of the wrong kind, tables beyond the dtype ------
def _preset_with(**fields):
    from dataclasses import replace

    from crfmap.crf.presets import get_preset

    return replace(get_preset(), **fields).refine(np.full((4, 4), 0.5))


_api("infer-region-of-floats", lambda d, m: _infer(region=np.full((4, 4), 0.3)), ["region"])
_api("infer-region-of-ints", lambda d, m: _infer(region=np.ones((4, 4), int)), ["region"])
_api("near-cells-mask-of-floats", lambda d, m: _imp("crfmap.crf.inference.regions", "near_cells")(
    np.full((4, 4), 0.3), 1), ["mask"])
_api("preset-refine-within-of-floats", lambda d, m: _imp("crfmap.crf.presets", "get_preset")().refine(
    np.full((4, 4), 0.5), within=np.full((4, 4), 0.3)), ["within"])
_api("preset-margin-2.5", lambda d, m: _preset_with(margin=2.5), ["margin"])
_api("preset-margin-True", lambda d, m: _preset_with(margin=True), ["margin"])
_api("preset-limit-NaN", lambda d, m: _preset_with(limit=float("nan")), ["limit"])
_api("preset-occupied-one-number", lambda d, m: _preset_with(occupied=(1.5,)), ["occupied"])
_api("preset-hidden-3x3", lambda d, m: _preset_with(hidden=np.ones((3, 3))), ["hidden"])
_api("infer-float32-hidden-1e39", lambda d, m: _infer(hidden=[[1e39, 1.0], [1.0, 10.0]], dtype=np.float32,
                                                      schedule="flooding"), ["hidden"])
_api("infer-float32-link-1e-39", lambda d, m: _infer(link=[[1.0, 1e-39], [1e-39, 1.0]], dtype=np.float32),
     ["link"])
_api("save-grid-trailing-slash", lambda d, m: _imp("crfmap.io.grid_files", "save_grid")(good_grid(),
                                                                                        str(d / "out.npy") + "/"),
     ["out.npy/"])
_api("load-grid-trailing-slash", lambda d, m: _imp("crfmap.io.grid_files", "load_grid")(str(m) + "/"), ["in.npy/"],
     prep=lambda d: good_npy(d))


# --- output: names that are not grid files, refused before the work ---------------------------------------
@case("output", "infer-output-trailing-slash")
def _(d):
    return cli("infer", good_npy(d), str(Path(d) / "out.npy") + "/", names=["out.npy/"])


@case("output", "infer-yaml-output-trailing-slash")
def _(d):
    return cli("infer", good_npy(d), str(Path(d) / "out.yaml") + "/", names=["out.yaml/"])


@case("output", "build-output-trailing-slash")
def _(d):
    return cli("build", carmen_log(d), str(Path(d) / "out.npy") + "/", names=["out.npy/"])


@case("potentials", "infer-float32-hidden-1e39")
def _(d):
    return cli("infer", good_npy(d), Path(d) / "out.npy", "--float32", "--hidden", "1e39,1,1,10",
               "--schedule", "flooding", names=["--hidden"])


# --- signals: a run as long as the user asked (tol 0, a huge max_iter) stops cleanly on Ctrl-C ----------------
def _long_lbp(d):
    from crfmap.grid import OccupancyGrid
    from crfmap.io.grid_files import save_grid

    rng = np.random.default_rng(0)
    save_grid(OccupancyGrid(np.clip(rng.random((256, 256)), 0.01, 0.99), 0.05), Path(d) / "in.npy")
    return cli("infer", Path(d) / "in.npy", Path(d) / "out.npy", "--preset", "thesis", "--tol", "0",
               "--max-iter", "1000000000", names=["interrupted"])


for _sig_name, _sig_number in (("SIGINT", 2), ("SIGTERM", 15)):
    CASES.append(Case("signals", f"infer-tol-0-max-iter-1e9-{_sig_name}", _long_lbp, subprocess=True,
                      signal=_sig_number, expect_rc=128 + _sig_number, extra={"signal_after": 10.0}))
