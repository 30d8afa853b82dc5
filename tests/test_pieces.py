"""Records placed in their global order without a gather, and pieces streamed to rank 0 one rank at a time
(``parallel.pieces``), on 3 real MPI ranks: against the order a gather and a sort would give."""
import numpy as np
import pytest

from parslip.parallel import pieces


def _records(rank: int, seed: int, spread: int):
    """Sorted steps of one rank's records: clusters (several records in one step, steps shared with other
    ranks) over ``spread`` steps, with gaps wider than a histogram window, and an empty rank."""
    rng = np.random.default_rng(seed + rank)
    if rank == 1 and seed % 2:
        return np.zeros(0, np.int64)
    steps = np.concatenate([rng.integers(-50, 50, 30), rng.integers(0, spread, 40), [spread + 5] * rank])
    return np.sort(steps).astype(np.int64)


@pytest.mark.parallel(nprocs=3)
@pytest.mark.parametrize("window,spread", [(pieces.WINDOW, 300_000), (8, 1000)])
def test_records_go_where_a_gather_and_sort_would_put_them(monkeypatch, window, spread):
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    monkeypatch.setattr(pieces, "WINDOW", window)
    rank = comm.Get_rank()
    for seed in range(4):
        steps = _records(rank, seed, spread)
        where, total = pieces.place_by_step(comm, steps)
        # The reference: every rank's records gathered and sorted by (step, rank, own order).
        every = comm.allgather(steps)
        assert total == sum(len(s) for s in every)
        keys = [(s, r, i) for r, ss in enumerate(every) for i, s in enumerate(ss)]
        order = sorted(range(len(keys)), key=lambda j: keys[j])
        place = {keys[j][1:]: p for p, j in enumerate(order)}
        assert list(where) == [place[(rank, i)] for i in range(len(steps))]


@pytest.mark.parallel(nprocs=3)
def test_no_records_anywhere():
    from mpi4py import MPI
    where, total = pieces.place_by_step(MPI.COMM_WORLD, np.zeros(0, np.int64))
    assert total == 0 and len(where) == 0


@pytest.mark.parallel(nprocs=3)
def test_rank_0_takes_every_rank_s_pieces_in_rank_order_in_small_messages():
    from mpi4py import MPI

    class Spy:
        """The communicator, keeping what this rank sends."""
        def __init__(self, comm):
            self.comm, self.sent = comm, []

        def __getattr__(self, name):
            return getattr(self.comm, name)

        def send(self, obj, dest, tag):
            self.sent.append(obj)
            self.comm.send(obj, dest=dest, tag=tag)

    comm = Spy(MPI.COMM_WORLD)
    rank = comm.Get_rank()
    items = [(rank, i, np.full(100, rank)) for i in range(5)]            # 800 bytes each
    taken = []
    pieces.stream_to_root(comm, items, taken.append, lambda item: item[2].nbytes, cap=2000)
    sent = comm.sent
    if rank == 0:
        assert [t[:2] for t in taken] == [(r, i) for r in range(3) for i in range(5)]
        assert all((t[2] == t[0]).all() for t in taken)
    else:
        assert taken == []
        # Two items (1600 bytes) per message under a cap of 2000: three messages, the last saying "no more".
        assert [[item[1] for item in batch] for batch, _ in sent] == [[0, 1], [2, 3], [4]]
        assert [more for _, more in sent] == [True, True, False]


def test_one_rank_needs_no_mpi():
    where, total = pieces.place_by_step(None, np.array([3, 3, 5]))
    assert list(where) == [0, 1, 2] and total == 3
    taken = []
    pieces.stream_to_root(None, ["a", "b"], taken.append, len, 1)
    assert taken == ["a", "b"]
