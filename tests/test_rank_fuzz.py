"""Rank-count fuzz: the shipped scenes' physics, small, on 1 to 4 ranks, past many full frame buffers,
a checkpoint and a restart on another rank count; every /interface dataset bitwise the 1-rank run's.

The lattice is SMALL with a substrate that overhangs the block by 63 columns each side, so the slabs
split the interface sites unevenly (4/16/4 on 3 ranks) and, on 4 ranks, the outer ranks own substrate
columns only (no interface site at all: 0/12/12/0).  At v0/c_r = 0.1 the block slides 7 a in 3 l/c_r,
more than the 4 block columns of each outer slab on 3 ranks: halos reach across slabs (slabs narrower
than the slip on every rank: ``test_parallel``).  The frame buffer holds 12 frames of the 73 a run
records, so every run flushes six times, and the restarts' halves three times each; before the fix of the
collective rule, ranks with fewer sites filled their (then larger) buffers at other frames and 3+ ranks
hung.  Each flush of the collective writer costs seconds here: its ranks (Debian's MPICH) poll without
yielding, three or four on two cores (a 4-rank run of the pull scene on a loaded host: about 5 s of wall a
flush; 107 s of CPU with 21 flushes in 2656 steps at v0/c_r = 0.05 over 6 l/c_r, the same slip, 87 s with
18 in 1406 steps, 49 s with 6).  The load settles for 1 l/c_r, not SMALL's 2.

Every run has a hard time limit (``helpers.run_limited``): a hang fails the test, it does not stall CI.
Rank counts above 2 are oversubscribed on a 2-core machine, up to 4 (more only makes the ranks spin
against each other: a 6-rank run of this scene took 11 s against 3 s on 2); both writers run on 2 to 4
ranks, the gathering writer on 1 too, and both on restarts.
"""
import numpy as np
import pytest

from helpers import SMALL, datasets, require, run_cli, scene, small_toml
from parslip.parallel.layout import column_cost, owned_site_counts, partition
from parslip.scene.derive import derive

FUZZ = {**SMALL, "lattice.bottom_cols": 150, "drive.v0": 0.1, "drive.duration": 3.0, "load.settle": 1.0,
        "output.buffer_frames": 12, "output.buffer_events": 5, "output.snapshots": 2}
HALF = FUZZ["drive.duration"] / 2          # where the restart tests' first half ends with a checkpoint
LIMIT_S = 150                # per run: a hung run fails here at the latest
WATCHDOG = ("--watchdog", "30")   # and its own watchdog ends it sooner, naming where the ranks wait
# scene -> [(ranks, writer)]: 2 to 4 ranks over the three scenes, both writers on each count.
RUNS = {"push": [(2, "mpio"), (4, "gather")],
        "pull": [(3, "gather"), (4, "mpio")],
        "shear": [(2, "gather"), (3, "mpio")]}
# scene -> (ranks, writer) of the first half, then (ranks, writer) of the restart.
RESTARTS = {"push": ((3, "gather"), (4, "gather")), "pull": ((4, "gather"), (2, "gather")),
            "shear": ((4, "mpio"), (2, "mpio"))}


def interface(path) -> dict:
    data, attrs = datasets(path)
    assert attrs["status"] == "complete", attrs["status"]
    return {k: v for k, v in data.items() if k.startswith("interface/")}


def assert_bitwise(got, ref, what):
    assert got.keys() == ref.keys(), what
    for name in ref:
        assert got[name].dtype == ref[name].dtype and got[name].shape == ref[name].shape, (what, name)
        assert got[name].tobytes() == ref[name].tobytes(), (what, name)


def test_the_fuzz_covers_what_it_claims():
    """The decompositions the fuzz runs on: uneven site splits, ranks with no interface site, slabs
    narrower than the slip the runs reach, and a frame buffer far smaller than the frames."""
    st = derive(scene(**FUZZ))
    lat = st.lattice
    splits = {n: owned_site_counts(lat, partition(column_cost(lat), n)) for n in range(2, 5)}
    assert all(len(set(splits[n].tolist())) > 1 for n in (3, 4))                   # uneven
    assert (splits[4] == 0).sum() == 2                                           # substrate-only slabs
    b3 = partition(column_cost(lat), 3)
    t0, t1 = lat.top.col0, lat.top.col0 + lat.top.cols
    held = [min(b3[i + 1], t1) - max(b3[i], t0) for i in range(3)]
    assert min(held) < FUZZ["drive.v0"] * FUZZ["drive.duration"] * st.l        # the drive moves the block 7.2 a
    assert st.n_frames > 6 * FUZZ["output.buffer_frames"]                      # six full frame buffers
    assert HALF / FUZZ["drive.duration"] * st.n_frames > 2 * FUZZ["output.buffer_frames"]     # two a half
    used = sorted({n for runs in RUNS.values() for n, _ in runs} | {n for a, b in RESTARTS.values() for n in (a[0], b[0])})
    assert used == [2, 3, 4]
    assert all({w for runs in RUNS.values() for m, w in runs if m == n} == {"gather", "mpio"} for n in used)


@pytest.fixture(scope="module", params=sorted(RUNS))
def reference(request, tmp_path_factory):
    """The scene on one rank, its /interface datasets, and its scene file."""
    mode = request.param
    require("gather")
    d = tmp_path_factory.mktemp(f"fuzz_{mode}")
    sc = d / f"{mode}.toml"
    sc.write_text(small_toml(**{**FUZZ, "drive.mode": mode}))
    out = d / "r1.vtkhdf"
    p = run_cli(1, "run", sc, "--out", out, "--no-png", "--quiet", timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr
    ref = interface(out)
    assert (ref["interface/intact"] == 0).any() and np.abs(ref["interface/ux"]).max() * 24 > 6   # slid > 6 a
    t = ref["interface/events/time"]
    assert (t < HALF).sum() > 50 and (t > HALF).sum() > 50       # bonds break and re-form on both sides of a restart
    return mode, sc, d, ref


def test_any_rank_count_writes_the_one_rank_interface(reference):
    mode, sc, d, ref = reference
    for n, writer in RUNS[mode]:
        require(writer)
        out = d / f"{writer}{n}.vtkhdf"
        p = run_cli(n, "run", sc, "--out", out, "--no-png", "--quiet", *WATCHDOG, writer=writer, timeout=LIMIT_S)
        assert p.returncode == 0, f"{mode} on {n} ranks ({writer}):\n{p.stderr[-3000:]}"
        assert_bitwise(interface(out), ref, f"{mode} on {n} ranks ({writer})")


def test_checkpoint_on_one_rank_count_restart_on_another(reference):
    """The first half (1.5 of the 3 l/c_r) ends with a checkpoint; a restart on another rank count extends
    it to 3 l/c_r: the file then holds the 1-rank run's interface, bit for bit.  A checkpoint at the half
    only: each one the collective writer writes on 4 ranks costs seconds here, and a checkpoint written
    over its previous generations on 4 mpio ranks is test_restart's (checkpoints every 1 l/c_r, written
    on 4 ranks, continued on 3)."""
    mode, sc, d, ref = reference
    (n1, w1), (n2, w2) = RESTARTS[mode]
    require(w1)
    require(w2)
    out = d / f"restart_{n1}_{n2}.vtkhdf"
    p = run_cli(n1, "run", sc, "--out", out, "--no-png", "--quiet", "--set", f"drive.duration={HALF}",
                "--set", f"checkpoint.every={HALF}", *WATCHDOG, writer=w1, timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    p = run_cli(n2, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", f"{out}.ckpt.h5",
                "--set", f"checkpoint.every={HALF}", *WATCHDOG, writer=w2, timeout=LIMIT_S)
    assert p.returncode == 0, p.stderr[-3000:]
    assert_bitwise(interface(out), ref, f"{mode}: {n1} ranks ({w1}), then {n2} ranks ({w2})")
