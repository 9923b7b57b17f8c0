"""The SLURM profile for real: a one-node cluster on this machine runs a two-point sweep as SLURM jobs, then stops.

Where SLURM cannot run (no slurm-wlm or munge, not root: CI) the cluster test skips, naming what is missing.
"""
import csv
import os
import re
import subprocess
from pathlib import Path

import pytest

from crfstudy.repro import local_slurm, provenance
from crfstudy.repro.reproduce import sweep_file
from crfstudy.repro.sweep import load

SWEEP = "02_noise_quick"  # notebook 02 at two noise levels, quick settings: seconds per point


def test_without_slurm_the_reason_names_the_missing_commands(monkeypatch):
    monkeypatch.setattr(local_slurm, "_find", lambda name: None if name in ("sbatch", "slurmd") else "/bin/true")
    reason = local_slurm.unavailable()
    assert reason is not None and "slurmd, sbatch not found" in reason
    cluster = local_slurm.LocalCluster()
    with pytest.raises(local_slurm.ClusterError, match="slurmd, sbatch not found"):
        cluster.start()
    assert not cluster.folder.exists() and not cluster.processes  # nothing started, its temporary folder removed


def test_without_root_the_reason_says_so(monkeypatch):
    monkeypatch.setattr(local_slurm, "_find", lambda name: "/bin/true")
    monkeypatch.setattr(os, "geteuid", lambda: 1000)
    assert local_slurm.unavailable() == "a local SLURM cluster needs root: slurmd runs each job as its user"


def test_a_daemon_that_cannot_start_is_named_and_nothing_is_left(monkeypatch):
    reason = local_slurm.unavailable()
    if reason:
        pytest.skip(reason)
    real = local_slurm._find
    monkeypatch.setattr(local_slurm, "_find", lambda name: "/bin/false" if name == "munged" else real(name))
    cluster = local_slurm.LocalCluster()
    with pytest.raises(local_slurm.ClusterError, match=r"^munged exited with status 1: "):
        cluster.start()
    assert set(cluster.processes) == {"munged"} and cluster.processes["munged"].poll() == 1
    assert not cluster.folder.exists()


@pytest.mark.slow
def test_a_two_point_sweep_runs_as_slurm_jobs_on_a_local_cluster(tmp_path, monkeypatch):
    reason = local_slurm.unavailable()
    if reason:
        pytest.skip(reason)
    sweep = load(sweep_file(SWEEP))
    assert list(sweep.grid) == ["noise"] and len(sweep.points()) == 2 and sweep.fixed == {"quick": True}
    out = tmp_path / "out"
    out.mkdir()
    monkeypatch.setenv("CRFMAP_OUTPUT_ROOT", str(out))
    cluster = local_slurm.LocalCluster()
    try:
        cluster.start()
    except local_slurm.ClusterError as exc:
        pytest.skip(f"the local SLURM cluster did not start: {exc}")
    daemons = dict(cluster.processes)
    try:
        assert set(daemons) == set(local_slurm.DAEMONS)
        done = subprocess.run(local_slurm.sweep_command(SWEEP), env=cluster.environment(), capture_output=True,
                              text=True, timeout=600)
        text = done.stdout + done.stderr
        assert done.returncode == 0, text[-4000:]
        submitted = {int(job) for job in re.findall(r"submitted with SLURM jobid (\d+)", text)}
        completed = cluster.completed_jobs()
        problems = local_slurm.check_sweep(SWEEP, cluster)
    finally:
        cluster.stop()
    # the workflow submitted one job per point, and slurmctld saw exactly those jobs end with status 0
    assert len(submitted) == 2 and completed == {job: 0 for job in submitted}, (submitted, completed)
    assert problems == []
    runs = out / "out" / "runs" / SWEEP
    for point, parameters in sweep.points().items():
        assert (runs / point / "02_worked_example.ipynb").is_file()
        stamp = provenance.read(runs / point / "paper" / "generated" / "learning_toy.json")
        assert stamp["parameters"]["noise"] == parameters["noise"] and stamp["quick"] is True
    rows = list(csv.DictReader((runs / "collected.csv").open()))
    assert [(r["point"], float(r["noise"])) for r in rows] == [(p, v["noise"]) for p, v in sweep.points().items()]
    assert rows[0]["learning_toy.mse_observed"] != rows[1]["learning_toy.mse_observed"]  # each ran its own noise
    # stopped: the three daemons ended (and were reaped), the cluster's folder is gone
    assert all(process.poll() is not None for process in daemons.values())
    assert not any(Path(f"/proc/{process.pid}").exists() for process in daemons.values())
    assert not cluster.folder.exists()
    assert "SLURM_CONF" not in os.environ  # the cluster's configuration reached only the commands run on it
