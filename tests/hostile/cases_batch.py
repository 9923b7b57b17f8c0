"""The catalogue, continued: the batch side -- sweep files (``make sweep``) and environment variables.

A sweep case runs ``python -m crfstudy.repro.reproduce --sweep FILE --dry-run`` (what ``make sweep``
runs; a dry run, so a sweep wrongly accepted does not start notebooks) with the outputs in the case's
folder. An environment case runs a command line with one variable set; numba reads
``NUMBA_NUM_THREADS`` only when it is imported, so those cases run in a child process.
"""
from __future__ import annotations

from pathlib import Path

from cases import CASES, Case
from fixtures import alias_bomb, fifo, good_npy

DENOISING = "notebook: 04_denoising\n"  # parameters: quick, seed, train_seed, noise (float), toolbox_seed
EXPLORER = "notebook: 08_explorer\n"  # parameters: scene (str), radius (None), iterations (None), ...


def _sweep_case(name, text=None, make=None, file="s.yaml", options=(), names=None):
    """A sweep file with ``text`` (or made by ``make(path)``), refused by ``reproduce --sweep``."""
    def setup(d):
        path = Path(d) / file
        if make is not None:
            make(path)
        else:
            path.write_bytes(text.encode() if isinstance(text, str) else text)
        spec = dict(argv=["--sweep", str(path), "--dry-run", *options], names=names or [file],
                    env={"CRFMAP_OUTPUT_ROOT": str(Path(d) / "out")})
        return spec
    CASES.append(Case("sweep", name, setup, entry="reproduce"))


def _grid(notebook, **grid):
    lines = [notebook, "parameters:"] + [f"  {k}: {v}" for k, v in grid.items()]
    return "\n".join(lines) + "\n"


# --- the YAML itself: as strict as a map YAML ------------------------------------------------------
_sweep_case("alias-bomb-in-fixed", DENOISING + "parameters:\n  noise: [0.3]\nfixed:\n  " +
            alias_bomb().replace("\n", "\n  ").replace("image:", "seed:").replace("resolution:", "train_seed:"))
_sweep_case("alias-product-9^8-values", DENOISING + "anchors:\n  " + "\n  ".join(alias_bomb(8).splitlines()[:8])
            + "\nparameters:\n  seed: *a7\n")
_sweep_case("alias-one-list-reused", DENOISING + "parameters:\n  seed: &s [0, 1, 2]\n  train_seed: *s\n")
_sweep_case("deep-nesting", DENOISING + "parameters:\n  noise: " + "[" * 20000 + "]" * 20000 + "\n")
_sweep_case("huge-file", DENOISING + "# " + "x" * (300 << 10) + "\nparameters:\n  noise: [0.3]\n")
_sweep_case("fifo-no-writer", make=fifo)
_sweep_case("folder", make=lambda p: p.mkdir())
_sweep_case("not-utf8", b"notebook: 04_denoising\nparameters:\n  noise: [0.3]\n# \xff\xfe\n")
_sweep_case("yaml-syntax", DENOISING + "parameters:\n  noise: [0.3\n")
_sweep_case("a-list", "- 1\n- 2\n")
_sweep_case("no-parameters", DENOISING)
_sweep_case("unknown-key", DENOISING + "parameter:\n  noise: [0.3]\nparameters:\n  noise: [0.3]\n")
_sweep_case("missing-file", make=lambda p: None)
_sweep_case("name-not-a-folder-name", _grid(DENOISING, noise="[0.3]"), file="-x y.yaml")

# --- what the file asks for --------------------------------------------------------------------
_sweep_case("notebook-matches-all", _grid("notebook: '0'\n", noise="[0.3]"))
_sweep_case("notebook-a-list", _grid("notebook: [04, 07]\n", noise="[0.3]"))
_sweep_case("unknown-parameter", _grid(DENOISING, nosie="[0.3]"))
_sweep_case("parameter-not-a-list", _grid(DENOISING, noise="0.3"))
_sweep_case("parameter-empty-list", _grid(DENOISING, noise="[]"))
_sweep_case("fixed-and-swept", _grid(DENOISING, noise="[0.3]") + "fixed: {noise: 0.5}\n")
_sweep_case("fixed-a-list", _grid(DENOISING, noise="[0.3]") + "fixed: [quick]\n")
_sweep_case("headline-a-number", _grid(DENOISING, noise="[0.3]") + "headline: 3\n")

# --- values: the notebook parameter's type, finite, printable, short --------------------------------
_sweep_case("float-vs-string-0.3", _grid(DENOISING, noise='[0.3, "0.3"]'))
_sweep_case("string-for-float", _grid(DENOISING, noise='["high"]'))
_sweep_case("bool-for-float", _grid(DENOISING, noise="[true]"))
_sweep_case("float-for-int-seed", _grid(DENOISING, seed="[1.5]"))
_sweep_case("string-for-bool-quick", _grid(DENOISING, quick='["yes"]'))
_sweep_case("int-for-bool-quick", _grid(DENOISING, quick="[1]"))
_sweep_case("number-for-string-scene", _grid(EXPLORER, scene="[3]"))
_sweep_case("mapping-value", _grid(DENOISING, noise="[{a: 1}]"))
_sweep_case("nested-list-value", _grid(EXPLORER, radius="[[[1]]]"))
_sweep_case("integer-too-large-for-a-float", _grid(DENOISING, noise=f"[1{'0' * 400}]"))
_sweep_case("date-value", _grid(DENOISING, noise="[2020-01-01]"))
_sweep_case("nan-value", _grid(DENOISING, noise="[.nan]"))
_sweep_case("inf-value", _grid(DENOISING, noise="[.inf, 0.3]"))
_sweep_case("nul-byte-value", _grid(EXPLORER, scene='["x\\0y"]'))
_sweep_case("newline-value", _grid(EXPLORER, scene='["x\\ny"]'))
_sweep_case("escape-character-value", _grid(EXPLORER, scene='["\\e[31mred"]'))
_sweep_case("value-300-characters", _grid(EXPLORER, scene=f'["{"y" * 300}"]'))
_sweep_case("values-together-over-255-bytes", _grid(EXPLORER, scene=f'["{"a" * 120}"]', schedule=f'["{"b" * 120}"]'))
_sweep_case("value-300-bytes-of-utf8", _grid(EXPLORER, scene=f'["{"é" * 50}"]'))  # 50 x %C3%A9

# --- two points, one folder: refused, naming both ----------------------------------------------------
_sweep_case("same-value-twice", _grid(DENOISING, noise="[0.3, 0.3]"))
_sweep_case("int-and-float-equal", _grid(DENOISING, noise="[1, 1.0]"))
_sweep_case("differ-only-in-case", _grid(EXPLORER, scene='["X", "x"]'))
_sweep_case("differ-only-in-case-escaped", _grid(EXPLORER, scene='["a/B", "a/b"]'))


def _previous_results(path):
    """A finished point of sweep s is in out/runs/s/ already; the refused sweep must leave it as it was."""
    done = path.parent / "out" / "runs" / "s" / "noise=0.3"
    done.mkdir(parents=True)
    (done / "04_denoising.ipynb").write_text("{}")
    path.write_text(_grid(DENOISING, noise="[0.3, 0.3]"))


_sweep_case("previous-results-kept", make=_previous_results)

# --- how many points -----------------------------------------------------------------------------
_sweep_case("grid-1000x1000", _grid(DENOISING, seed=list(range(1000)), train_seed=list(range(1000))))
_sweep_case("grid-201-points", _grid(DENOISING, seed=list(range(201))))
_sweep_case("max-points-zero", _grid(DENOISING, noise="[0.3]"), options=("--max-points", "0"), names=["--max-points"])
_sweep_case("max-points-inf", _grid(DENOISING, noise="[0.3]"), options=("--max-points", "inf"),
            names=["--max-points"])
_sweep_case("max-points-below-the-grid", _grid(DENOISING, seed="[0, 1, 2]"), options=("--max-points", "2"))


def _two_folders(d):
    for sub in ("a", "b"):
        (Path(d) / sub).mkdir()
        (Path(d) / sub / f"{sub}.yaml").write_text(_grid(DENOISING, noise="[0.3]"))
    return dict(argv=["--sweep", str(Path(d) / "a" / "a.yaml"), str(Path(d) / "b" / "b.yaml"), "--dry-run"],
                names=["--sweep"], env={"CRFMAP_OUTPUT_ROOT": str(Path(d) / "out")})


def _same_name_twice(d):
    for name in ("Noise", "noise"):
        (Path(d) / f"{name}.yaml").write_text(_grid(DENOISING, noise="[0.3]"))
    return dict(argv=["--sweep", str(Path(d) / "Noise.yaml"), str(Path(d) / "noise.yaml"), "--dry-run"],
                names=["--sweep"], env={"CRFMAP_OUTPUT_ROOT": str(Path(d) / "out")})


CASES.append(Case("sweep", "files-of-two-folders", _two_folders, entry="reproduce"))
CASES.append(Case("sweep", "names-differ-only-in-case", _same_name_twice, entry="reproduce"))
CASES.append(Case("sweep", "name-not-in-workflow-sweeps", lambda d: dict(
    argv=["--sweep", "no_such_sweep", "--dry-run"], names=["no_such_sweep"],
    env={"CRFMAP_OUTPUT_ROOT": str(Path(d) / "out")}), entry="reproduce"))


# --- environment variables: each checked where it is read, one line naming it ------------------------
def _env_case(name, env, names, entry="crfmap", argv=None, subprocess=False, fault=None):
    """``env`` ({variable: value}, a value may use {d}) set for a command line (default ``crfmap infer``).

    The folder holds ``in.npy`` (a good grid) and ``root`` (a plain file) before the run.
    """
    def setup(d):
        good_npy(d)
        (Path(d) / "root").write_text("a file, not a folder\n")
        values = {k: v.format(d=d) for k, v in env.items()}
        if entry == "crfmap":
            command = argv or ["infer", "{d}/in.npy", "{d}/out.npy"]
        elif entry == "library":  # import crfmap; infer(load_grid(...)) in a script of its own
            command = argv or ["{d}/in.npy"]
        else:  # reproduce: a dry run of one quick notebook (nothing would run for long if accepted)
            command = argv or ["--quick", "--only", "02", "--dry-run"]
            values.setdefault("CRFMAP_OUTPUT_ROOT", str(Path(d) / "out"))
        return dict(argv=[c.format(d=d) for c in command], names=names, env=values)
    CASES.append(Case("environment", name, setup, entry=entry, subprocess=subprocess, fault=fault))


for _value in ("1e400", "abc", "0", "-5", "nan", "inf", "1.5", "1e8 cells"):
    _env_case(f"CRFMAP_MAX_CELLS={_value}", {"CRFMAP_MAX_CELLS": _value}, ["CRFMAP_MAX_CELLS"])
for _value in ("inf", "nan", "1e400", "-inf", "0.5"):
    _env_case(f"--max-cells-{_value}", {}, ["--max-cells"],
              argv=["--max-cells", _value, "infer", "{d}/in.npy", "{d}/out.npy"])
for _value in ("abc", "0", "-1", "1.5", "2 threads"):
    _env_case(f"NUMBA_NUM_THREADS={_value}", {"NUMBA_NUM_THREADS": _value}, ["NUMBA_NUM_THREADS"], subprocess=True)
for _value in ("abc", "0"):  # numba's own import would fail (0) or ignore it (abc): crfmap checks it first
    _env_case(f"NUMBA_NUM_THREADS={_value}-library", {"NUMBA_NUM_THREADS": _value}, ["NUMBA_NUM_THREADS"],
              entry="library", subprocess=True)
_env_case("NUMBA_NUM_THREADS=0-reproduce", {"NUMBA_NUM_THREADS": "0"}, ["NUMBA_NUM_THREADS"], entry="reproduce",
          subprocess=True)
_env_case("NUMBA_NUM_THREADS=0-run", {"NUMBA_NUM_THREADS": "0"}, ["NUMBA_NUM_THREADS"], entry="run",
          argv=["nb.ipynb", "--output-root", "{d}/out"], subprocess=True)
_env_case("NUMBA_NUM_THREADS=0-warmup", {"NUMBA_NUM_THREADS": "0"}, ["NUMBA_NUM_THREADS"], entry="warmup",
          argv=["--jobs", "1"], subprocess=True)
_env_case("NUMBA_CACHE_DIR-unwritable", {"NUMBA_CACHE_DIR": "/proc/crfmap-numba"}, ["NUMBA_CACHE_DIR"])
_env_case("NUMBA_CACHE_DIR-a-file", {"NUMBA_CACHE_DIR": "{d}/in.npy"}, ["NUMBA_CACHE_DIR"])
# the study's variables (crfstudy.repro.variables), checked by each study entry point; the crfmap command ignores them
_env_case("CRFMAP_OUTPUT_ROOT-empty-reproduce", {"CRFMAP_OUTPUT_ROOT": ""}, ["CRFMAP_OUTPUT_ROOT"], entry="reproduce")
_env_case("CRFMAP_OUTPUT_ROOT-empty-run", {"CRFMAP_OUTPUT_ROOT": ""}, ["CRFMAP_OUTPUT_ROOT"], entry="run",
          argv=["nb.ipynb", "--output-root", "{d}/out"])
_env_case("CRFMAP_OUTPUT_ROOT-blank", {"CRFMAP_OUTPUT_ROOT": "  "}, ["CRFMAP_OUTPUT_ROOT"], entry="reproduce")
_env_case("CRFMAP_OUTPUT_ROOT-a-file", {"CRFMAP_OUTPUT_ROOT": "{d}/root"}, ["CRFMAP_OUTPUT_ROOT"], entry="reproduce",
          argv=["--quick", "--only", "02", "--dry-run"])
_env_case("CRFMAP_OUTPUT_ROOT-unwritable", {"CRFMAP_OUTPUT_ROOT": "/proc/crfmap-out"}, ["CRFMAP_OUTPUT_ROOT"],
          entry="reproduce")
_env_case("CRFMAP_OUTPUT_ROOT-permission-denied", {"CRFMAP_OUTPUT_ROOT": "{d}/out"}, ["CRFMAP_OUTPUT_ROOT"],
          entry="reproduce", fault="eacces")
_env_case("CRFMAP_OUTPUT_ROOT-read-only", {"CRFMAP_OUTPUT_ROOT": "{d}/out"}, ["CRFMAP_OUTPUT_ROOT"],
          entry="reproduce", fault="erofs")
_env_case("CRFMAP_DATA-empty", {"CRFMAP_DATA": ""}, ["CRFMAP_DATA"], entry="reproduce")
_env_case("CRFMAP_DATA-a-file", {"CRFMAP_DATA": "{d}/in.npy"}, ["CRFMAP_DATA"], entry="crfmap")
_env_case("CRFMAP_ROOT-empty", {"CRFMAP_ROOT": ""}, ["CRFMAP_ROOT"], entry="reproduce", subprocess=True)
_env_case("CRFMAP_ROOT-missing", {"CRFMAP_ROOT": "{d}/no-checkout"}, ["CRFMAP_ROOT"], entry="reproduce",
          subprocess=True)
_env_case("CRFMAP_RUN-not-json", {"CRFMAP_RUN": "{{notebook"}, ["CRFMAP_RUN"], entry="run",
          argv=["nb.ipynb", "--output-root", "{d}/out"])
_env_case("CRFMAP_REPRODUCE_STARTED-not-a-time", {"CRFMAP_REPRODUCE_STARTED": "yesterday"},
          ["CRFMAP_REPRODUCE_STARTED"], entry="reproduce")
_env_case("CRFMAP_RUN-path-escape", {"CRFMAP_RUN": '{{"notebook": "../../etc/passwd", "parameters": {{}}}}'},
          ["CRFMAP_RUN"], entry="reproduce")


def _save_numbers(name, numbers):
    from crfstudy.repro.report import save_numbers

    return save_numbers(name, numbers)


def _save_numbers_with_bad_run(d):
    return dict(call=lambda: _save_numbers("x", {"a": 1}), names=["CRFMAP_RUN"], env={"CRFMAP_RUN": "[1, 2]", "CRFMAP_OUTPUT_ROOT": str(d)})


CASES.append(Case("environment", "CRFMAP_RUN-a-list-save_numbers", _save_numbers_with_bad_run))
CASES.append(Case("environment", "CRFMAP_OUTPUT_ROOT-empty-save_numbers", lambda d: dict(
    call=lambda: _save_numbers("x", {"a": 1}),
    names=["CRFMAP_OUTPUT_ROOT"], env={"CRFMAP_OUTPUT_ROOT": ""})))
def _load_grid_with_bad_limit(d):
    source = good_npy(d)

    def call():
        from crfmap.io.grid_files import load_grid

        load_grid(source)
    return dict(call=call, names=["CRFMAP_MAX_CELLS"], env={"CRFMAP_MAX_CELLS": "1e400"})


CASES.append(Case("environment", "CRFMAP_MAX_CELLS-1e400-load_grid", _load_grid_with_bad_limit))
