"""The hostile-input catalogue: every case is input a careful user or an attacker could give crfmap.

Each case's ``setup(d)`` writes its files into the folder ``d`` and returns ``argv`` (a
``crfmap`` command line) or ``call`` (a library call), plus ``names``: strings of which the
one error line must contain at least one (the input it is about), and optionally ``env``:
environment variables set for the run (a value of None removes one), ``stdout``: ``"full"`` (standard
output on a full disk), ``written``: outputs completed before the failure, which the line must name
(``whole(d)``: what is wrong with them, or None). Every case must end in a
refusal: exit status 2 (library: an InputError), exactly one stderr line naming the input,
no traceback, the folder unchanged (no output, previous output intact, no temporary file),
in bounded time and memory. ``fault`` makes writes fail (see faults.py); ``subprocess``
cases need a real process (signals, resource limits).
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fixtures import (GOOD_YAML, alias_bomb, carmen_log, carmen_text, deep_yaml, fifo, good_bag, good_npy, gzip_bomb, map_yaml, npy_with_header, png_header_only, tf_bag)


@dataclass
class Case:
    cls: str
    name: str
    setup: object  # d -> dict(argv=[...] | call=callable, names=[...])
    fault: str | None = None  # 'enospc' | 'eacces' | 'erofs' (in-process) | 'fsize' (subprocess)
    subprocess: bool = False
    signal: int | None = None  # send this signal once a temporary file appears
    expect_rc: int = 2
    extra: dict = field(default_factory=dict)
    entry: str = "crfmap"  # the command line: a key of harness.ENTRIES (crfmap, reproduce, run, warmup)


CASES: list[Case] = []


def case(cls, name, **kw):
    def register(setup):
        CASES.append(Case(cls, name, setup, **kw))
        return setup
    return register


def cli(*argv, names):
    return dict(argv=[str(a) for a in argv], names=[str(n) for n in names])


def infer_on(d, path):
    return cli("infer", path, Path(d) / "out.npy", names=[Path(path).name])


# --- maps: map_server YAML + image ----------------------------------------------------------
def _yaml_case(name, text, image=True):
    @case("yaml" if name.startswith("yaml-") else "maps", name)
    def setup(d):
        p = map_yaml(d, text, image=image)
        return infer_on(d, p)


_yaml_case("missing-resolution", GOOD_YAML.replace("resolution: 0.05\n", ""))
_yaml_case("resolution-1e308", GOOD_YAML.replace("0.05", "1e308"))
_yaml_case("resolution-zero", GOOD_YAML.replace("0.05", "0"))
_yaml_case("resolution-inf", GOOD_YAML.replace("0.05", ".inf"))
_yaml_case("origin-two-values", GOOD_YAML.replace("[0, 0, 0]", "[0, 0]"))
_yaml_case("origin-huge", GOOD_YAML.replace("[0, 0, 0]", "[1e308, 0, 0]"))
_yaml_case("negate-2", GOOD_YAML.replace("negate: 0", "negate: 2"))
_yaml_case("thresholds-swapped", GOOD_YAML.replace("0.65", "0.1"))
_yaml_case("mode-unknown", GOOD_YAML + "mode: fancy\n")
_yaml_case("image-missing", GOOD_YAML.replace("img.pgm", "nothere.pgm"))
_yaml_case("image-empty-name", GOOD_YAML.replace("img.pgm", "''"))


@case("maps", "image-is-folder")
def _(d):
    os.mkdir(Path(d) / "dir.pgm")
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "dir.pgm"), image=False))


@case("maps", "image-garbage")
def _(d):
    (Path(d) / "g.pgm").write_bytes(os.urandom(300))
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "g.pgm"), image=False))


@case("maps", "pgm-truncated")
def _(d):
    (Path(d) / "t.pgm").write_bytes(b"P5\n100 100\n255\n" + b"\xfe" * 50)
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "t.pgm"), image=False))


@case("maps", "pgm-header-20000x20000")
def _(d):
    (Path(d) / "h.pgm").write_bytes(b"P5\n20000 20000\n255\n" + b"\xfe" * 1000)
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "h.pgm"), image=False))


@case("maps", "png-header-20000x20000")
def _(d):
    png_header_only(Path(d) / "h.png", 20000, 20000)
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "h.png"), image=False))


@case("maps", "png-header-12000x12000")
def _(d):
    png_header_only(Path(d) / "h.png", 12000, 12000)  # under Pillow's bomb limit, over crfmap's cell limit
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "h.png"), image=False))


@case("maps", "tiff-float-nan")
def _(d):
    from PIL import Image

    a = np.full((6, 8), 0.5, np.float32)
    a[2, 3] = np.nan
    Image.fromarray(a, mode="F").save(Path(d) / "f.tif")
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "f.tif"), image=False))


@case("maps", "image-fifo")
def _(d):
    fifo(Path(d) / "p.pgm")
    return infer_on(d, map_yaml(d, GOOD_YAML.replace("img.pgm", "p.pgm"), image=False))


# --- YAML itself -------------------------------------------------------------------------------
_yaml_case("yaml-syntax", "image: x.pgm\nresolution: [\n", image=False)
_yaml_case("yaml-list", "- 1\n- 2\n", image=False)
_yaml_case("yaml-deep-nesting", deep_yaml(), image=False)
_yaml_case("yaml-alias-bomb", alias_bomb(), image=False)
_yaml_case("yaml-alias-in-origin", GOOD_YAML.replace("origin: [0, 0, 0]", "o: &o [0, 0, 0]\norigin: *o"))


@case("yaml", "yaml-not-utf8")
def _(d):
    (Path(d) / "bin.yaml").write_bytes(b"image: \xff\xfe\n")
    return infer_on(d, Path(d) / "bin.yaml")


@case("yaml", "yaml-fifo")
def _(d):
    return infer_on(d, fifo(Path(d) / "p.yaml"))


@case("yaml", "yaml-huge-file")
def _(d):
    (Path(d) / "big.yaml").write_text("# " + "x" * (3 << 20) + "\n" + GOOD_YAML)
    return infer_on(d, Path(d) / "big.yaml")


@case("yaml", "etc-passwd-as-yaml")
def _(d):
    return cli("infer", "/etc/passwd", Path(d) / "out.npy", names=["/etc/passwd"])


@case("yaml", "sidecar-alias-bomb")
def _(d):
    good_npy(d)
    (Path(d) / "in.npy.yaml").write_text(alias_bomb())
    return infer_on(d, Path(d) / "in.npy")


@case("yaml", "sidecar-resolution-1e308")
def _(d):
    good_npy(d)
    (Path(d) / "in.npy.yaml").write_text("resolution: 1e308\norigin: [0, 0, 0]\nframe_id: map\n")
    return infer_on(d, Path(d) / "in.npy")


@case("yaml", "sidecar-is-folder")
def _(d):
    np.save(Path(d) / "in.npy", np.full((3, 3), 0.5))
    os.mkdir(Path(d) / "in.npy.yaml")
    return infer_on(d, Path(d) / "in.npy")


# --- .npy grids --------------------------------------------------------------------------------
def _npy_case(name, make):
    @case("npy", name)
    def setup(d):
        p = Path(d) / f"{name}.npy"
        make(p)
        return infer_on(d, p)


_npy_case("nan", lambda p: np.save(p, np.array([[0.5, np.nan]])))
_npy_case("above-one", lambda p: np.save(p, np.array([[0.5, 2.0]])))
_npy_case("three-d", lambda p: np.save(p, np.zeros((2, 2, 2))))
_npy_case("ints", lambda p: np.save(p, np.zeros((2, 2), np.int64)))
_npy_case("empty-0x5", lambda p: np.save(p, np.zeros((0, 5))))
_npy_case("complex", lambda p: np.save(p, np.zeros((2, 2), complex)))
_npy_case("pickled-object", lambda p: np.save(p, np.array([[{"a": 1}]], dtype=object), allow_pickle=True))
_npy_case("npz-renamed", lambda p: np.savez(open(p, "wb"), a=np.zeros((2, 2))))
_npy_case("zero-bytes", lambda p: p.write_bytes(b""))
_npy_case("truncated", lambda p: p.write_bytes(np.lib.format.magic(1, 0) + b"\x76\x00{'descr': '<f8'"))
_npy_case("header-huge", lambda p: npy_with_header(p, b"{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), "
                                                     b"'x': '" + b"A" * 70000 + b"'}", b"\0" * 32))
_npy_case("header-shape-1e5x1e5", lambda p: npy_with_header(
    p, b"{'descr': '<f8', 'fortran_order': False, 'shape': (100000, 100000), }", b"\0" * 64))
_npy_case("header-newlines", lambda p: npy_with_header(p, b"{'descr': '<f8',\n\n 'shape': (2,)}", b""))
_npy_case("float16-inf", lambda p: np.save(p, np.array([[0.5, np.inf]], np.float16)))


@case("npy", "npy-fifo")
def _(d):
    return infer_on(d, fifo(Path(d) / "p.npy"))


@case("npy", "npy-folder")
def _(d):
    os.mkdir(Path(d) / "dir.npy")
    return infer_on(d, Path(d) / "dir.npy")


@case("npy", "dev-zero-symlink")
def _(d):
    os.symlink("/dev/zero", Path(d) / "z.npy")
    return infer_on(d, Path(d) / "z.npy")


@case("npy", "proc-path")
def _(d):
    return cli("infer", "/proc/self/status", Path(d) / "out.npy", names=["/proc/self/status"])


# --- CARMEN logs (crfmap build) ----------------------------------------------------------------
def _carmen_case(name, text=None, log_name="log.log", out="out.npy", words=None, **kw):
    @case("carmen", name)
    def setup(d):
        p = carmen_log(d, text=text, name=log_name, **kw)
        return cli("build", p, Path(d) / out, names=[p.name])


_carmen_case("no-flaser", text="PARAM a 1 nohost 0\nODOM 0 0 0 0 0 0 1 nohost 1\n")
_carmen_case("empty-file", text="")
_carmen_case("flaser-count-missing", text="FLASER x 1 2\n")
_carmen_case("flaser-one-reading", text="FLASER 1 2.0 0 0 0 0 0 0 1 nohost 1\n")
_carmen_case("flaser-short-line", text=carmen_text().replace(" nohost 1.0\n", "\n", 1) + "FLASER 9 1 2\n")
_carmen_case("flaser-text-range", text=carmen_text().replace("2.00", "abc", 1))
_carmen_case("flaser-negative-range", text=carmen_text().replace("2.00", "-3.00", 1))
_carmen_case("flaser-inf-pose", text=carmen_text(pose=(float("inf"), 0.0, 0.0)))
_carmen_case("flaser-pose-1e9", pose=(1e9, 0.0, 0.0), text=None)
_carmen_case("flaser-pose-1e300", pose=(1e300, 0.0, 0.0), text=None)
_carmen_case("flaser-stamp-inf", stamp=float("inf"), text=None)
_carmen_case("flaser-beam-count-varies", text=carmen_text(n=9) + carmen_text(n=7).split("\n", 2)[2])
_carmen_case("flaser-count-huge", text="FLASER 99999999999999999999 1 2 3\n")
_carmen_case("flaser-one-pose-at-1e9", text=carmen_text() + carmen_text(pose=(1e9, 0.0, 0.0)).split("\n", 2)[2])
_carmen_case("odom-inf", text=carmen_text().replace("ODOM 0.0", "ODOM inf", 1))


@case("carmen", "binary-garbage")
def _(d):
    (Path(d) / "g.log").write_bytes(bytes(range(256)) * 4)
    return cli("build", Path(d) / "g.log", Path(d) / "out.npy", names=["g.log"])


@case("carmen", "gzip-corrupt")
def _(d):
    (Path(d) / "c.log.gz").write_bytes(b"\x1f\x8b\x08\x00" + os.urandom(200))
    return cli("build", Path(d) / "c.log.gz", Path(d) / "out.npy", names=["c.log.gz"])


@case("carmen", "gzip-bomb-700MB")
def _(d):
    gzip_bomb(Path(d) / "bomb.log.gz")
    return cli("build", Path(d) / "bomb.log.gz", Path(d) / "out.npy", names=["bomb.log.gz"])


@case("carmen", "gzip-bomb-of-text-300MB")
def _(d):
    gzip_bomb(Path(d) / "tbomb.log.gz", expanded_mb=300, text=True)
    return cli("build", Path(d) / "tbomb.log.gz", Path(d) / "out.npy", names=["tbomb.log.gz"])


@case("carmen", "log-fifo")
def _(d):
    return cli("build", fifo(Path(d) / "p.log"), Path(d) / "out.npy", names=["p.log"])


@case("carmen", "log-folder")
def _(d):
    os.mkdir(Path(d) / "dir.log")
    return cli("build", Path(d) / "dir.log", Path(d) / "out.npy", names=["dir.log"])


@case("carmen", "convert-stamp-overflow")
def _(d):
    p = carmen_log(d, text=carmen_text().replace(" 1.0 nohost 1.0", " 1e300 nohost 1e300"))
    return cli("convert", p, Path(d) / "out", names=[p.name])


# --- ROS 1 and ROS 2 bags ----------------------------------------------------------------------
@case("ros1", "truncated")
def _(d):
    p = good_bag(d, "b.bag", fmt="ros1")
    p.write_bytes(p.read_bytes()[:300])
    return cli("build", p, Path(d) / "out.npy", names=["b.bag"])


@case("ros1", "garbage")
def _(d):
    (Path(d) / "g.bag").write_bytes(os.urandom(2000))
    return cli("build", Path(d) / "g.bag", Path(d) / "out.npy", names=["g.bag"])


@case("ros1", "empty")
def _(d):
    (Path(d) / "e.bag").write_bytes(b"")
    return cli("build", Path(d) / "e.bag", Path(d) / "out.npy", names=["e.bag"])


@case("ros1", "fifo")
def _(d):
    return cli("build", fifo(Path(d) / "p.bag"), Path(d) / "out.npy", names=["p.bag"])


@case("ros1", "zero-quaternion-tf")
def _(d):
    p = tf_bag(d, (0.0, 0.0, 0.0, 0.0), fmt="ros1")
    return cli("build", p, Path(d) / "out.npy", names=[p.name])


@case("ros1", "nan-quaternion-tf")
def _(d):
    p = tf_bag(d, (0.0, 0.0, float("nan"), 1.0), fmt="ros1")
    return cli("build", p, Path(d) / "out.npy", names=[p.name])


@case("ros2", "zero-quaternion-tf")
def _(d):
    p = tf_bag(d, (0.0, 0.0, 0.0, 0.0))
    return cli("build", p, Path(d) / "out.npy", names=[p.name])


@case("ros2", "metadata-garbage")
def _(d):
    p = good_bag(d)
    (p / "metadata.yaml").write_text("rosbag2_bagfile_information: [\n")
    return cli("build", p, Path(d) / "out.npy", names=["bag"])


@case("ros2", "metadata-alias-bomb")
def _(d):
    p = good_bag(d)
    (p / "metadata.yaml").write_text(alias_bomb().replace("image", "rosbag2_bagfile_information"))
    return cli("build", p, Path(d) / "out.npy", names=["bag"])


@case("ros2", "metadata-deep")
def _(d):
    p = good_bag(d)
    (p / "metadata.yaml").write_text(deep_yaml())
    return cli("build", p, Path(d) / "out.npy", names=["bag"])


@case("ros2", "db3-garbage")
def _(d):
    p = good_bag(d)
    for f in [*p.glob("*.db3"), *p.glob("*.mcap")]:
        f.write_bytes(os.urandom(4096))
    return cli("build", p, Path(d) / "out.npy", names=["bag"])


@case("ros2", "db3-missing")
def _(d):
    p = good_bag(d)
    for f in [*p.glob("*.db3"), *p.glob("*.mcap")]:
        f.unlink()
    return cli("build", p, Path(d) / "out.npy", names=["bag"])


@case("ros2", "folder-without-metadata")
def _(d):
    os.mkdir(Path(d) / "nobag")
    (Path(d) / "nobag" / "x.txt").write_text("x")
    return cli("build", Path(d) / "nobag", Path(d) / "out.npy", names=["nobag"])


# --- potentials (crfmap infer --hidden / --link) ------------------------------------------------
for _name, _flag, _value in [("negative", "--hidden", "1,-2,1,1"), ("all-zero", "--link", "0,0,0,0"),
                             ("nan", "--hidden", "nan,1,1,1"), ("inf", "--hidden", "inf,1,1,1"),
                             ("three-values", "--hidden", "1,2,3"), ("text", "--link", "a,b,c,d"),
                             ("overflow-float32", "--hidden", "1e39,1,1,1e39"),
                             ("tiny-float32", "--hidden", "1e-46,1,1,1e-46")]:
    def _make(d, flag=_flag, value=_value, name=_name):
        p = good_npy(d)
        extra = ["--float32"] if "float32" in name else []
        return cli("infer", p, Path(d) / "out.npy", f"{flag}={value}", *extra, names=[flag])
    CASES.append(Case("potentials", _name, _make))
