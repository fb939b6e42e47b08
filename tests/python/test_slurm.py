"""`uq-driver slurm` on a real single-node Slurm cluster that this module starts
(tests/slurm/slurm.sh: slurm-wlm and munge from Debian, installed with apt-get if missing; its
own munged, slurmctld and slurmd under a temp dir, on free ports) and stops afterwards, even
when a test fails.

Where Slurm cannot be had (not root, no apt-get, the install fails) the tests are skipped with
the reason, except under CI (env CI set), where that is a failure."""
import os
import pathlib
import re
import shutil
import subprocess
import tempfile
import time

import pytest

from conftest import ROOT
from test_shards import assert_same_outputs, driver, local_run, records_in, resumed_count, \
    write_study

SCRIPT = ROOT / "tests" / "slurm" / "slurm.sh"
UNAVAILABLE = 77  # slurm.sh start: Slurm cannot be had on this machine
JOB_TIMEOUT = 180  # seconds for a whole study on the cluster
FINAL_STATES = {"COMPLETED", "FAILED", "CANCELLED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY",
                "BOOT_FAIL", "DEADLINE", "PREEMPTED", "REVOKED"}


def in_ci():
    return os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no")


class Cluster:
    def __init__(self, folder, conf):
        self.folder = pathlib.Path(folder)
        self.env = dict(os.environ, SLURM_CONF=conf)

    def cmd(self, *args, check=True, timeout=60):
        p = subprocess.run([str(a) for a in args], capture_output=True, text=True, env=self.env,
                           timeout=timeout)
        if check and p.returncode != 0:
            pytest.fail(f"{' '.join(map(str, args))} exited {p.returncode}:\n{p.stdout}{p.stderr}"
                        f"{self.logs()}")
        return p.stdout

    def sbatch(self, *args):
        return self.cmd("sbatch", "--parsable", *args).strip().split(";")[0]

    def jobs(self, job_id):
        """{job or array task id: (state, reason)} as scontrol reports them."""
        out = self.cmd("scontrol", "-o", "show", "job", job_id, check=False)
        jobs = {}
        for line in out.splitlines():
            f = dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
            if "JobId" not in f:
                continue
            jid = f["JobId"]
            if f.get("ArrayTaskId") and "_" not in jid:
                jid = f"{f.get('ArrayJobId', jid)}_{f['ArrayTaskId']}"
            jobs[jid] = (f.get("JobState", "?"), f.get("Reason", ""))
        return jobs

    def wait(self, job_id, until=lambda jobs: False, timeout=JOB_TIMEOUT, plan_dir=None):
        """Waits until every job or task of job_id has ended (or `until(jobs)`); returns the
        states. A job whose dependency can never be met fails the test."""
        deadline = time.monotonic() + timeout
        while True:
            jobs = self.jobs(job_id)
            if until(jobs):
                return jobs
            if jobs and all(s in FINAL_STATES for s, _ in jobs.values()):
                return jobs
            stuck = [j for j, (s, r) in jobs.items() if r == "DependencyNeverSatisfied"]
            if stuck:
                pytest.fail(f"job {stuck} will never run (a job it depends on failed): {jobs}"
                            f"{self.logs(plan_dir)}")
            if time.monotonic() > deadline:
                pytest.fail(f"job {job_id} not done after {timeout} s: {jobs}{self.logs(plan_dir)}")
            time.sleep(0.2)

    def logs(self, plan_dir=None):
        text = ""
        dirs = [plan_dir] if plan_dir else []
        for f in [p for d in dirs for p in sorted((pathlib.Path(d) / "slurm").glob("*.out"))] + \
                sorted((self.folder / "log").glob("*.log")):
            lines = f.read_text(errors="replace").splitlines()[-15:]
            text += f"\n--- {f} (end) ---\n" + "\n".join(lines)
        return text


@pytest.fixture(scope="module")
def cluster():
    folder = tempfile.mkdtemp(prefix="railuq-slurm-", dir="/tmp")
    started = False
    try:
        if os.geteuid() != 0:
            reason = "a test Slurm needs root (slurmd runs the jobs as root here)"
            rc = UNAVAILABLE
        else:
            t0 = time.monotonic()
            p = subprocess.run(["bash", str(SCRIPT), "start", folder], capture_output=True,
                               text=True, timeout=900)
            rc = p.returncode
            reason = p.stderr.strip()
            print(f"slurm.sh start: {time.monotonic() - t0:.1f} s, exit {rc}")
        if rc == UNAVAILABLE:
            message = f"Slurm cannot be started here: {reason}"
            if in_ci():
                pytest.fail(message + " (CI is set: this is a failure, not a skip)")
            pytest.skip(message)
        if rc != 0:
            pytest.fail(f"tests/slurm/slurm.sh start {folder} failed (exit {rc}):\n{reason}")
        started = True
        conf = re.search(r"^SLURM_CONF=(.+)$", p.stdout, re.M)
        assert conf, p.stdout
        yield Cluster(folder, conf.group(1))
    finally:
        stop = subprocess.run(["bash", str(SCRIPT), "stop", folder], capture_output=True,
                              text=True, timeout=120)
        if stop.returncode == 0:
            shutil.rmtree(folder, ignore_errors=True)
        elif started:
            print(f"slurm.sh stop {folder} failed: {stop.stderr}")


def submit(cluster, study, out, *extra):
    """`uq-driver slurm`; returns (array job id, merge job id)."""
    p = driver("slurm", study, "--shards", 4, "--out", out, *extra, env=cluster.env)
    array = re.search(r"^array job (\d+)\s*$", p.stdout, re.M)
    merge = re.search(r"^merge job (\d+)\s*$", p.stdout, re.M)
    assert array and merge, f"no 'array job N' / 'merge job N' in:\n{p.stdout}{p.stderr}"
    return array.group(1), merge.group(1)


def test_slurm_study_equals_local_run(cluster, tmp_path):
    study = write_study(tmp_path, "wheel-slurm", samples=400)
    out = tmp_path / "plan"
    array, merge = submit(cluster, study, out)
    assert (out / "plan.json").is_file()
    assert (out / "slurm" / "shard.sbatch").is_file() and (out / "slurm" / "merge.sbatch").is_file()
    states = cluster.wait(merge, plan_dir=out)
    assert states == {merge: ("COMPLETED", "None")}, f"{states}{cluster.logs(out)}"
    tasks = cluster.wait(array, plan_dir=out)
    assert sorted(tasks) == [f"{array}_{k}" for k in range(4)], tasks
    assert all(s == "COMPLETED" for s, _ in tasks.values()), f"{tasks}{cluster.logs(out)}"
    for k in range(4):
        assert records_in(out / "shards" / str(k)) == 100
    assert_same_outputs(out / "result", local_run(study, tmp_path / "local"))


def test_slurm_cancelled_task_resumes(cluster, tmp_path):
    # h = 1e-5: a point takes ~20 ms, a shard of 50 points ~1 s on one CPU: long enough to
    # cancel task 1 after its first points.
    study = write_study(tmp_path, "wheel-slurm-kill", samples=200, h=1e-5)
    out = tmp_path / "plan"
    array, merge = submit(cluster, study, out, "--cpus-per-task", 1)
    shard1 = out / "shards" / "1"
    deadline = time.monotonic() + JOB_TIMEOUT
    while records_in(shard1) < 1:
        assert time.monotonic() < deadline, f"shard 1 never started{cluster.logs(out)}"
        time.sleep(0.01)
    cluster.cmd("scancel", f"{array}_1")
    tasks = cluster.wait(array, plan_dir=out)
    assert tasks[f"{array}_1"][0] == "CANCELLED", tasks
    done = records_in(shard1)
    assert 0 < done < 50, f"task 1 was to be cancelled part-way; it had {done} of 50 points"
    assert all(tasks[f"{array}_{k}"][0] == "COMPLETED" for k in (0, 2, 3)), tasks
    # The merge depended on afterok of the whole array: it never runs now. It stays pending
    # (DependencyNeverSatisfied) or, with --kill-on-invalid-dep, is cancelled; either way it goes.
    states = cluster.wait(merge, until=lambda jobs: jobs.get(merge, ("", ""))[1]
                          == "DependencyNeverSatisfied", timeout=30, plan_dir=out)
    assert states[merge][0] in ("PENDING", "CANCELLED"), states
    cluster.cmd("scancel", merge, check=False)
    assert not (out / "result" / "summary.json").exists()
    # Re-submit task 1 alone and the merge after it, as a user would.
    again = cluster.sbatch("--array=1", out / "slurm" / "shard.sbatch")
    merge2 = cluster.sbatch(f"--dependency=afterok:{again}", out / "slurm" / "merge.sbatch")
    states = cluster.wait(merge2, plan_dir=out)
    assert states == {merge2: ("COMPLETED", "None")}, f"{states}{cluster.logs(out)}"
    log = (out / "slurm" / "shard-1.out").read_text()
    assert resumed_count(log) == done, log
    assert records_in(shard1) == 50, "the resumed task ran points it already had"
    assert_same_outputs(out / "result", local_run(study, tmp_path / "local"))
