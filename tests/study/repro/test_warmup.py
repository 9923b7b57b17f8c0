"""The numba cache warm-up: knows (by its own stamp) when the cache is cold, and when it has nothing to do."""
from crfstudy.repro import warmup


def test_an_empty_cache_is_cold_and_a_fresh_stamp_is_warm(tmp_path, monkeypatch):
    import os

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    assert not warmup.is_warm()
    (tmp_path / "cache").mkdir()
    stamp = tmp_path / "cache" / "crfmap-warmed.stamp"
    stamp.touch()
    assert warmup.is_warm()  # newer than every source crfmap infer runs
    oldest = min(p.stat().st_mtime for p in warmup._sources())
    os.utime(stamp, (oldest - 1, oldest - 1))  # a source changed since the warm-up: cold again
    assert not warmup.is_warm()


def test_the_tasks_are_shared_out_evenly_and_unknown_ones_refused():
    import pytest

    groups = warmup.share(list(warmup.all_tasks()), 2)
    assert sorted(t for g in groups for t in g) == sorted(warmup.all_tasks())
    load = [sum(warmup.all_tasks()[t][1] for t in g) for g in groups]
    assert max(load) - min(load) <= max(cost for _, cost in warmup.all_tasks().values())
    assert warmup.share(["sweep"], 4) == [["sweep"]]  # no empty processes
    with pytest.raises(ValueError, match="unknown warm-up task"):
        warmup.run_tasks(["no such task"])


def test_every_module_with_cached_numba_kernels_is_watched():
    """A change to any module holding ``cache=True`` kernels makes the cache cold again."""
    watched = {p.resolve() for p in warmup._sources()}
    kernels = {p.resolve() for p in warmup.LIBRARY.rglob("*.py")
               if "cache=True" in p.read_text() and p.name != "_numba_cache.py"}
    assert kernels and kernels <= watched, sorted(str(p) for p in kernels - watched)


def test_the_warm_up_runs_with_only_the_distributions_installed_first():
    """`make venv` installs warmup.NEEDS, then warms the cache while pip installs the rest: every task must run
    with the other distributions absent (here their imports fail, as they would before pip writes them)."""
    import json
    import subprocess
    import sys
    from importlib import metadata

    from packaging.requirements import Requirement

    def closure(names):  # the distributions pip installs with these (their requirements on this platform)
        seen, todo = set(), [n.lower() for n in names]
        while todo:
            name = todo.pop()
            if name in seen:
                continue
            seen.add(name)
            for req in map(Requirement, metadata.requires(name) or []):
                if req.marker is None or req.marker.evaluate({"extra": ""}):
                    todo.append(req.name.lower().replace("_", "-"))
        return seen

    code = ("import json, sys, importlib.metadata as md\n"
            "allowed = set(json.loads(sys.argv[1])) | {'crfmap', 'crfmap-study'}  # the checkout: on PYTHONPATH (lib, study) in make venv\n"
            "owners = md.packages_distributions()\n"
            "class NotInstalledYet:\n"
            "    def find_spec(self, name, path=None, target=None):\n"
            "        dists = {d.lower().replace('_', '-') for d in owners.get(name.split('.')[0], [])}\n"
            "        if dists and not dists & allowed:\n"
            "            blocked.add(name.split('.')[0])\n"
            "            raise ModuleNotFoundError(f'{name} is not installed yet')\n"
            "blocked = set()\n"
            "sys.meta_path.insert(0, NotInstalledYet())\n"
            "from crfstudy.repro import warmup\n"
            "warmup.run_tasks(list(warmup.all_tasks()))\n"
            "print(json.dumps(sorted(blocked)))\n")
    run = subprocess.run([sys.executable, "-c", code, json.dumps(sorted(closure(warmup.NEEDS)))],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    print("imports refused, and survived:", run.stdout.strip().splitlines()[-1])  # optional ones (numba's cffi)
    assert [r.split(">")[0].lower().replace("_", "-") for r in warmup.requirements()] == list(warmup.NEEDS)
