"""Importing crfmap changes nothing in the process: no environment variable, no import hook, no file."""
import os
import subprocess
import sys

CHILD = r"""
import os, sys, json
from pathlib import Path

def files(root):
    return sorted(str(p) for p in Path(root).rglob("*"))

root = Path(sys.argv[1])
before_env, before_hooks, before_files = dict(os.environ), list(sys.meta_path), files(root)
import crfmap, crfmap.assess, crfmap.crf, crfmap.io, crfmap.mapping, crfmap.ros, crfmap.sim, crfmap.world
import crfmap.crf.presets, crfmap.crf.inference.lbp, crfmap.assess.scansplit, crfmap.mapping.online
print(json.dumps({"env": dict(os.environ) == before_env, "env_diff": sorted(set(os.environ.items()) ^ set(before_env.items())),
                  "hooks": [repr(h) for h in sys.meta_path if h not in before_hooks],
                  "files": sorted(set(files(root)) ^ set(before_files))}))
"""


def test_import_crfmap_changes_nothing(tmp_path):
    import crfmap

    package = os.path.dirname(crfmap.__file__)
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "OMP_WAIT_POLICY")}
    env["PYTHONDONTWRITEBYTECODE"] = "1"  # Python's own bytecode files are not crfmap's doing
    run = subprocess.run([sys.executable, "-c", CHILD, package], env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    import json

    seen = json.loads(run.stdout.strip().splitlines()[-1])
    assert seen["env_diff"] == [] and seen["env"], seen["env_diff"]
    assert seen["hooks"] == []
    assert seen["files"] == []


def test_prepare_does_what_import_does_not(monkeypatch):
    import crfmap

    monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    crfmap.prepare()
    assert os.environ["OMP_WAIT_POLICY"] == "PASSIVE"
