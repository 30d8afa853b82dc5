"""Records placed in one global order without a gather, and pieces streamed to one rank one rank at a time.

Both serve the writer (``io.output``), so that no rank holds what every rank holds:

- ``place_by_step``: each rank holds records sorted by step; the global order is by step, then by rank,
  then by the rank's own order (the bond events: sites are dealt to the ranks in increasing order, so
  (step, rank, local order) is (step, site, kind)).  Each rank learns where its records go from
  histograms over steps, an exclusive scan over the ranks and an allreduce, in windows of at most
  WINDOW steps: memory and messages of O(WINDOW) per rank, none of them growing with the rank count.
- ``stream_to_root``: rank 0 takes its own pieces, then asks each other rank in turn for its pieces, a
  message of at most a fixed number of bytes at a time, and takes them before asking again, so it never
  holds more than its own pieces and one message (a rank that sent unasked could pile messages up at
  rank 0: MPI buffers small ones on arrival).
"""
from __future__ import annotations

import numpy as np

WINDOW = 1 << 16                # steps per histogram (int64 each): 512 KiB
TAG = 7301                      # point-to-point tag of the stream, apart from every other message


def place_by_step(comm, steps: np.ndarray) -> tuple[np.ndarray, int]:
    """(index of each of this rank's records in the global order, records over all ranks), for records
    sorted by ``steps`` (int64, ascending) on every rank.  Collective; ``comm`` None: one rank."""
    steps = np.asarray(steps, np.int64)
    if comm is None or comm.Get_size() == 1:
        return np.arange(len(steps), dtype=np.int64), len(steps)
    from mpi4py import MPI
    big = np.iinfo(np.int64).max
    span = np.array([-steps[0], steps[-1]] if len(steps) else [-big, -big], np.int64)
    comm.Allreduce(MPI.IN_PLACE, span, op=MPI.MAX)
    first, last = -int(span[0]), int(span[1])
    if last < first:                                   # no records on any rank
        return np.zeros(0, np.int64), 0
    width = min(WINDOW, last - first + 1)
    n_win = (last - first) // width + 1
    # Which windows hold a record on some rank: one byte each.
    used = np.zeros(n_win, np.uint8)
    used[(steps - first) // width] = 1
    comm.Allreduce(MPI.IN_PLACE, used, op=MPI.BOR)
    # Within a step, a record's place among this rank's records of that step.
    within = np.arange(len(steps), dtype=np.int64) - np.searchsorted(steps, steps, side="left")
    pos = np.zeros(len(steps), np.int64)
    base = 0
    below, total = np.zeros(width, np.int64), np.zeros(width, np.int64)
    for w in np.flatnonzero(used):
        a = first + int(w) * width
        i0, i1 = np.searchsorted(steps, [a, a + width])
        hist = np.bincount(steps[i0:i1] - a, minlength=width).astype(np.int64)
        comm.Exscan(hist, below, op=MPI.SUM)           # records of the lower ranks, step by step
        if comm.Get_rank() == 0:
            below[:] = 0                               # (Exscan leaves rank 0's undefined)
        comm.Allreduce(hist, total, op=MPI.SUM)        # records of every rank, step by step
        start = base + np.cumsum(total) - total        # where each step's records begin
        s = steps[i0:i1] - a
        pos[i0:i1] = start[s] + below[s] + within[i0:i1]
        base += int(total.sum())
    return pos, base


def stream_to_root(comm, items: list, take, weight, cap: int) -> None:
    """``take(item)`` on rank 0 for each of its own ``items``, then for every other rank's, in rank order,
    each rank's sent in messages of at most ``cap`` bytes (``weight(item)``: an item's bytes; an item
    heavier than ``cap`` travels alone), each message only when rank 0 asks for it: rank 0 holds its own
    items and one message.  Collective; ``comm`` None: ``take`` here."""
    if comm is None or comm.Get_size() == 1 or comm.Get_rank() == 0:
        for item in items:
            take(item)
    if comm is None or comm.Get_size() == 1:
        return
    if comm.Get_rank() == 0:
        for r in range(1, comm.Get_size()):
            more = True
            while more:
                comm.send(None, dest=r, tag=TAG)       # your turn
                batch, more = comm.recv(source=r, tag=TAG)
                for item in batch:
                    take(item)
                del batch
        return
    batches, batch, load = [], [], 0
    for item in items:
        if batch and load + weight(item) > cap:
            batches.append(batch)
            batch, load = [], 0
        batch.append(item)
        load += weight(item)
    batches.append(batch)
    for i, batch in enumerate(batches):
        comm.recv(source=0, tag=TAG)
        comm.send((batch, i + 1 < len(batches)), dest=0, tag=TAG)
