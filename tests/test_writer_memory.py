"""Rank 0 of the gathering writer holds its own share and one message, not every rank's share.

tests/writer_memory.py runs the writer on one lattice (10,000 nodes) on 2 and 6 ranks and measures,
with tracemalloc, what rank 0 allocates while it writes a snapshot, a block of interface frames and a
flush of bond events.  With the fields gathered onto rank 0 (the writer before the streamed pieces), a
snapshot took 0.61 MB on 2 ranks and 0.53 MB on 6, the events 0.77 MB on both: the whole lattice's every
time.  Streamed one rank at a time, in messages of at most ``io.output.STREAM_BYTES``, rank 0's share
shrinks with the rank count and so does what it holds.
"""
import json
import os
import sys
from pathlib import Path

import pytest

from helpers import WHEEL_MPIEXEC, cli_env, require, run_limited
from parslip.io.output import STREAM_BYTES

PROBE = Path(__file__).with_name("writer_memory.py")


def _probe(n: int, out) -> dict:
    env = cli_env()
    env["PYTHONPATH"] = os.pathsep.join([str(PROBE.parent), env["PYTHONPATH"]])
    p = run_limited([WHEEL_MPIEXEC, "-n", str(n), sys.executable, str(PROBE), str(out)], env=env, timeout=600)
    assert p.returncode == 0, p.stderr[-3000:]
    return json.loads(p.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    require("gather")
    d = tmp_path_factory.mktemp("writer_memory")
    return {n: _probe(n, d / f"m{n}.vtkhdf") for n in (2, 6)}


@pytest.mark.parametrize("call,share", [("snapshot", "own_snapshot_bytes"), ("events", "own_event_bytes")])
def test_rank_0_holds_about_its_own_share_of_a_snapshot_and_of_the_events(measured, call, share):
    two, six = measured[2], measured[6]
    assert two["nodes"] == six["nodes"]
    # Three times fewer nodes and sites on rank 0, and not much more than three times less held.
    assert six[call] < 0.6 * two[call], (two, six)
    # Its own share as written (sorted, with times and places: up to three times what it was handed), one
    # other rank's in one message (pickled, then unpickled: twice that rank's share), and little else.
    for m in (two, six):
        assert m[call] < 6 * m[share] + 100_000, m


def test_rank_0_holds_a_block_of_frames_one_message_at_a_time(measured):
    for m in measured.values():
        assert m["frames"] < 3 * STREAM_BYTES, m
