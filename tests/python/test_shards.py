"""`uq-driver plan` / `run-shard` / `merge` without a cluster: the merged outputs equal those of
`uq-driver run`, a killed shard resumes, and `merge` refuses a missing shard, a shard of another
plan and a duplicated point, naming it. (The Slurm path is in test_slurm.py.)"""
import json
import os
import pathlib
import re
import shutil
import signal
import struct
import subprocess
import time

import pytest

from conftest import DRIVER, fmu_path

# Outputs that must be byte-identical between a sharded and a single-machine run.
SAME_FILES = ("q.csv", "q_pdf.csv", "points.csv")


def driver(*args, check=True, env=None, timeout=600):
    """Runs uq-driver; returns the CompletedProcess (stdout and stderr as text)."""
    if not DRIVER.is_file():
        pytest.fail(f"{DRIVER} is missing: run `make build` first")
    p = subprocess.run([str(DRIVER), *map(str, args)], capture_output=True, text=True,
                       env=env, timeout=timeout)
    if check and p.returncode != 0:
        pytest.fail(f"uq-driver {' '.join(map(str, args))} exited {p.returncode}:\n"
                    f"{p.stdout}\n{p.stderr}")
    return p


def write_study(folder, name, samples=400, seed=42, h=None):
    """The built-in wheel-lhs-1000 study, renamed, with the absolute FMU path and `samples`
    samples; `h` (largest RK4 step) makes every point slower, for the kill tests."""
    text = driver("show", "wheel-lhs-1000").stdout
    text = text.replace('fmu = "Wheel.fmu"', f'fmu = "{fmu_path("Wheel")}"')
    text = re.sub(r'^name = ".*"$', f'name = "{name}"', text, count=1, flags=re.M)
    text = re.sub(r"^samples = \d+$", f"samples = {samples}", text, count=1, flags=re.M)
    text = re.sub(r"^seed = \d+$", f"seed = {seed}", text, count=1, flags=re.M)
    assert f'name = "{name}"' in text and f"samples = {samples}" in text, text
    if h is not None:
        text += f"\n[fixed]\nh = {h!r}\n"
    path = pathlib.Path(folder) / f"{name}.toml"
    path.write_text(text)
    return path


def local_run(study, out):
    driver("run", study, "--out", out)
    return pathlib.Path(out)


def assert_same_outputs(merged, reference):
    merged, reference = pathlib.Path(merged), pathlib.Path(reference)
    for name in SAME_FILES:
        a, b = merged / name, reference / name
        assert a.is_file(), f"{a} is missing"
        assert a.read_bytes() == b.read_bytes(), f"{a} differs from {b}"
    summary = json.loads((merged / "summary.json").read_text())
    assert summary, "empty summary.json"
    assert (merged / "index.html").is_file()


def record_size(shard_dir):
    """Bytes of one successful record in a shard's store (format 2, see uq-driver's study/store/format.rs: 25-byte header, 4-byte trailer)."""
    manifest = json.loads((pathlib.Path(shard_dir) / "store" / "manifest.json").read_text())
    return 29 + 8 * manifest["n_values"]


def identity_size(records):
    """Bytes of the identity frame (kind 2) a store's records.bin begins with, 0 without one
    (format 2: magic, index u64, kind u8, length u64, header crc32, payload, crc32)."""
    if len(records) < 25 or records[:4] != b"\xf5RQ2" or records[12] != 2:
        return 0
    (length,) = struct.unpack("<Q", records[13:21])
    return 25 + length + 4


def records_in(shard_dir):
    """Whole records in a shard's store (a torn tail of a killed writer is not counted)."""
    path = pathlib.Path(shard_dir) / "store" / "records.bin"
    if not path.is_file() or not (pathlib.Path(shard_dir) / "store" / "manifest.json").is_file():
        return 0
    data = path.read_bytes()
    return (len(data) - identity_size(data)) // record_size(shard_dir)


def resumed_count(text):
    m = re.search(r"(\d+) resumed", text)
    assert m, f"no 'N resumed' in the run-shard output:\n{text}"
    return int(m.group(1))


def plan(study, out, shards=4):
    driver("plan", study, "--shards", shards, "--out", out)
    assert (pathlib.Path(out) / "plan.json").is_file()
    return pathlib.Path(out)


def run_shards(plan_dir, shards, threads=1):
    for k in shards:
        driver("run-shard", plan_dir, "--shard", k, "--threads", threads)


def test_merge_equals_run(tmp_path):
    study = write_study(tmp_path, "wheel-shards", samples=200)
    d = plan(study, tmp_path / "plan")
    for k, threads in ((0, 1), (1, 2), (2, 1), (3, 3)):
        driver("run-shard", d, "--shard", k, "--threads", threads)
    driver("merge", d)
    assert_same_outputs(d / "result", local_run(study, tmp_path / "local"))
    # --out elsewhere gives the same.
    driver("merge", d, "--out", tmp_path / "merged2")
    assert_same_outputs(tmp_path / "merged2", tmp_path / "local")


def test_killed_shard_resumes(tmp_path):
    # h = 1e-5 makes a point take ~20 ms: shard 1 (25 points) is killed after its first record.
    study = write_study(tmp_path, "wheel-shards-kill", samples=100, h=1e-5)
    d = plan(study, tmp_path / "plan")
    run_shards(d, (0, 2, 3))
    sdir = d / "shards" / "1"
    proc = subprocess.Popen([str(DRIVER), "run-shard", str(d), "--shard", "1", "--threads", "1"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while records_in(sdir) < 1 and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.005)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    done = records_in(sdir)
    assert 0 < done < 25, f"shard 1 was to be killed part-way, it had {done} of 25 points"
    # The merge refuses the incomplete shard and says which.
    p = driver("merge", d, check=False)
    assert p.returncode != 0
    assert "shard 1" in p.stderr, p.stderr
    again = driver("run-shard", d, "--shard", "1", "--threads", "1")
    assert resumed_count(again.stdout + again.stderr) == done
    assert records_in(sdir) == 25, "the resumed shard ran points it already had"
    driver("merge", d)
    assert_same_outputs(d / "result", local_run(study, tmp_path / "local"))


def merge_refused(d, pattern):
    """`uq-driver merge D` fails, with `pattern` (a regex) in its error and no result written;
    returns the finished process."""
    p = driver("merge", d, check=False)
    assert p.returncode != 0
    assert re.search(pattern, p.stderr), p.stderr
    assert not (d / "result" / "summary.json").exists()
    return p


def test_merge_names_a_missing_shard(tmp_path):
    d = plan(write_study(tmp_path, "wheel-shards", samples=40), tmp_path / "plan")
    run_shards(d, (0, 1, 3))
    p = merge_refused(d, r"\bshard 2\b")
    assert not re.search(r"\bshard [013]\b", p.stderr), f"names a complete shard: {p.stderr}"


def test_merge_names_a_shard_of_another_plan(tmp_path):
    d = plan(write_study(tmp_path, "wheel-shards", samples=40), tmp_path / "plan")
    other = plan(write_study(tmp_path, "wheel-shards-other", samples=40,
                             seed=7), tmp_path / "other")
    run_shards(d, (0, 1, 3))
    run_shards(other, (2,))
    shutil.copytree(other / "shards" / "2", d / "shards" / "2")
    merge_refused(d, r"\bshard 2\b")


def test_merge_names_a_duplicated_point(tmp_path):
    d = plan(write_study(tmp_path, "wheel-shards", samples=40), tmp_path / "plan")
    run_shards(d, (0, 1, 2, 3))
    # Append shard 0's first record, verbatim, to shard 1's store: that point is then twice.
    size = record_size(d / "shards" / "0")
    records = (d / "shards" / "0" / "store" / "records.bin").read_bytes()
    start = identity_size(records)
    assert start > 0, "a store begins with its identity frame"
    first = records[start:start + size]
    assert first[:4] == b"\xf5RQ2" and first[12] == 0  # a finished run (study/store/format.rs)
    (index,) = struct.unpack("<Q", first[4:12])
    with open(d / "shards" / "1" / "store" / "records.bin", "ab") as f:
        f.write(first)
    merge_refused(d, rf"\bpoint {index}\b")


def test_run_shard_outside_the_plan_is_refused(tmp_path):
    d = plan(write_study(tmp_path, "wheel-shards", samples=40), tmp_path / "plan")
    p = driver("run-shard", d, "--shard", 4, check=False)
    assert p.returncode != 0 and "shard 4" in p.stderr, p.stderr
    env = dict(os.environ, SLURM_ARRAY_TASK_ID="2")
    driver("run-shard", d, env=env)
    assert records_in(d / "shards" / "2") == 10
    assert not (d / "shards" / "0").exists()
