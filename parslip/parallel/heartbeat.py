"""Heartbeats between ranks, for the watchdog: who still answers, and where each rank is.

Used by the monitor thread (``engine.monitor``) beside the compiled loop, so
it needs MPI_THREAD_MULTIPLE (``available``).  It talks on a duplicate of the
run's communicator, so it never matches the run's own messages, and point to
point only, never blocking: every rank sends its beat to rank 0, rank 0 sends
its own to every rank, and a send to a rank that stopped answering is left
pending (at most ``MAX_PENDING`` per peer) instead of waited for.

A beat is the int64 array BEAT_FIELDS: the sender's rank, its step, its phase
(an index into ``engine.monitor.PHASES``), how many agreements it has taken
part in, and whether it is inside the compiled loop.  Rank 0 can also ask
every rank to report (REPORT): each writes its own state to its log before
the job is aborted.
"""
from __future__ import annotations

import time

import numpy as np

BEAT_FIELDS = ("rank", "step", "phase", "agreements", "in_loop")
BEAT, REPORT = 71, 72            # message tags on the heartbeat communicator
MAX_PENDING = 4                  # unanswered sends kept per peer before that peer is skipped


def available(comm) -> bool:
    """Heartbeats need MPI_THREAD_MULTIPLE: the monitor thread calls MPI while the loop does."""
    from mpi4py import MPI
    return comm is not None and comm.Get_size() > 1 and MPI.Query_thread() == MPI.THREAD_MULTIPLE


_DUPS: dict = {}


def for_comm(comm) -> "Heartbeat":
    """The heartbeat of ``comm``, made on first use (collective then: Comm_dup) and kept for later runs on
    the same communicator (a sweep runs many), so no run ends with a collective Comm_free."""
    key = comm.py2f()
    hb = _DUPS.get(key)
    if hb is None:
        hb = _DUPS[key] = Heartbeat(comm)
    hb.reset()
    return hb


class Heartbeat:
    """Beats on a duplicate communicator; ``__init__`` is collective (Comm_dup)."""

    def __init__(self, comm):
        self.comm = comm.Dup()
        self.rank, self.size = self.comm.Get_rank(), self.comm.Get_size()
        self.peers = range(1, self.size) if self.rank == 0 else (0,)
        self._pending = {p: [] for p in self.peers}
        self._buf = np.zeros(len(BEAT_FIELDS), np.int64)
        self.reset()

    def reset(self):
        """A new run: every peer counts as heard now."""
        now = time.monotonic()
        # rank -> (time last heard, its last beat as a dict); rank 0 hears every rank, the others rank 0.
        self.heard = {p: (now, None) for p in self.peers}

    def send(self, beat: dict, tag: int = BEAT):
        """Send ``beat`` to rank 0 (or, from rank 0, to every rank) without waiting."""
        msg = np.array([beat[k] for k in BEAT_FIELDS], np.int64)
        for p in self.peers:
            reqs = [r for r in self._pending[p] if not r.Test()]
            if len(reqs) < MAX_PENDING:
                reqs.append(self.comm.Isend(msg.copy(), dest=p, tag=tag))
            self._pending[p] = reqs

    def poll(self) -> list:
        """Messages that arrived: [(source, tag, beat dict)]; each beat refreshes ``heard``."""
        from mpi4py import MPI
        got = []
        st = MPI.Status()
        while self.comm.Iprobe(source=MPI.ANY_SOURCE, tag=MPI.ANY_TAG, status=st):
            src, tag = st.Get_source(), st.Get_tag()
            buf = np.zeros(len(BEAT_FIELDS), np.int64)
            self.comm.Recv(buf, source=src, tag=tag)
            beat = dict(zip(BEAT_FIELDS, (int(v) for v in buf)))
            self.heard[src] = (time.monotonic(), beat)
            got.append((src, tag, beat))
        return got

    def silent(self, longer_than: float) -> list[int]:
        """Ranks not heard from for longer than ``longer_than`` seconds."""
        now = time.monotonic()
        return sorted(p for p, (t, _) in self.heard.items() if now - t > longer_than)
