"""A one-node SLURM cluster on this machine, all of it in one temporary folder: the SLURM profile run for real.

    make slurm-sweep [SWEEP=02_noise_quick]          # = python -m crfstudy.repro.local_slurm sweep 02_noise_quick
    python -m crfstudy.repro.local_slurm run -- CMD  # CMD (sinfo, sbatch --wrap ..., a shell) on a cluster of its own

Each starts the cluster, runs, and stops it. ``sweep`` runs every point of the sweep anew, as one SLURM job each,
through ``workflow/profiles/slurm`` (:func:`sweep_command`), then checks (:func:`check_sweep`) that each point's
outputs are there and that slurmctld saw its jobs end with status 0.

:class:`LocalCluster` writes a ``slurm.conf`` and a fresh munge key into its folder and starts ``munged``,
``slurmctld`` and ``slurmd`` (Debian's ``munge`` and ``slurm-wlm``) as child processes on free ports of 127.0.0.1;
one node, this machine as ``slurmd -C`` sees it, one partition. No cgroups, no accounting database, nothing
written outside the folder; stopping cancels the cluster's jobs, ends the three daemons and deletes the folder.
It needs root (slurmd runs each job as its user): :func:`unavailable` says why a cluster cannot run here.

Client commands find the configuration through ``SLURM_CONF`` and, inside jobs too, through ``bin/``: wrappers
of sbatch, srun, squeue, ... that set it. The wrappers are needed because snakemake's jobstep executor
(snakemake-executor-plugin-slurm-jobstep 0.6) removes every ``SLURM_*`` variable but the job's identity before
its ``srun`` inside a job, and srun would then look for ``/etc/slurm/slurm.conf``; the job keeps ``PATH``.
"""
from __future__ import annotations

import argparse
import os
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from crfmap.errors import one_line

DAEMONS = ("munged", "slurmctld", "slurmd")
CLIENTS = ("sbatch", "srun", "squeue", "scontrol", "sinfo", "scancel", "sacct", "sacctmgr", "sshare")
PARTITION = "local"
SOCKET_PATH_MAX = 100  # [bytes] the longest socket path we let slurmd make (a job step's; Linux allows 107)
START_SECONDS = 30  # for each daemon to answer; a daemon that cannot start usually exits within a second
# The profile's account and partition are a site's and its resources a real node's: on this one node the jobs run
# in the default partition without an account (none given: the plugin says it proceeds without), with one core
# each, so two points run side by side on two cores. Job states come from squeue (no accounting database for
# sacct); the first status check comes after 5 s instead of 40 s.
SNAKEMAKE_OPTIONS = ("--default-resources", "runtime=10", "mem_mb=1000", "cpus_per_task=1",
                     "--slurm-status-command", "squeue", "--slurm-init-seconds-before-status-checks", "5")


class ClusterError(RuntimeError):
    """The local cluster could not start (the message names the daemon and the last line of its log)."""


def _find(name) -> str | None:
    """The program ``name`` on PATH or in the sbin folders, where the daemons live but a user's PATH may not look."""
    return shutil.which(name, path=os.pathsep.join([os.environ.get("PATH", ""), "/usr/sbin", "/sbin",
                                                     "/usr/local/sbin"]))


def unavailable() -> str | None:
    """Why a local cluster cannot run on this machine (``None``: it can). Fast: looks at files only."""
    if not sys.platform.startswith("linux"):
        return f"a local SLURM cluster needs Linux, this is {sys.platform}"
    missing = [name for name in DAEMONS + CLIENTS[:5] if _find(name) is None]
    if missing:
        return f"SLURM or munge not installed: {', '.join(missing)} not found (Debian: apt install slurm-wlm munge)"
    if os.geteuid() != 0:
        return "a local SLURM cluster needs root: slurmd runs each job as its user"
    try:
        import snakemake_executor_plugin_slurm  # noqa: F401  (the profile's executor)
    except ImportError:
        return "snakemake-executor-plugin-slurm not installed (pip install -e '.[test]')"
    return None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LocalCluster:
    """munged, slurmctld and slurmd of a one-node cluster in ``folder`` (default: a new temporary folder).

    ``with LocalCluster() as cluster: subprocess.run(["sbatch", ...], env=cluster.environment())``
    """

    def __init__(self, folder=None):
        self.made_folder = folder is None  # a folder of our own is deleted on stop
        self.folder = Path(folder or tempfile.mkdtemp(prefix="crfmap-slurm-")).resolve()
        self.conf = self.folder / "etc" / "slurm.conf"
        self.bin = self.folder / "bin"
        self.logs = self.folder / "log"
        self.processes: dict[str, subprocess.Popen] = {}

    def environment(self, base=None) -> dict:
        """``base`` (default: this process's environment) with the cluster's client commands first on PATH."""
        base = dict(os.environ if base is None else base)
        return {**base, "SLURM_CONF": str(self.conf), "PATH": f"{self.bin}{os.pathsep}{base.get('PATH', '')}"}

    def start(self) -> LocalCluster:
        try:
            reason = unavailable()
            if reason:
                raise ClusterError(reason)
            node = self._node()
            longest_socket = self.folder / "spool" / f"{node['NodeName']}_4294967294.4294967294"  # a job step's
            if len(str(longest_socket).encode()) > SOCKET_PATH_MAX:
                raise ClusterError(f"{self.folder}: too long a path for the daemons' sockets (give a shorter folder)")
            for sub in ("etc", "bin", "log", "munge", "state", "spool", "run"):
                (self.folder / sub).mkdir(mode=0o700, parents=True, exist_ok=True)
            munge_socket, key = self.folder / "munge" / "socket", self.folder / "munge" / "munge.key"
            key.touch(mode=0o600)
            key.write_bytes(secrets.token_bytes(1024))  # a key of this cluster only: munge authenticates its messages
            self._write_clients()
            self._write_conf(node, munge_socket)
            self._spawn("munged", "--foreground", "--force", f"--socket={munge_socket}", f"--key-file={key}",
                        f"--pid-file={self.folder / 'run' / 'munged.pid'}", f"--seed-file={self.folder / 'munge' / 'seed'}",
                        f"--log-file={self.logs / 'munged.log'}")
            self._wait("munged", munge_socket.exists)
            self._spawn("slurmctld", "-D", "-f", str(self.conf))
            self._wait("slurmctld", lambda: "is UP" in self._client("scontrol", "ping"))
            self._spawn("slurmd", "-D", "-f", str(self.conf))
            self._wait("slurmd", lambda: self._client("sinfo", "--noheader", "--format=%t").strip() == "idle")
        except BaseException:
            self.stop()  # the daemons started so far, and a folder of our own
            raise
        return self

    @staticmethod
    def _node() -> dict:
        """This machine as ``slurmd -C`` sees it (NodeName, CPUs, cores, RealMemory): the node never drains as low."""
        done = subprocess.run([_find("slurmd"), "-C"], capture_output=True, text=True, timeout=30,
                              env={**os.environ, "SLURM_CONF": "/dev/null"})
        fields = dict(item.split("=", 1) for item in (done.stdout.splitlines() or [""])[0].split() if "=" in item)
        if "NodeName" not in fields or "CPUs" not in fields:
            raise ClusterError(f"slurmd -C did not describe this machine: {one_line(done.stdout + done.stderr)}")
        return fields

    def _write_clients(self):
        for name in CLIENTS:
            real = _find(name)
            if real is None:
                continue
            wrapper = self.bin / name
            wrapper.write_text(f'#!/bin/sh\nSLURM_CONF="{self.conf}" exec "{real}" "$@"\n')
            wrapper.chmod(0o755)

    def _write_conf(self, node, munge_socket):
        host = node["NodeName"]
        f = self.folder
        self.conf.write_text("\n".join([
            "ClusterName=crfmap-local",
            f"SlurmctldHost={host}(127.0.0.1)", f"SlurmctldPort={_free_port()}", f"SlurmdPort={_free_port()}",
            "SlurmUser=root", "SlurmdUser=root",
            "AuthType=auth/munge", "CredType=cred/munge", f"AuthInfo=socket={munge_socket}",
            f"StateSaveLocation={f / 'state'}", f"SlurmdSpoolDir={f / 'spool'}",
            f"SlurmctldPidFile={f / 'run' / 'slurmctld.pid'}", f"SlurmdPidFile={f / 'run' / 'slurmd.pid'}",
            f"SlurmctldLogFile={self.logs / 'slurmctld.log'}", f"SlurmdLogFile={self.logs / 'slurmd.log'}",
            "SlurmctldDebug=info", "SlurmdDebug=info",
            f"PlugStackConfig={f / 'etc' / 'plugstack.conf'}",  # none: not the system's /etc/slurm/plugstack.conf
            "ProctrackType=proctrack/linuxproc", "TaskPlugin=task/none",  # no cgroups
            "SelectType=select/cons_tres", "SelectTypeParameters=CR_Core",
            "JobAcctGatherType=jobacct_gather/none", "AccountingStorageType=accounting_storage/none",
            "JobCompType=jobcomp/none", "MpiDefault=none", "ReturnToService=2", "MailProg=/bin/true",
            "MinJobAge=600",  # finished jobs stay in squeue for 10 min: the workflow reads their state there
            " ".join(f"{k}={v}" for k, v in node.items()) + " NodeAddr=127.0.0.1 State=UNKNOWN",
            f"PartitionName={PARTITION} Nodes={host} Default=YES MaxTime=INFINITE State=UP", ""]))
        (f / "etc" / "plugstack.conf").write_text("")

    def _spawn(self, name, *args):
        log = open(self.logs / f"{name}.out", "ab")  # what a daemon prints before its own log is open
        with log:
            self.processes[name] = subprocess.Popen([_find(name), *args], stdout=log, stderr=subprocess.STDOUT,
                                                    stdin=subprocess.DEVNULL, start_new_session=True)

    def _client(self, name, *args, timeout=10) -> str:
        try:
            done = subprocess.run([str(self.bin / name), *args], capture_output=True, text=True, timeout=timeout,
                                  env=self.environment())
        except subprocess.TimeoutExpired:
            return ""
        return done.stdout

    def _wait(self, name, ready):
        deadline = time.monotonic() + START_SECONDS
        while not ready():
            code = self.processes[name].poll()
            if code is not None or time.monotonic() > deadline:
                state = f"exited with status {code}" if code is not None else f"not ready after {START_SECONDS} s"
                raise ClusterError(f"{name} {state}: {self.last_log_line(name)}")
            time.sleep(0.2)

    def last_log_line(self, name) -> str:
        lines = []
        for log in (self.logs / f"{name}.log", self.logs / f"{name}.out"):
            if log.exists():
                lines += [line for line in log.read_text(errors="replace").splitlines() if line.strip()]
        return lines[-1] if lines else f"its log is empty ({self.logs})"

    def completed_jobs(self) -> dict[int, int]:
        """``{job id: exit status}`` of every batch job slurmctld saw end (from its log)."""
        log = self.logs / "slurmctld.log"
        text = log.read_text(errors="replace") if log.exists() else ""
        return {int(job): int(status) for job, status in re.findall(r"_job_complete: JobId=(\d+) WEXITSTATUS (\d+)",
                                                                    text)}

    def stop(self):
        """Cancel the cluster's jobs, end its daemons (slurmd, slurmctld, munged), delete a folder of our own."""
        if "slurmctld" in self.processes and self.processes["slurmctld"].poll() is None:
            self._client("scancel", f"--partition={PARTITION}")
            deadline = time.monotonic() + 15
            while self._client("squeue", "--noheader", "--states=RUNNING,COMPLETING") and time.monotonic() < deadline:
                time.sleep(0.5)
        for name in reversed(DAEMONS):
            process = self.processes.get(name)
            if process is None or process.poll() is not None:
                continue
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        if self.made_folder:
            shutil.rmtree(self.folder, ignore_errors=True)

    def __enter__(self) -> LocalCluster:
        return self.start()

    def __exit__(self, *exc):
        self.stop()


def sweep_command(name, cores=2) -> list[str]:
    """``reproduce`` running sweep ``name`` through ``workflow/profiles/slurm`` on the local cluster, every point anew."""
    from crfstudy import paths

    profile = paths.PROJECT_ROOT / "workflow" / "profiles" / "slurm"
    return [sys.executable, "-m", "crfstudy.repro.reproduce", "--cores", str(cores), "--profile", str(profile),
            "--sweep", name, "--", *SNAKEMAKE_OPTIONS, "--forcerun", "sweep_point"]


def check_sweep(name, cluster: LocalCluster) -> list[str]:
    """What is wrong with sweep ``name``'s run on ``cluster`` (empty: every point ran as a SLURM job and is there)."""
    from crfstudy import paths
    from crfstudy.repro.reproduce import sweep_file
    from crfstudy.repro.sweep import load

    sweep = load(sweep_file(name))
    runs = paths.OUTPUT_ROOT / "out" / "runs" / sweep.name
    problems = [f"{runs / point}: no executed {sweep.notebook.name}" for point in sweep.points()
                if not (runs / point / sweep.notebook.name).is_file()]
    if not (runs / "collected.csv").is_file():
        problems.append(f"{runs / 'collected.csv'}: missing")
    succeeded = [job for job, status in cluster.completed_jobs().items() if status == 0]
    if len(succeeded) < len(sweep.points()):
        problems.append(f"slurmctld saw {len(succeeded)} jobs succeed for {len(sweep.points())} points "
                        f"({cluster.logs / 'slurmctld.log'})")
    return problems


def _end_group(child, seconds=30):
    """End ``child``'s process group: SIGINT (snakemake then cancels its SLURM jobs and exits; on SIGTERM it would
    wait for them to finish), then, after ``child`` ended or ``seconds``, SIGKILL to whatever is left of it."""
    for sig in (signal.SIGINT, signal.SIGKILL):
        try:
            os.killpg(child.pid, sig)
        except ProcessLookupError:  # the group is gone
            break
        try:
            child.wait(timeout=seconds)
        except subprocess.TimeoutExpired:
            pass


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crfstudy.repro.local_slurm", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="action", required=True)
    sweep = sub.add_parser("sweep", help="run a sweep (default 02_noise_quick) through workflow/profiles/slurm")
    sweep.add_argument("name", nargs="?", default="02_noise_quick", help="a sweep of workflow/sweeps/ or a .yaml")
    sweep.add_argument("--cores", type=int, default=2, help="snakemake's --cores (the collect step's)")
    run = sub.add_parser("run", help="run a command with the cluster's environment (its sbatch, srun, squeue...)")
    run.add_argument("command", nargs=argparse.REMAINDER, help="-- then the command")
    args = parser.parse_args(argv)
    command = sweep_command(args.name, args.cores) if args.action == "sweep" else args.command
    command = command[1:] if command[:1] == ["--"] else command  # only the first --: the command may have its own
    if not command:
        parser.error("run: give a command after --")
    # SIGTERM (a killed make) ends this process through its finally: the daemons are stopped, not left running
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    cluster = LocalCluster()
    try:
        cluster.start()
    except ClusterError as exc:
        print(f"local_slurm: {exc}", file=sys.stderr)
        return 2
    try:
        print(f"local_slurm: one-node cluster up in {cluster.folder}", file=sys.stderr)
        try:  # a process group of its own: on Ctrl-C or SIGTERM here, all of it (reproduce and snakemake) is ended
            child = subprocess.Popen(command, env=cluster.environment(), start_new_session=True)
        except OSError as exc:
            print(f"local_slurm: {command[0]}: {exc.strerror or exc}", file=sys.stderr)
            return 2
        try:
            code = child.wait()
        finally:
            if child.poll() is None:  # interrupted: the workflow ends first, then the cluster
                _end_group(child)
        jobs = cluster.completed_jobs()
        print(f"local_slurm: slurmctld ran {len(jobs)} job{'s' * (len(jobs) != 1)}"
              f"{': ' + ', '.join(f'{j} (exit {s})' for j, s in sorted(jobs.items())) if jobs else ''}", file=sys.stderr)
        if code == 0 and args.action == "sweep":
            problems = check_sweep(args.name, cluster)
            for line in problems or [f"every point of {args.name} ran as a SLURM job; its outputs are there"]:
                print(f"local_slurm: {line}", file=sys.stderr)
            code = 1 if problems else 0
        return code
    finally:
        cluster.stop()
        print("local_slurm: cluster stopped", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
