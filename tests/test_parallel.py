"""Parallel runs against serial runs, compared by global node id.

The in-process tests run under mpi-pytest on 2 ranks; the rank-count tests
launch the real command line on 1, 2, 3 (and 8, with slabs narrower than the
slip) ranks, oversubscribed on a 2-core machine, through both writers, and
compare the output files bit for bit: rank against rank, and HDF5's
collective mpio driver (the venv that tests/install.sh builds, under
Debian's mpiexec.mpich) against rank 0 gathering (PyPI's serial h5py, under
the mpich wheel's mpiexec).
"""
import re

import h5py
import numpy as np
import pytest

from helpers import SMALL, WRITERS, datasets, require, run_cli, scene, small_toml
from parslip.engine.simulation import Simulation
from parslip.io.contract import read_status
from parslip.model.lattice import Lattice
from parslip.parallel.exchange import build_plan, release
from parslip.parallel.halo_mpi import mpi_complete, mpi_post
from parslip.parallel.layout import PAD, build_layout, column_cost, interface_reach, partition
from parslip.scene.derive import derive



def _gids(lat, lay, b):
    """Global id of every array cell of block b on this rank (-1 for ghost cells)."""
    B = lay.blocks[b]
    rows, cols = np.meshgrid(np.arange(B.shape[0]) - PAD, np.arange(B.width) + B.base, indexing="ij")
    return lat.gid(np.full(rows.shape, b), rows, cols)


@pytest.mark.parallel(nprocs=2)
@pytest.mark.parametrize("shared", (True, False))
def test_halo_exchange_by_global_id(shared):
    """A 4-row free strip of 10 columns cut at column 5 (bulk rows only: a halo of one column).

        column      0 1 2 3 4 | 5 6 7 8 9
        rank 0      O O O O O | H              O owned, H halo copy
        rank 1              H | O O O O O

    After the exchange every halo copy holds its owner's value (here 1000 + gid, then 2000 + gid, 3000 + gid
    in the steps after: the shared windows' two parities and the first one again) and no other cell changed;
    through the shared window and by MPI messages alike.
    """
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    lat = Lattice(4, 10, 0, 0)
    lay = build_layout(lat, comm.rank, comm.size, interface_reach(0.5, 0.7, 0.0))
    assert lay.col_range == ((0, 5) if comm.rank == 0 else (5, 10))
    plan = build_plan(lay, np.float64, comm, shared)
    assert list(plan.shared) == [int(shared)]
    gid = _gids(lat, lay, 1)
    B = lay.blocks[1]
    cols = np.arange(B.width) + B.base
    lo, hi = lay.col_range
    owned = (gid >= 0) & (cols[None, :] >= lo) & (cols[None, :] < hi)
    halo_col = 5 if comm.rank == 0 else 4
    halo = (gid >= 0) & (cols[None, :] == halo_col)
    assert halo.sum() == 4
    e = np.zeros((0, 0))
    bonds = np.zeros((2, B.width))
    tx = np.where(owned, 0.0, -1.0)
    for step in (1, 2, 3):
        tx[owned] = 1000.0 * step + gid[owned]
        ty = -tx
        assert mpi_post(plan, e, e, tx, ty, bonds) == 0
        assert mpi_complete(plan, e, e, tx, ty, bonds) == 0
        np.testing.assert_array_equal(tx[halo], 1000.0 * step + gid[halo])
        np.testing.assert_array_equal(ty[halo], -1000.0 * step - gid[halo])
        np.testing.assert_array_equal(tx[~halo & ~owned], -1.0)            # ghost and unneeded cells untouched
    release(plan)


@pytest.mark.parallel(nprocs=2)
def test_parallel_state_matches_serial_by_global_id():
    """Two ranks and one rank agree to the bit on every node, after bonds broke and re-formed."""
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    sc = scene(**SMALL)
    st = derive(sc)
    par = Simulation(st, comm)
    ser = Simulation(derive(sc, (st.omega_max, st.omega_method)))
    n = st.n_drive_start + int(0.8 * st.n_drive)
    par.run(until=n)
    ser.run(until=n)
    total = comm.allreduce(int(par.counters[0]))
    assert total > 5 and total == ser.counters[0]
    pos = np.searchsorted(ser.state.gid, par.state.gid)
    np.testing.assert_array_equal(par.u, ser.u[pos])
    np.testing.assert_array_equal(par.u_prev, ser.u_prev[pos])
    s = par.state.site0()
    np.testing.assert_array_equal(par.state.owned_partner(), ser.state.owned_partner()[s:s + len(par.state.owned_partner())])


# SMALL with a short settle and a faster drive: bonds still break and re-form
# across slab boundaries.  Short because Debian's MPICH (the mpio venv's) spins
# while it waits: on 3 ranks over 2 cores each halo exchange then costs a
# scheduler time slice, about 4 ms against 0.04 ms for the wheel.
QUICK = {"load.ramp": 0.2, "load.settle": 0.5, "drive.v0": 0.05, "drive.duration": 2.0}


class SmallRuns:
    """SMALL + QUICK on n ranks through each writer, each run once per module and only when asked."""

    def __init__(self, tmp):
        self.tmp = tmp
        self.scene = tmp / "small.toml"
        self.scene.write_text(small_toml(**QUICK))
        self.files = {}

    def get(self, writer, n):
        """(datasets, root attributes, stderr) of the run on n ranks with that writer."""
        if (writer, n) not in self.files:
            out = self.tmp / f"{writer}{n}.vtkhdf"
            p = run_cli(n, "run", self.scene, "--out", out, "--no-png", "--quiet", writer=writer)
            assert p.returncode == 0, p.stderr
            self.files[writer, n] = (*datasets(out), p.stderr)
        return self.files[writer, n]


@pytest.fixture(scope="module")
def small_runs(tmp_path_factory):
    return SmallRuns(tmp_path_factory.mktemp("small_runs"))


def assert_same_datasets(got, ref, what):
    assert got.keys() == ref.keys(), what
    for name in ref:
        assert got[name].dtype == ref[name].dtype and got[name].shape == ref[name].shape, (what, name)
        assert got[name].tobytes() == ref[name].tobytes(), (what, name)


@pytest.mark.parametrize("writer", WRITERS)
def test_output_bitwise_identical_with_ranks_that_hold_no_interface(tmp_path, writer):
    """The substrate overhangs the block 12:1 on each side, so on 3 ranks the outer
    slabs hold no interface site of the block, not even as a halo copy: they must
    still take part in every exchange and every write."""
    require(writer)
    over = {"lattice.top_cols": 12, "lattice.bottom_cols": 300, "drive.v0": 0.02, "drive.duration": 4.0,
            "load.ramp": 0.2, "load.settle": 0.5}
    sc = tmp_path / "overhang.toml"
    sc.write_text(small_toml(**over))
    st = derive(scene(**{**SMALL, **over}))
    for rank in (0, 2):
        top = build_layout(st.lattice, rank, 3, st.reach).blocks[1]
        assert (top.stored[:, 1] <= top.stored[:, 0]).all()
    files = {}
    for n in (1, 3):
        out = tmp_path / f"o{n}.vtkhdf"
        p = run_cli(n, "run", sc, "--out", out, "--no-png", "--quiet", writer=writer)
        assert p.returncode == 0, p.stderr
        files[n] = datasets(out)[0]
    assert (files[1]["interface/intact"] == 0).any()
    assert_same_datasets(files[3], files[1], f"{writer} on 3 ranks")


@pytest.mark.parametrize("writer", WRITERS)
def test_output_bitwise_identical_on_1_2_3_ranks(small_runs, writer):
    require(writer)
    ref, ref_attrs, _ = small_runs.get(writer, 1)
    assert ref_attrs["status"] == "complete"
    for n in (1, 2, 3):
        data, attrs, log = small_runs.get(writer, n)
        mode = writer if n > 1 else "gather"          # one rank loads no MPI, so no collective HDF5 either
        assert attrs["n_ranks"] == n and attrs["hdf5_mode"] == mode
        assert f"writer: {mode} (" in log
        assert_same_datasets(data, ref, f"{writer} on {n} ranks")

    # The test must exercise the hard case: a bond that broke and re-formed
    # with its top node and its new bottom partner on different ranks.
    st = derive(scene(**{**SMALL, **QUICK}))
    intact, partner = ref["interface/intact"], ref["interface/partner"]
    crossed = {}
    for n in (2, 3):
        bounds = partition(column_cost(st.lattice), n)
        owner = lambda col: np.searchsorted(bounds, col, side="right") - 1   # noqa: E731
        top_owner = owner(st.lattice.top.col0 + np.arange(st.lattice.top.cols))
        was_broken = np.maximum.accumulate(intact == 0, axis=0)
        rebonded = (intact == 1) & was_broken
        across = rebonded & (owner(np.maximum(partner, 0)) != top_owner[None, :])
        crossed[n] = int(across.sum())
    assert crossed[2] > 0 and crossed[3] > 0, crossed


@pytest.mark.parametrize("n", (2, 3))
def test_collective_mpio_and_gathered_files_are_identical(small_runs, n):
    """Every rank writing its slices through HDF5's mpio driver gives, byte for byte, the
    datasets rank 0 writes after gathering; only hdf5_mode (and the run's own command line
    and clock) tell the files apart."""
    require("gather")
    require("mpio")
    (mpio, mpio_attrs, _), (gather, gather_attrs, _) = small_runs.get("mpio", n), small_runs.get("gather", n)
    assert (mpio_attrs["hdf5_mode"], gather_attrs["hdf5_mode"]) == ("mpio", "gather")
    assert_same_datasets(mpio, gather, f"mpio vs gather on {n} ranks")
    own = {"hdf5_mode", "command", "created_utc", "run_id", "numpy", "numba", "python"}   # two Pythons
    assert mpio_attrs.keys() == gather_attrs.keys()
    for k in mpio_attrs.keys() - own:
        if k.startswith("timing_"):
            continue
        assert np.array_equal(mpio_attrs[k], gather_attrs[k]), k


def test_overlap_cuts_only_the_rows_peers_keep():
    """Without run.overlap (the default) a rank with peers runs whole rows, all before the exchange; with it,
    each row is cut where its HALO-facing columns end and only those columns run before the exchange.  Either
    way every OWNED node of an integrated row is in exactly one task."""
    st = derive(scene(**{**SMALL, **QUICK}))
    lat = st.lattice
    for rank in (0, 1):
        plain = build_layout(lat, rank, 3, st.reach, st.drive.mode)
        cut = build_layout(lat, rank, 3, st.reach, st.drive.mode, overlap=True)
        assert plain.tasks["early"].all()
        assert 0 < cut.tasks["early"].sum() < len(cut.tasks) and len(cut.tasks) > len(plain.tasks)
        nodes = {k: t["n"] * t["rows"] for k, t in (("plain", plain.tasks), ("cut", cut.tasks))}
        assert nodes["cut"][cut.tasks["early"] == 1].sum() < nodes["plain"].sum() / 2
        assert nodes["cut"].sum() == nodes["plain"].sum() == sum(
            int(max(hi - lo, 0)) for b in plain.blocks for r, (lo, hi) in enumerate(b.owned) if b.integrated[r])
        for lay in (plain, cut):            # each node in exactly one task, a task's rows consecutive
            seen = {(t["block"], t["row"] + i, t["j0"] + k) for t in lay.tasks for i in range(t["rows"])
                    for k in range(t["n"])}
            assert len(seen) == nodes["plain"].sum()
    serial = build_layout(lat, 0, 1, st.reach, st.drive.mode, overlap=True)
    assert not serial.tasks["early"].any()


def test_slabs_narrower_than_the_slip_are_bitwise_identical(small_runs, tmp_path):
    """Eight ranks on 40 columns: under the contact slabs of 3 or 4 columns, narrower than the interface halos
    (9 to 11 columns), so halos reach across several slabs (multi-hop).  With run.overlap, so that the cut rows
    and the exchange that overlaps the rest give the bits of one rank too (1, 2 and 3 ranks run without).
    The ranks are grouped three to a pretend node (``PARSLIP_NODE_RANKS``): a rank reaches the peers of its
    group through the shared windows and the others by MPI messages, both in one exchange (the 1-, 2- and
    3-rank runs use the windows alone)."""
    require("gather")
    st = derive(scene(**{**SMALL, **QUICK}))
    lay = build_layout(st.lattice, 0, 8, st.reach)
    assert max(np.diff(lay.bounds)[1:-1]) < min(st.reach.bottom) and len(lay.peers) >= 3
    ref = small_runs.get("gather", 1)[0]
    out = tmp_path / "r8.vtkhdf"
    p = run_cli(8, "run", small_runs.scene, "--out", out, "--no-png", "--set", "run.overlap=true",
                env={"PARSLIP_NODE_RANKS": "3"})
    assert p.returncode == 0, p.stderr
    assert re.search(r"halo exchange: shared memory with \d+ to \d+ peers on its node, messages to \d+ to \d+",
                     p.stderr), p.stderr
    assert_same_datasets(datasets(out)[0], ref, "gather on 8 ranks")


def test_messages_alone_give_the_bits_of_shared_memory(small_runs, tmp_path):
    """``run.exchange = "messages"``: every halo copy travels as an MPI message; the same bits as one rank."""
    require("gather")
    out = tmp_path / "m3.vtkhdf"
    p = run_cli(3, "run", small_runs.scene, "--out", out, "--no-png", "--set", 'run.exchange="messages"')
    assert p.returncode == 0, p.stderr
    assert "halo exchange: MPI messages" in p.stderr, p.stderr
    assert_same_datasets(datasets(out)[0], small_runs.get("gather", 1)[0], "messages on 3 ranks")


def test_slip_beyond_the_halo_stops_the_run(tmp_path):
    """The halo serves interface.slip_reach; sliding further is refused, not wrong.

    At v0 = 0.05 c_r the block's interface slides about 7 a in 6 l/c_r; halos sized for 0.2 a
    (plus the interface's own reach) stop serving it about halfway."""
    require("gather")
    sc = tmp_path / "small.toml"
    sc.write_text(small_toml(**{"interface.slip_reach": 0.2, "drive.v0": 0.05}))
    out = tmp_path / "o.vtkhdf"
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet")
    assert p.returncode == 3, p.stderr
    assert "interface.slip_reach" in p.stderr and "Traceback" not in p.stderr
    with h5py.File(out, "r") as f:
        assert read_status(f).startswith("failed: interface slip reached")


@pytest.mark.parallel(nprocs=3)
def test_a_failure_on_rank_0_reaches_every_rank_of_a_decision():
    """collective.decide: a ConfigError on rank 0 is that ConfigError everywhere; any other exception is raised
    as it is on rank 0 and as a RunError naming it on the others (none is left waiting in the broadcast);
    a value reaches all three ranks."""
    from mpi4py import MPI
    from parslip.errors import ConfigError, RunError
    from parslip.parallel.collective import decide
    comm = MPI.COMM_WORLD

    def bad_key():
        raise ConfigError("drive.v0 = -1: accepted: > 0")

    def disk_gone():
        raise OSError("disk gone")

    with pytest.raises(ConfigError, match="drive.v0 = -1"):
        decide(comm, bad_key)
    with pytest.raises(OSError if comm.rank == 0 else RunError, match="disk gone"):
        decide(comm, disk_gone)
    assert decide(comm, lambda: comm.rank + 42) == 42
