"""crfmap.environment: each variable crfmap reads is checked where it is read, errors name the variable.

(tests/test_environment.py is about environment.yml.) The command-line refusals are in the hostile
catalogue (tests/hostile/cases_batch.py, class "environment").
"""
import os
import subprocess
import sys

import pytest

from crfmap import checks, environment
from crfstudy import paths
from crfmap.errors import InputError


@pytest.mark.parametrize("text, expected", [("4e8", 400_000_000), ("12", 12), (" 7 ", 7), ("1" * 30, int("1" * 30)),
                                            ("2.0", 2)])
def test_whole_numbers(text, expected):
    assert environment.whole_number("X", text, "cells") == expected


@pytest.mark.parametrize("text, problem", [("1e400", "infinity"), ("inf", "infinity"), ("nan", "not-a-number"),
                                           ("0", "at least 1"), ("1.5", "whole number"), ("abc", "whole number"),
                                           ("-3", "at least 1")])
def test_bad_numbers_name_the_variable_and_value(text, problem):
    with pytest.raises(InputError, match=f"X={text}: .*{problem}"):
        environment.whole_number("X", text, "cells")


def test_max_cells_reads_the_variable_at_each_call(monkeypatch):
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "4e8")
    assert checks.max_cells() == 400_000_000
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "")
    assert checks.max_cells() == checks.MAX_CELLS_DEFAULT  # empty: unset
    monkeypatch.setenv("CRFMAP_MAX_CELLS", "1e400")
    with pytest.raises(InputError, match="CRFMAP_MAX_CELLS=1e400"):
        checks.max_cells()


def test_output_paths_follow_the_variable_and_refuse_an_empty_one(monkeypatch, tmp_path):
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path))
    assert paths.GENERATED == tmp_path / "paper" / "generated" and paths.OUT == tmp_path / "out"
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", "")
    with pytest.raises(InputError, match="CRFMAP_OUTPUT_ROOT: is set but empty"):
        getattr(paths, "FIGURES")
    (tmp_path / "file").write_text("x")
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path / "file"))
    with pytest.raises(InputError, match="CRFMAP_OUTPUT_ROOT=.*file: is not a folder"):
        paths.output_root()
    monkeypatch.delenv("CRFMAP_OUTPUT_ROOT")
    assert paths.OUTPUT_ROOT == paths.PROJECT_ROOT


def test_writable_folder_probe_leaves_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(tmp_path / "a"))
    assert environment.writable_folder(tmp_path / "a" / "b", "CRFMAP_OUTPUT_ROOT") == tmp_path / "a" / "b"
    assert list(tmp_path.iterdir()) == []
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", "/proc/x")  # nobody, root included, can make a folder there
    with pytest.raises(InputError, match=r"CRFMAP_OUTPUT_ROOT=/proc/x: cannot write /proc/x/out \(in /proc\)"):
        environment.writable_folder("/proc/x/out", "CRFMAP_OUTPUT_ROOT")


@pytest.mark.parametrize("text", ["abc", "0", "-1", "1.5"])
def test_numba_threads_refused_in_one_line_before_numba_is_imported(text):
    """Numba itself ignores 'abc' (a warning) and fails on '0' with a traceback at its import."""
    done = subprocess.run([sys.executable, "-m", "crfmap", "infer", "in.npy", "out.npy"], capture_output=True,
                          text=True, env={**os.environ, "NUMBA_NUM_THREADS": text}, timeout=300)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        f"crfmap: error: NUMBA_NUM_THREADS={text}: " + ("must be at least 1 (numba refuses 0)" if text == "0" else
                                                        "expected a whole number of threads >= 1")]


def test_numba_threads_unset_or_empty_means_numbas_default(monkeypatch):
    monkeypatch.setenv("NUMBA_NUM_THREADS", "")
    assert environment.numba_threads() is None
    monkeypatch.setenv("NUMBA_NUM_THREADS", "2")
    assert environment.numba_threads() == 2
