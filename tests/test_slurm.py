"""The batch scripts in slurm/, end to end on this machine.

Stand-ins for sbatch and srun (tests/slurm_standin/, put first on PATH) run a
batch script at once with the SLURM_* variables Slurm would set, a job array
task by task, a dependency chain in order, and srun as the mpich wheel's
mpiexec on the step's task count.  Scenes are tiny; everything else (parslip,
MPI, HDF5 files, numba's cache) is real.
"""
import os
import subprocess
import sys
try:
    import tomllib
except ImportError:          # Python 3.10
    import tomli as tomllib
from pathlib import Path

import h5py
import pytest

from helpers import REPO, WHEEL_MPIEXEC, cli_env, datasets, require, small_toml
from parslip.io.contract import read_status

SLURM = REPO / "slurm"
STANDIN = REPO / "tests" / "slurm_standin"
SCRIPTS = sorted(SLURM.glob("*.sbatch")) + sorted(SLURM.glob("*.sh"))
TINY = {"drive.duration": 1.0, "output.snapshots": 1}


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.name)
def test_script_parses(script):
    p = subprocess.run(["bash", "-n", str(script)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr


@pytest.mark.parametrize("script", [s for s in SCRIPTS if s.suffix == ".sbatch"], ids=lambda p: p.name)
def test_batch_script_requests_the_checkpoint_signal_and_uses_srun(script):
    text = script.read_text()
    assert "#SBATCH --signal=USR1@300" in text
    assert '"${SRUN[@]}"' in text and "source " in text and "slurm/env.sh" in text
    env = (SLURM / "env.sh").read_text()
    assert "export NUMBA_CACHE_DIR" in env and "SRUN=(srun" in env


class Cluster:
    """A submit directory, an output directory and the stand-ins, for one test."""

    def __init__(self, tmp: Path, numba_cache: Path):
        require("gather")
        self.dir = tmp / "submit"
        self.out = tmp / "out"
        self.dir.mkdir()
        self.scene = self.dir / "tiny.toml"
        self.scene.write_text(small_toml(**TINY))
        self.numba_cache = numba_cache
        self.env = cli_env(PATH=f"{STANDIN}{os.pathsep}{os.environ['PATH']}", SRUN_STANDIN_MPIEXEC=WHEEL_MPIEXEC,
                           SLURM_STANDIN_STATE=str(tmp / "state"), PARSLIP_ROOT=str(REPO),
                           PARSLIP_OUTDIR=str(self.out), NUMBA_CACHE_DIR=str(numba_cache))

    def run(self, *cmd, **env):
        p = subprocess.run(list(map(str, cmd)), cwd=self.dir, env={**self.env, **env}, capture_output=True, text=True,
                           timeout=600)
        assert p.returncode == 0, p.stdout + p.stderr
        return p

    def log(self, name):
        return (self.dir / name).read_text()

    def sbatch(self, *args, **env):
        """Submit through the stand-in; returns the job id."""
        return int(self.run("sbatch", "--parsable", *args, **env).stdout.split()[-1])


@pytest.fixture(scope="module")
def batch_numba_cache():
    """The batch jobs' NUMBA_CACHE_DIR, shared as a cluster's would be: the session's kernel cache
    (tests/conftest.py), so the jobs load the loop the suite has compiled; were it cold, the first job's
    warm-up would compile it (about 40 s) and every later job load it."""
    return Path(os.environ["NUMBA_CACHE_DIR"])


@pytest.fixture
def cluster(tmp_path, batch_numba_cache):
    return Cluster(tmp_path, batch_numba_cache)


def _status(path):
    with h5py.File(path, "r") as f:
        return read_status(f), int(f.attrs["n_ranks"])


def _v0(path):
    with h5py.File(path, "r") as f:
        return tomllib.loads(f.attrs["scene"])["drive"]["v0"]


def _kernel_indexes(folder: Path) -> set:
    return set(folder.rglob("*.nbi")) if folder.is_dir() else set()


def test_single_run(cluster, tmp_path):
    """The job's kernels come from NUMBA_CACHE_DIR: none is compiled where parslip would keep them
    without it (PARSLIP_CACHE_DIR, empty here) or where env.sh's default would (the checkout's)."""
    fallback, beside = tmp_path / "parslip-cache", REPO / ".numba-cache"
    before = _kernel_indexes(beside)
    job = cluster.sbatch("--ntasks=2", SLURM / "parslip.sbatch", cluster.scene, "", "--set", "drive.v0=0.03",
                         PARSLIP_CACHE_DIR=str(fallback))
    log = cluster.log(f"parslip-{job}.log")
    out = cluster.out / f"tiny-{job}.vtkhdf"
    assert _status(out) == ("complete", 2), log
    assert "ranks            1 to" in log          # parslip info ran first
    assert any(cluster.numba_cache.rglob("*.nbi")), "numba cache not in NUMBA_CACHE_DIR"
    assert not _kernel_indexes(fallback) and _kernel_indexes(beside) == before, "kernels compiled elsewhere"
    assert _v0(out) == 0.03


def test_v0_sweep_as_a_job_array(cluster):
    job = cluster.sbatch("--array=0-1", "--ntasks=2", SLURM / "sweep-v0.sbatch", cluster.scene,
                         V0_LIST="0.01 0.03")
    for i, v0 in enumerate(("0.01", "0.03")):
        log = cluster.log(f"parslip-sweep-{job}_{i}.log")
        out = cluster.out / f"tiny-v0_{v0}.vtkhdf"
        assert _status(out) == ("complete", 2), log
        assert _v0(out) == float(v0)
    # An index past the list is refused, naming the list.
    bad = cluster.sbatch("--array=2", SLURM / "sweep-v0.sbatch", cluster.scene, V0_LIST="0.01 0.03")
    assert "array index 2 is past V0_LIST (2 values" in cluster.log(f"parslip-sweep-{bad}_2.log")


def test_scaling_study_writes_its_table(cluster):
    job = cluster.sbatch("--ntasks=2", SLURM / "scaling.sbatch", cluster.scene, RANKS="1 2 4")
    log = cluster.log(f"parslip-scaling-{job}.log")
    table = (cluster.out / f"scaling-{job}.tsv").read_text().splitlines()
    assert table[0].split("\t") == ["study", "ranks", "lattice_nodes", "nodes_per_rank", "steps", "loop_wall_s",
                                    "node_updates_per_s"], log
    rows = [r.split("\t") for r in table[1:]]
    assert [(r[0], r[1]) for r in rows] == [("strong", "1"), ("strong", "2"), ("weak", "1"), ("weak", "2")], log
    assert "4 ranks: skipped, the job has 2 tasks" in log
    strong, weak = rows[:2], rows[2:]
    assert strong[0][2] == strong[1][2] == "256" and strong[1][3] == "128"     # same lattice, split
    assert weak[1][2] == "512" and weak[0][3] == weak[1][3] == "256"          # twice the lattice, same share
    assert weak[0][4] == weak[1][4]                                          # and the same number of steps
    for r in rows:
        assert float(r[5]) >= 0 and float(r[6]) > 0
    assert not list((cluster.out / f"scaling-{job}").glob("*.vtkhdf"))     # outputs removed after their row


def test_restart_chain_continues_to_the_end(cluster, tmp_path):
    """Links stop after 3 s each; the chain ends with the same datasets as one uninterrupted run, and the
    links left over find the run complete and start no ranks.

    937,000 steps: 6 to 19 s of stepping on 2 ranks (150,000 to 50,000 steps/s, idle to loaded host).
    A link steps up to 400,000 of them on an idle host, so the first cannot finish, and 100,000 to
    200,000 on a loaded one (none when its ranks take the 3 s to start).  With the suite's two workers
    beside it 12 links once ended 120,000 steps short, so 24 are submitted; a surplus link costs a second."""
    out = cluster.out / "chain.vtkhdf"
    cluster.out.mkdir(exist_ok=True)
    long = {"drive.duration": 3000.0, "drive.v0": 0.001}
    scene = cluster.dir / "long.toml"
    scene.write_text(small_toml(**long))
    ids = cluster.run("bash", SLURM / "submit-chain.sh", scene, out, "24", PARSLIP_STOP_AFTER="00:00:03",
                      PARSLIP_SBATCH_ARGS="--ntasks=2").stdout.split()
    assert len(ids) == 24
    logs = [cluster.log(f"parslip-chain-{j}.log") for j in ids]
    assert "checkpointed at step" in logs[0], logs[0]
    assert _status(out)[0] == "complete", logs[-1]
    assert "the run is complete; nothing left to do" in logs[-1] and "INFO" not in logs[-1], logs[-1]
    ref = tmp_path / "ref.vtkhdf"
    p = subprocess.run([WHEEL_MPIEXEC, "-n", "2", sys.executable, "-m", "parslip", "run", str(scene), "--out", str(ref),
                        "--no-png", "--quiet"], env=cluster.env, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    got, want = datasets(out)[0], datasets(ref)[0]
    assert got.keys() == want.keys()
    for name in want:
        assert got[name].tobytes() == want[name].tobytes(), name


def test_sweep_as_a_job_array_of_shards(cluster):
    """Two array tasks of 2 ranks each (one point per rank) share a 5-point sweep by shards: every point
    runs once, in its own file, and the last task's summary holds all five; resubmitted, nothing reruns.
    The kernels come from the module's shared NUMBA_CACHE_DIR."""
    (cluster.dir / "sweep.toml").write_text('base = "tiny.toml"\n[set]\n"drive.duration" = 2.0\n'
                                            '[grid]\n"load.FN" = [0.5, 1.0, 1.5, 2.0, 2.5]\n')
    job = cluster.sbatch("--array=0-1", "--ntasks=2", SLURM / "sweep.sbatch", "sweep.toml")
    out = cluster.out / "sweep"
    ran = []
    for i in (0, 1):
        log = cluster.log(f"parslip-sweep-{job}_{i}.log")
        assert f"array task {i}: shard {i}/2 of sweep.toml" in log, log
        assert "to run on 2 rank(s) in 2 group(s) of 1" in log, log
        ran.append({ln.split(": ")[2].split()[0] for ln in log.splitlines() if "sweep group" in ln})
    assert not ran[0] & ran[1] and ran[0] | ran[1] == {f"p{k:03d}" for k in range(5)}, ran
    rows = (out / "summary.csv").read_text().splitlines()
    assert len(rows) == 6 and all(",ok," in r for r in rows[1:]), rows
    for k in range(5):
        assert _status(out / "points" / f"p{k:03d}.vtkhdf") == ("complete", 1)
    again = cluster.sbatch("--array=0-1", "--ntasks=2", SLURM / "sweep.sbatch", "sweep.toml")
    assert "this job ran 0:" in cluster.log(f"parslip-sweep-{again}_1.log")
    # A bad sweep file stops the task before any rank starts, with its one line.
    (cluster.dir / "bad.toml").write_text('base = "tiny.toml"\n[grid]\n"load.fn" = [1.0]\n')
    bad = cluster.sbatch(SLURM / "sweep.sbatch", "bad.toml")
    assert "unknown scene key (did you mean load.FN?)" in cluster.log(f"parslip-sweep-{bad}_None.log")
