"""One compile per job: one rank per kernel cache compiles the time loop, the other ranks load it from numba's cache.

A job on an empty cache must compile the loop once, on rank 0, and give the bits of a run that compiled it on
its own; a compile that fails on one rank must end every rank with the same error (exit 3), none left waiting;
and the ranks that wait must sleep, not poll MPI in a busy loop.  The first test costs one cold compile of the
loop for three ranks (about a minute of a core); it builds it for haswell (AVX2 + FMA), so that the same compile
also shows that build giving the default build's bits (``tests/test_portable.py``, docs/hpc/cluster.md).
"""
import re
import time
from pathlib import Path

import pytest

from helpers import datasets, run_cli, small_toml

LINE = re.compile(r"compiled the time loop in \d+ s \(\d+ s of CPU summed over the ranks; (\d+) functions\): "
                  r"on (\d+) of (\d+) ranks, the others loaded it from numba's cache")
# Rank 0 compiles the loop, rank 1 meanwhile the kernels it does not call: two of three ranks compile.


def _record(out) -> dict:
    got, _ = datasets(out)
    return {k: v for k, v in got.items() if k.startswith(("interface/", "energy/"))}


def test_one_rank_compiles_the_loop_and_the_others_load_it(tmp_path):
    """Three ranks on an empty kernel cache: one rank compiles (numba's own compile events, counted on every
    rank and logged), and no function more than once (the functions compiled, summed over the ranks, are no
    more than the entries the cache holds, each written once however many ranks compile it); a second job on
    that cache compiles nothing; both write the record of a run on one rank (the session's cache), bit for bit.

    The job's loop is built for haswell (NUMBA_CPU_NAME, AVX2 + FMA) and the one-rank run's for this host's
    CPU (on an AVX-512 host, another instruction set): the bits they share are also the promise that a
    cluster's nodes of either kind give the same run."""
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**{"drive.duration": 5.0, "output.snapshots": 1}))
    cache = tmp_path / "numba"
    env = {"NUMBA_CACHE_DIR": str(cache), "NUMBA_CPU_NAME": "haswell"}
    outs = [tmp_path / "cold.vtkhdf", tmp_path / "warm.vtkhdf"]
    p = run_cli(3, "run", sc, "--out", outs[0], "--no-png", "--quiet", env=env, timeout=1200)
    assert p.returncode == 0, p.stderr
    said = [LINE.search(line) for line in p.stderr.splitlines() if "compiled the time loop" in line]
    assert len(said) == 1 and said[0] is not None, p.stderr
    functions, on, ranks = (int(g) for g in said[0].groups())
    assert (on, ranks) == (2, 3), p.stderr
    entries = list(cache.rglob("*.nbc"))
    assert 10 < functions <= len(entries), (functions, sorted(e.name for e in entries))
    assert not list(cache.rglob(".first-call-*"))        # rank 0's mark of its folder is gone
    p = run_cli(3, "run", sc, "--out", outs[1], "--no-png", "--quiet", env=env, timeout=300)
    assert p.returncode == 0, p.stderr
    assert "compiled the time loop" not in p.stderr, p.stderr     # every rank found it where rank 0 stored it
    p = run_cli(1, "run", sc, "--out", tmp_path / "one.vtkhdf", "--no-png", "--quiet", timeout=900)
    assert p.returncode == 0, p.stderr
    cold, warm, one = _record(outs[0]), _record(outs[1]), _record(tmp_path / "one.vtkhdf")
    assert "interface/drive_force" in cold and "energy/work_drive" in cold
    assert len(cold["interface/time"]) > 100
    assert cold.keys() == warm.keys() == one.keys()
    for name in cold:
        assert cold[name].tobytes() == warm[name].tobytes() == one[name].tobytes(), name


@pytest.mark.parametrize("failing", [0, 1])
def test_a_compile_that_fails_on_one_rank_ends_every_rank_alike(tmp_path, failing):
    """The test hook compile_error=RANK makes that rank's first call of the loop raise: rank 0's before any other
    rank makes its own (the compiling rank), rank 1's after rank 0's has returned (a loading rank).  Every rank ends
    with exit code 3 and the one message (no rank waits for the others forever: a hang fails under the limit)."""
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**{"drive.duration": 1.0, "output.snapshots": 0}))
    p = run_cli(2, "run", sc, "--out", tmp_path / "o.vtkhdf", "--no-png", "--quiet",
                env={"PARSLIP_TEST_HOOKS": f"compile_error={failing}"}, timeout=900)
    assert p.returncode == 3, p.stderr
    assert (f"parslip: run failed: rank {failing} failed: RuntimeError: injected failure of the compile on rank "
            f"{failing}") in p.stderr, p.stderr
    assert "MPI_Abort" not in p.stderr


@pytest.mark.parallel(nprocs=2)
def test_the_ranks_that_wait_sleep():
    """Rank 0 works for 2 s of wall time (a sleep, standing for a compile) while rank 1 waits in ``outcome``: rank
    1's CPU time meanwhile is a small part of the wait (MPICH's blocking MPI_Barrier would poll for all of it);
    then rank 0's error reaches rank 1 as the same RunError."""
    from mpi4py import MPI

    from parslip.errors import RunError
    from parslip.parallel.collective import Attempt, outcome
    comm = MPI.COMM_WORLD
    t0, c0 = time.monotonic(), time.process_time()
    mine = Attempt(lambda: time.sleep(2.0)) if comm.rank == 0 else None
    outcome(comm, mine)
    wall, cpu = time.monotonic() - t0, time.process_time() - c0
    if comm.rank == 1:
        assert wall > 1.9 and cpu < 0.2 * wall, (wall, cpu)
    mine = Attempt(lambda: 1 / 0) if comm.rank == 0 else None
    with pytest.raises(RunError, match="rank 0 failed: ZeroDivisionError"):
        outcome(comm, mine)


def test_an_unwritable_cache_folder_leaves_every_rank_to_compile_alone(tmp_path):
    """Nothing to mark: ``_mark`` returns None (and every rank compiles for itself, as numba cannot share)."""
    from parslip.engine.compile import _mark
    (tmp_path / "file").write_text("")
    assert _mark(str(tmp_path / "file" / "below")) is None
    made = _mark(str(tmp_path / "new"))
    assert made is not None and Path(made).parent == tmp_path / "new"
