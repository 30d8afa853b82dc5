"""Parallel runs against serial runs, compared by global node id.

The in-process tests run under mpi-pytest on 2 ranks; the rank-count tests
launch the real command line on 1, 2 and 3 ranks (3 is oversubscribed on a
2-core machine) through both writers, and compare the output files bit for
bit: rank against rank, and HDF5's collective mpio driver (the venv that
tests/install.sh builds, under Debian's mpiexec.mpich) against rank 0
gathering (PyPI's serial h5py, under the mpich wheel's mpiexec).
"""
import h5py
import numpy as np
import pytest

from helpers import SMALL, WRITERS, datasets, require, run_cli, scene, small_toml
from parslip.parallel.decomposition import LEFT, RIGHT, SlabExchanger, build_layout, partition, bottom_site_reach
from parslip.engine.simulation import Simulation
from parslip.scene.derive import derive
from parslip.model.lattice import Lattice


@pytest.mark.parallel(nprocs=2)
def test_halo_exchange_by_global_id():
    """A 4-row bulk strip of 10 columns cut at column 5 (reach 1: bulk rows only).

        column      0 1 2 3 4 | 5 6 7 8 9
        rank 0      O O O O O | H              O owned, H halo copy
        rank 1              H | O O O O O

    After ``forward`` every halo copy holds its owner's value (here 1000 + gid);
    after ``reverse_add`` each owner has received the values written into the
    copies of its nodes (here 1 per copy), so exactly the nodes of columns 4
    and 5 (4 rows each) gain 1.
    """
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    lat = Lattice(4, 10, 0, 0)
    lay = build_layout(lat, comm.rank, comm.size, 0.0)
    assert lay.col_range == ((0, 5) if comm.rank == 0 else (5, 10))
    ex = SlabExchanger(comm)
    gid = lay.nodes["gid"]
    u = np.where(np.arange(len(gid)) < lay.n_owned, 1000.0 + gid, -1.0)[:, None] * np.ones(2)
    ex.forward(lay.node_channel, u)
    np.testing.assert_array_equal(u[:, 0], 1000.0 + gid)
    halo_cols = lay.nodes["col"][lay.n_owned:]
    assert set(halo_cols) == ({5} if comm.rank == 0 else {4})
    assert len(lay.node_channel.recv[LEFT if comm.rank else RIGHT]) == 4

    r = np.zeros((len(gid), 2))
    r[lay.n_owned:] = 1.0
    ex.reverse_add(lay.node_channel, r)
    own_cols = lay.nodes["col"][:lay.n_owned]
    edge = 4 if comm.rank == 0 else 5
    np.testing.assert_array_equal(r[:lay.n_owned, 0], (own_cols == edge).astype(float))


@pytest.mark.parallel(nprocs=2)
def test_parallel_state_matches_serial_by_global_id():
    """Two ranks and one rank agree to the bit on every node, after bonds broke and re-formed."""
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    sc = scene(**SMALL)
    st = derive(sc)
    par = Simulation(st, SlabExchanger(comm), comm)
    ser = Simulation(derive(sc, (st.omega_max, st.omega_method)))
    n = st.n_drive_start + int(0.8 * st.n_drive)
    par.run(until=n)
    ser.run(until=n)
    total = comm.allreduce(int(par.counters[0]))
    assert total > 5 and total == ser.counters[0]
    g_par = par.layout.nodes["gid"][:par.n_owned]
    pos = np.searchsorted(ser.layout.nodes["gid"][:ser.n_owned], g_par)
    np.testing.assert_array_equal(par.u[:par.n_owned], ser.u[pos])
    np.testing.assert_array_equal(par.u_prev[:par.n_owned], ser.u_prev[pos])
    own = par.own_sites
    np.testing.assert_array_equal(par.partner[own], ser.partner[par.layout.top_gsite[own]])




# SMALL with a short settle and a faster drive: 926 steps in which bonds still
# break and re-form across slab boundaries.  Short because Debian's MPICH (the
# mpio venv's) spins while it waits: on 3 ranks over 2 cores each halo exchange
# then costs a scheduler time slice, about 4 ms against 0.04 ms for the wheel.
QUICK = {"load.ramp": 0.2, "load.settle": 0.5, "drive.v0": 0.05, "drive.duration": 2.0}


class SmallRuns:
    """SMALL + QUICK on 1, 2 and 3 ranks through each writer, each run once per module and only when asked."""

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
    """The substrate overhangs the block 2:1 on each side, so on 3 ranks the outer
    slabs hold no top node: they must still take part in every exchange and every write."""
    require(writer)
    over = {"lattice.top_cols": 12, "lattice.bottom_cols": 100, "drive.v0": 0.02, "drive.duration": 4.0,
            "load.ramp": 0.2, "load.settle": 0.5}
    sc = tmp_path / "overhang.toml"
    sc.write_text(small_toml(**over))
    st = derive(scene(**{**SMALL, **over}))
    bounds = partition(st.lattice.col_count, 3, max(bottom_site_reach(st.slip_reach), 4))
    # Not even a halo copy of a top node on the outer ranks (the top row's halo reaches 4 columns).
    assert bounds[1] <= st.lattice.top.col0 - 4 and bounds[2] >= st.lattice.top.col0 + 12 + 4
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
        assert attrs["n_ranks"] == n and attrs["hdf5_mode"] == writer
        assert f"writer: {writer} (" in log
        assert_same_datasets(data, ref, f"{writer} on {n} ranks")

    # The test must exercise the hard case: a bond that broke and re-formed
    # with its top node and its new bottom partner on different ranks.
    lat = Lattice(4, 24, 4, 40)
    intact, partner = ref["interface/intact"], ref["interface/partner"]
    crossed = {}
    for n in (2, 3):
        reach = max(bottom_site_reach(QUICK["drive.v0"] * QUICK["drive.duration"] * 24 + 2.0), 4)
        bounds = partition(lat.col_count, n, reach)
        owner = lambda col: np.searchsorted(bounds, col, side="right") - 1   # noqa: E731
        top_owner = owner(lat.top.col0 + np.arange(lat.top.cols))
        was_broken = np.maximum.accumulate(intact == 0, axis=0)
        rebonded = (intact == 1) & was_broken
        across = rebonded & (owner(np.maximum(partner, 0)) != top_owner[None, :])
        crossed[n] = int(across.sum())
    assert crossed[2] > 0 and crossed[3] > 0, crossed


@pytest.mark.parametrize("n", (1, 2, 3))
def test_collective_mpio_and_gathered_files_are_identical(small_runs, n):
    """Every rank writing its slices through HDF5's mpio driver gives, byte for byte, the
    datasets rank 0 writes after gathering; only hdf5_mode (and the run's own command line
    and clock) tell the files apart."""
    require("gather")
    require("mpio")
    (mpio, mpio_attrs, _), (gather, gather_attrs, _) = small_runs.get("mpio", n), small_runs.get("gather", n)
    assert (mpio_attrs["hdf5_mode"], gather_attrs["hdf5_mode"]) == ("mpio", "gather")
    assert_same_datasets(mpio, gather, f"mpio vs gather on {n} ranks")
    own = {"hdf5_mode", "command", "created_utc"}
    assert mpio_attrs.keys() == gather_attrs.keys()
    for k in mpio_attrs.keys() - own:
        assert np.array_equal(mpio_attrs[k], gather_attrs[k]), k


def test_slip_beyond_the_halo_stops_the_run(tmp_path):
    """A slab's halo reaches interface.slip_reach + 6 columns; sliding further is refused, not wrong."""
    sc = tmp_path / "small.toml"
    sc.write_text(small_toml(**{"interface.slip_reach": 0.2}))
    out = tmp_path / "o.vtkhdf"
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet")
    assert p.returncode == 3, p.stderr
    assert "interface.slip_reach" in p.stderr and "Traceback" not in p.stderr
    with h5py.File(out, "r") as f:
        assert f.attrs["status"].startswith("failed: interface slip reached")
