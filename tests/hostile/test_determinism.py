"""Kept as it was: the same command twice, and with 1 or 2 threads, writes byte-identical files."""
import hashlib
from pathlib import Path

import numba
import pytest

from crfmap.cli import main
from fixtures import carmen_log, good_npy


def _digest(path):
    path = Path(path)
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    return [(p.name, hashlib.sha256(p.read_bytes()).hexdigest()) for p in files]


def _twice(tmp_path, argv_of, outputs_of, threads=(None, None)):
    digests = []
    for k, t in enumerate(threads):
        before = numba.get_num_threads()
        if t is not None:
            numba.set_num_threads(min(t, numba.config.NUMBA_NUM_THREADS))
        try:
            assert main(argv_of(tmp_path / f"run{k}")) == 0
        finally:
            numba.set_num_threads(before)
        digests.append([_digest(p) for p in outputs_of(tmp_path / f"run{k}")])
    return digests


def test_build_infer_and_convert_twice_are_byte_identical(tmp_path, capsys):
    log = carmen_log(tmp_path, n_scans=20, n=90)
    src = good_npy(tmp_path)
    for argv, outs in [
        (lambda d: ["build", str(log), str(d / "m.npy")], lambda d: [d / "m.npy", d / "m.npy.yaml"]),
        (lambda d: ["build", str(log), str(d / "m.yaml")], lambda d: [d / "m.yaml", d / "m.pgm"]),
        (lambda d: ["infer", str(src), str(d / "o.yaml"), "--mode", "trinary"], lambda d: [d / "o.yaml", d / "o.pgm"]),
        (lambda d: ["convert", str(log), str(d / "b.bag")], lambda d: [d / "b.bag"]),
        (lambda d: ["convert", str(log), str(d / "b2")], lambda d: [d / "b2"]),
    ]:
        first, second = _twice(tmp_path, argv, outs)
        assert first == second


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs 2 threads")
def test_infer_with_one_or_two_threads_is_byte_identical(tmp_path, capsys):
    src = good_npy(tmp_path)
    first, second = _twice(tmp_path, lambda d: ["infer", str(src), str(d / "o.npy"), "--tol", "0"],
                           lambda d: [d / "o.npy"], threads=(1, 2))
    assert first == second


def test_simulate_twice_is_byte_identical(tmp_path, capsys):
    first, second = _twice(tmp_path, lambda d: ["simulate", "x", str(d / "s.bag"), "--format", "ros1", "--quiet",
                                                "--seed", "3", "--range-noise", "0.05", "--beams", "90"],
                           lambda d: [d / "s.bag"])
    assert first == second
