"""A user who cannot write the kernel cache (the venv's, made by another user) still reads ``crfmap --help``."""
import os
import subprocess
import sys

import pytest


@pytest.mark.parametrize("argv", [["--help"], ["infer", "--help"]])
def test_help_needs_no_kernel_cache(argv):
    env = dict(os.environ, NUMBA_CACHE_DIR="/proc/crfmap-numba")  # no one can write there
    done = subprocess.run([sys.executable, "-m", "crfmap", *argv], capture_output=True, text=True, env=env,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: crfmap") and done.stderr == ""
