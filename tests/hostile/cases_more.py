"""The catalogue, continued: options, output paths, signals, faults and library calls."""
from __future__ import annotations

import signal
from pathlib import Path

import numpy as np

from cases import CASES, Case, case, cli
from fixtures import carmen_log, good_bag, good_grid, good_map, good_npy


# --- options that are absurd or do not apply -----------------------------------------------------
def _opt(cls, name, make):
    CASES.append(Case(cls, name, make))


def _simulate(*opts, names):
    def make(d):
        return cli("simulate", "x", Path(d) / "sim", "--quiet", *opts, names=names)
    return make


for _n, _o in [("beams-negative", ("--beams", "-5")), ("beams-zero", ("--beams", "0")),
               ("beams-1e9", ("--beams", "1000000000")), ("fov-negative", ("--fov", "-10")),
               ("range-negative", ("--range", "-1")), ("range-min-above-max", ("--range-min", "9")),
               ("stride-zero", ("--stride", "0")), ("resolution-1e-9", ("--resolution", "1e-9")),
               ("seed-negative", ("--seed", "-1")), ("range-noise-negative", ("--range-noise", "-1")),
               ("odom-noise-nan", ("--odom-noise", "nan")), ("range-sigma-inf", ("--range-sigma", "inf"))]:
    _opt("options", "simulate-" + _n, _simulate(*_o, names=[_o[0]]))


def _infer_opt(name, *opts, names, yaml_in=False, out="out.npy"):
    def make(d):
        src = good_map(d) if yaml_in else good_npy(d)
        return cli("infer", src, Path(d) / out, *opts, names=names)
    _opt("options", "infer-" + name, make)


_infer_opt("tol-nan", "--tol", "nan", names=["--tol"])
_infer_opt("tol-negative", "--tol", "-1", names=["--tol"])
_infer_opt("damping-one", "--damping", "1", names=["--damping"])
_infer_opt("max-iter-negative", "--max-iter", "-1", names=["--max-iter"])
_infer_opt("margin-negative", "--margin", "-1", names=["--margin"])
_infer_opt("free-thresh-2", "--free-thresh", "2", names=["--free-thresh", "thresh"], yaml_in=True)
_infer_opt("free-thresh-with-npy-input", "--free-thresh", "0.2", names=["--free-thresh"])
_infer_opt("mode-with-npy-output", "--mode", "trinary", names=["--mode"])


def _build_opt(name, *opts, names):
    def make(d):
        log = carmen_log(d)
        return cli("build", log, Path(d) / "out.npy", *opts, names=names)
    _opt("options", "build-" + name, make)


_build_opt("resolution-zero", "--resolution", "0", names=["resolution"])
_build_opt("resolution-nan", "--resolution", "nan", names=["resolution"])
_build_opt("resolution-1e-9", "--resolution", "1e-9", names=["resolution"])
_build_opt("extent-inverted", "--extent", "1", "1", "0", "0", names=["extent"])
_build_opt("extent-huge", "--extent", "-1e7", "-1e7", "1e7", "1e7", names=["extent", "resolution"])
_build_opt("free-on-no-return-negative", "--free-on-no-return", "-1", names=["--free-on-no-return", "free_on_no_return"])
_build_opt("scan-topic-with-carmen", "--scan-topic", "/scan", names=["--scan-topic"])
_build_opt("pose-source-tf-with-carmen", "--pose-source", "tf", names=["--pose-source"])


@case("options", "build-max-range-with-bag")
def _(d):
    return cli("build", good_bag(d), Path(d) / "out.npy", "--max-range", "5", names=["--max-range"])


@case("options", "metrics-truth-not-binary")
def _(d):
    from crfmap.io.grid_files import save_grid

    good_npy(d, "p.npy")
    save_grid(good_grid(), Path(d) / "t.npy")  # probabilities 0.1 / 0.9: not a 0/1 truth
    return cli("metrics", Path(d) / "p.npy", Path(d) / "t.npy", names=["t.npy"])


@case("options", "bench-sizes-tiny")
def _(d):
    return cli("bench", "--sizes", "4", "--quick", names=["--sizes"])


@case("options", "bench-repeats-zero")
def _(d):
    return cli("bench", "--repeats", "0", "--quick", names=["--repeats"])


# --- output paths --------------------------------------------------------------------------------
@case("output", "convert-into-nonempty-folder")
def _(d):
    log = carmen_log(d)
    (Path(d) / "mine").mkdir()
    (Path(d) / "mine" / "thesis.tex").write_text("my thesis")
    return cli("convert", log, Path(d) / "mine", names=["mine"])


@case("output", "convert-into-dot")
def _(d):
    log = carmen_log(d)
    return cli("convert", log, ".", names=["."])


@case("output", "infer-output-is-input-yaml")
def _(d):
    p = good_map(d)
    return cli("infer", p, p, names=["map.yaml"])


@case("output", "infer-output-is-input-npy")
def _(d):
    p = good_npy(d)
    return cli("infer", p, p, names=["in.npy"])


@case("output", "build-output-is-input")
def _(d):
    log = carmen_log(d, name="log.npy.log")
    return cli("build", log, log, names=["log.npy.log"])


@case("output", "infer-output-dot")
def _(d):
    return cli("infer", good_npy(d), ".", names=["."])


@case("output", "infer-output-name-too-long")
def _(d):
    return cli("infer", good_npy(d), Path(d) / ("x" * 300 + ".npy"), names=["x" * 40])


@case("output", "infer-output-parent-is-file")
def _(d):
    (Path(d) / "afile").write_text("x")
    return cli("infer", good_npy(d), Path(d) / "afile" / "out.npy", names=["afile"])


@case("output", "infer-sidecar-is-folder")
def _(d):
    src = good_npy(d)
    np.save(Path(d) / "out.npy", np.full((2, 2), 0.25))
    (Path(d) / "out.npy.yaml").mkdir()
    return cli("infer", src, Path(d) / "out.npy", names=["out.npy"])


@case("output", "infer-map-image-is-folder")
def _(d):
    src = good_npy(d)
    (Path(d) / "out.png").mkdir()
    return cli("infer", src, Path(d) / "out.yaml", names=["out.png", "out.yaml"])


@case("output", "infer-map-yaml-is-folder-beside-an-image")
def _(d):
    src = good_npy(d)
    (Path(d) / "out.png").write_bytes(b"the user's old image")
    (Path(d) / "out.yaml").mkdir()
    return cli("infer", src, Path(d) / "out.yaml", names=["out.yaml"])


@case("output", "infer-output-to-proc")
def _(d):
    return cli("infer", good_npy(d), "/proc/self/out.npy", names=["/proc/self"])


@case("output", "simulate-out-exists")
def _(d):
    (Path(d) / "sim").mkdir()
    (Path(d) / "sim" / "keep.txt").write_text("x")
    return cli("simulate", "x", Path(d) / "sim", "--quiet", names=["sim"])


@case("output", "simulate-overwrite-nonbag-folder")
def _(d):
    (Path(d) / "sim").mkdir()
    (Path(d) / "sim" / "keep.txt").write_text("x")
    return cli("simulate", "x", Path(d) / "sim", "--quiet", "--overwrite", "--beams", "8", names=["sim"])


# --- faults: the file system refuses the write -------------------------------------------------
for _fault in ("enospc", "eacces", "erofs"):
    def _npy_fault(d):
        return cli("infer", good_npy(d), Path(d) / "out.npy", names=["out.npy"])

    def _map_fault(d):
        return cli("infer", good_npy(d), Path(d) / "out.yaml", names=["out."])

    def _bag_fault(d):
        return cli("convert", carmen_log(d), Path(d) / "out.bag", names=["out.bag"])

    CASES.append(Case("faults", f"{_fault}-npy", _npy_fault, fault=_fault))
    CASES.append(Case("faults", f"{_fault}-map", _map_fault, fault=_fault))
    CASES.append(Case("faults", f"{_fault}-ros1-bag", _bag_fault, fault=_fault))


@case("faults", "efbig-npy", fault="fsize", subprocess=True)
def _(d):
    np.save(Path(d) / "big.npy", np.full((1100, 1100), 0.5))  # 9.7 MB out
    return cli("infer", Path(d) / "big.npy", Path(d) / "out.npy", "--max-iter", "1", names=["out.npy"])


@case("faults", "efbig-ros2-bag", fault="fsize", subprocess=True)
def _(d):
    return cli("convert", carmen_log(d, n_scans=6000, n=180), Path(d) / "out", names=["out"])


@case("faults", "efbig-simulate", fault="fsize", subprocess=True)
def _(d):
    return cli("simulate", "x", Path(d) / "sim", "--quiet", names=["sim"])


# --- signals: interrupted while writing -----------------------------------------------------------
for _sig in (signal.SIGTERM, signal.SIGHUP, signal.SIGINT):
    def _sim(d):
        return cli("simulate", "office", Path(d) / "sim", "--quiet", "--beams", "720", names=["sim", "interrupted"])

    def _conv(d):
        return cli("convert", carmen_log(d, n_scans=3000, n=180), Path(d) / "out.bag", names=["out.bag", "interrupted"])

    CASES.append(Case("signals", f"simulate-{_sig.name}", _sim, subprocess=True, signal=int(_sig),
                      expect_rc=128 + int(_sig)))
    CASES.append(Case("signals", f"convert-{_sig.name}", _conv, subprocess=True, signal=int(_sig),
                      expect_rc=128 + int(_sig)))


# --- library calls with wrong types ---------------------------------------------------------------
def _lib(name, call, names, prep=None):
    """A library call; ``prep(d)`` writes its input files first (before the folder's snapshot)."""
    def setup(d):
        made = prep(d) if prep else None
        return dict(call=lambda: call(d) if prep is None else call(d, made), names=names)
    CASES.append(Case("library", name, setup))


def _imp(module, attr):
    import importlib

    return getattr(importlib.import_module(module), attr)


_lib("load_grid-None", lambda d: _imp("crfmap.io.grid_files", "load_grid")(None), ["None"])
_lib("load_grid-int", lambda d: _imp("crfmap.io.grid_files", "load_grid")(123), ["123"])
_lib("save_grid-array", lambda d: _imp("crfmap.io.grid_files", "save_grid")(np.zeros((2, 2)), Path(d) / "o.npy"),
     ["o.npy"])
_lib("save_grid-map-array", lambda d: _imp("crfmap.io.grid_files", "save_grid")(np.zeros((2, 2)), Path(d) / "o.yaml"),
     ["o.yaml"])
_lib("read_carmen-None", lambda d: _imp("crfmap.io.carmen", "read_carmen")(None), ["None"])
_lib("read_carmen-no_return-list", lambda d, log: _imp("crfmap.io.carmen", "read_carmen")(log, no_return=[1]),
     ["no_return", "max_range"], prep=carmen_log)
_lib("read_bag-int", lambda d: _imp("crfmap.io.bag_reader", "read_bag")(42), ["42"])
_lib("read_bag-laser_mount-text", lambda d, bag: _imp("crfmap.io.bag_reader", "read_bag")(bag, laser_mount="abc"),
     ["laser_mount"], prep=good_bag)
_lib("write_bag-not-a-recording", lambda d: _imp("crfmap.io.bag_writer", "write_bag")("rec", Path(d) / "b"), ["b"])
_lib("load_npy-list", lambda d: _imp("crfmap.io.npy_grid", "load_npy")([1, 2]), ["[1, 2]"])
_lib("read_map_yaml-None", lambda d: _imp("crfmap.io.map_server", "read_map_yaml")(None), ["None"])
