"""The compiled loop against independent computations: the first engine's plain step, a brute-force
re-bonding search, the interface kernel's reach checks, and the rigid substrate's own limits."""
import os
import pathlib

import numpy as np
import pytest

from helpers import (SMALL, assert_extension_is_the_run, datasets, reference, require, run_cli, scene, simulation,
                     small_toml)
from parslip.engine.kernels import budget as bg
from parslip.engine.kernels import interface as ik
from parslip.model.interface import PARTNER
from parslip.errors import NonFiniteError
from parslip.model.lattice import BOTTOM, TOP
from parslip.scene.memory import CHECK_EVERY
from parslip.scene.derive import derive


def test_fused_step_equals_the_reference_step_while_bonds_break_and_reform():
    """From the same state, one compiled step and one step of the first engine's per-node kernels
    (neighbours gathered by index, each bond's force on its own) agree to round-off, and their bonds
    agree exactly, at every step of a stretch in which bonds break and re-form."""
    sim = simulation(SMALL)
    st = sim.setup
    sim.run(until=st.n_drive_start + int(0.5 * st.n_drive))
    events = 0
    worst = 0.0
    for _ in range(300):
        ref = reference(sim)
        before = sim.counters.copy()
        ref_before = ref.counters.copy()
        sim.step()
        ref.step()
        scale = np.abs(ref.u[:ref.n_owned]).max()
        worst = max(worst, np.abs(sim.u - ref.u[:ref.n_owned]).max() / scale)
        np.testing.assert_array_equal(sim.state.owned_partner(), ref.partner[ref.own_sites])
        assert np.array_equal(sim.counters - before, ref.counters - ref_before)
        events += int((sim.counters - before).sum())
    assert events >= 2, events                 # the stretch really had breaks and re-formations
    assert worst < 1e-13, worst


def test_whole_run_matches_the_reference_run():
    """A whole run of SMALL (about 2,900 steps, 39 breaks) stays within 1e-11 of the reference run."""
    sim = simulation(SMALL)
    ref = reference(simulation(SMALL))
    sim.run()
    ref.run(until=sim.n)
    assert np.abs(sim.u - ref.u[:ref.n_owned]).max() < 1e-11 * np.abs(ref.u).max()
    np.testing.assert_array_equal(sim.counters, ref.counters)
    np.testing.assert_array_equal(sim.state.owned_partner(), ref.partner[ref.own_sites])


# A wide gap under a heavy load: delta0 = 2.5 compressed to about 0.5 by F_N = 2 x 24 x 0.3 = 14.4,
# so a free node may re-bond to a substrate site up to 2.45 a away in x: two columns off.
WIDE = {**SMALL, "interface.delta0": 2.5, "interface.delta_b": 2.8, "load.FN": 14.4, "drive.v0": 0.05,
        "output.snapshots": 0}
# A substrate of the block's own material, tall and loaded so that its interface sites follow the block by
# about 2 a (a substrate 35 times stiffer moves a few hundredths of that): re-bonding must find them there.
SOFT_PAIR = {**SMALL, "lattice.top_rows": 8, "lattice.bottom_rows": 24, "material.bottom_kn": 2.81154,
             "material.bottom_kt": 0.133883, "drive.mode": "shear", "drive.duration": 12.0, "load.FN": 6.0,
             "interface.ky": 1.0, "interface.kx": 0.3, "output.snapshots": 0}


def _nearest_free(sim, j, taken):
    """Brute force over every substrate site: the nearest free one within delta0 (ties: lower index)."""
    s = sim.state
    bx, by, tx, ty = s.level(sim.n)
    g = s.iface.geom
    br = g.brow
    d0 = sim.setup.scene["interface.delta0"]
    gcol = j + g.tbase
    best, who = np.inf, -1
    for i in range(g.blo, g.bhi):
        q = i + g.bbase
        if taken[i]:
            continue
        dx = (gcol - q) + (tx[1, j] - bx[br, i])
        dy = d0 + (ty[1, j] - by[br, i])
        d2 = dx * dx + dy * dy
        if d2 <= d0 * d0 and d2 < best:
            best, who = d2, q
    return who


@pytest.mark.parametrize("case", ["wide gap", "drifted substrate"])
def test_rebonds_to_the_nearest_free_site_even_two_columns_away(case):
    """Each bond formed is the brute-force nearest free site of the whole substrate row, and some are two
    or more columns from the node's nearest column: because delta0 = 2.5 reaches that far (a free site
    looks R + 1/2 = 3 a either way), or because the substrate's sites have drifted about 2 a from their
    columns (a soft substrate)."""
    sim = simulation(WIDE if case == "wide gap" else SOFT_PAIR)
    st = sim.setup
    assert st.reach.link == (3 if case == "wide gap" else 1)
    sim.run(until=st.n_drive_start)
    far = formed = 0
    drift = 0.0
    g = sim.state.iface.geom
    for _ in range(st.n_drive):
        s = sim.state
        drift = max(drift, float(np.abs(s.level(sim.n)[0][g.brow, g.bown0:g.bown1]).max()))
        partner_before = s.iface.bonds[PARTNER].astype(np.int64)
        _, _, tx, _ = s.level(sim.n)
        ux = tx[1].copy()
        sim.step()
        lo, hi = g.tlo, g.thi
        now = s.iface.bonds[PARTNER].astype(np.int64)
        new = [j for j in range(lo, hi) if now[j] >= 0 and now[j] != partner_before[j]]
        if not new:
            continue
        # Recompute the claims at the state the step started from (level n - 1 now holds u(n - 1)).
        sim.n -= 1
        taken = np.zeros(g.bhi + 1, bool)
        for j in range(lo, hi):
            p = int(s.iface.bonds[PARTNER, j])
            if p >= 0 and j not in new:
                taken[p - g.bbase] = True
        for j in new:
            assert int(s.iface.bonds[PARTNER, j]) == _nearest_free(sim, j, taken), j
            taken[int(s.iface.bonds[PARTNER, j]) - g.bbase] = True
            formed += 1
            far += abs(int(s.iface.bonds[PARTNER, j]) - round(j + g.tbase + ux[j])) >= 2
        sim.n += 1
    assert formed > 10 and far > 0, (formed, far)
    assert drift > (1.5 if case == "drifted substrate" else 0.0), drift


def test_a_folded_substrate_row_stops_the_run_with_one_line():
    """Re-bonding walks the substrate's interface row in x order, so a site that passes its left neighbour
    stops the run (exit 3) at the next check, naming the step and the column.  A substrate soft enough
    (k_n = 0.02) that the fold does not first run away."""
    sim = simulation(SMALL, **{"material.bottom_kn": 0.02, "material.bottom_kt": 0.001})
    n = CHECK_EVERY - 1                       # the next step ends on a check
    sim.run(until=n)
    nd = sim.state.nodes()
    u = sim.u
    site = (nd["block"] == BOTTOM) & (nd["row"] == sim.setup.lattice.bottom.rows - 1) & (nd["col"] == 20)
    u[site, 0] -= 1.3                         # 0.3 a to the left of column 19's site
    sim.set_u(u)
    with pytest.raises(NonFiniteError, match=rf"interface row folded at step {n + 1} .* column 20 stood -0\.[23]"):
        sim.run(until=n + 1)

def test_drifted_substrate_runs_the_same_on_1_and_3_ranks_and_through_a_restart(tmp_path):
    """SOFT_PAIR through the command line: 3 ranks write the 1-rank run bit for bit, and so does the run
    stopped halfway (2 ranks, its end checkpoint) and continued to the end on 3 ranks."""
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**{**SOFT_PAIR, "checkpoint.every": 3.0}))
    outs = {}
    for n in (1, 3):
        outs[n] = tmp_path / f"o{n}.vtkhdf"
        p = run_cli(n, "run", sc, "--out", outs[n], "--no-png", "--quiet")
        assert p.returncode == 0, p.stderr
    ref, _ = datasets(outs[1])
    got, _ = datasets(outs[3])
    assert ref.keys() == got.keys() and all(ref[k].tobytes() == got[k].tobytes() for k in ref)
    assert len(ref["interface/events/kind"]) > 20
    assert_extension_is_the_run(sc, tmp_path / "r.vtkhdf", ref, 6.0, 2, 3)


def test_wide_gap_is_bitwise_identical_on_1_and_3_ranks(tmp_path):
    require("gather")
    sc = tmp_path / "wide.toml"
    sc.write_text(small_toml(**{k: v for k, v in WIDE.items() if k not in SMALL or WIDE[k] != SMALL[k]}))
    files = {}
    for n in (1, 3):
        p = run_cli(n, "run", sc, "--out", tmp_path / f"w{n}.vtkhdf", "--no-png", "--quiet")
        assert p.returncode == 0, p.stderr
        files[n] = datasets(tmp_path / f"w{n}.vtkhdf")[0]
    intact = files[1]["interface/intact"]
    assert (intact == 0).any() and (np.diff(intact.astype(int), axis=0) > 0).any()   # broke and re-formed
    for name, ref in files[1].items():
        assert files[3][name].tobytes() == ref.tobytes(), name


def test_a_bond_out_of_reach_is_caught_not_skipped():
    """An OWNED interface site bonded to a substrate site this rank does not hold: the kernel reports
    it (and leaves the bond alone) instead of silently skipping its force and its break test."""
    sim = simulation(SMALL)
    s = sim.state
    g = s.iface.geom
    j = g.town0 + 3
    s.iface.bonds[PARTNER, j] = int(g.bbase + g.bhi) + 5          # beyond the stored substrate columns
    bx, by, tx, ty = s.level(0)
    br = g.brow
    s.iface.reach[0] = -1
    ik.update(0, tx[1], ty[1], bx[br], by[br], tx[1], ty[1], bx[br], by[br], s.iface,
              np.zeros((len(bg.SITE_TERMS), 2, tx.shape[1])))
    assert s.iface.reach[0] == j + g.tbase


def test_rigid_substrate_static_gap_and_no_substrate_nodes():
    """Rigid: at rest the springs carry the whole load, sum_i k_y (delta0 - gap_i) = F_N, so the mean gap
    is delta0 - F_N/(N k_y); the lattice holds the block only, and omega_max (dt) comes from the block
    and the springs."""
    FN, N, ky = 2.0, 24, 0.3
    sim = simulation(SMALL, **{"lattice.substrate": "rigid", "drive.mode": "none", "load.FN": FN,
                               "load.settle": 30.0, "drive.duration": 0.01})
    st = sim.setup
    assert st.lattice.n_nodes == 4 * 24 and (sim.state.own_block == TOP).all()
    sim.run(until=st.n_drive_start)
    _, _, tx, ty = sim.state.level(sim.n)
    s = sim.state.owned_sites()
    gaps = 0.5 + ty[1, s]
    assert gaps.mean() == pytest.approx(0.5 - FN / (N * ky), abs=1e-10)
    assert np.abs(sim.u - sim.u_prev).max() / st.dt < 1e-10               # at rest
    elastic = derive(scene(**SMALL))
    assert st.dt_limit > 4 * elastic.dt_limit           # no stiff substrate: a much longer time step


def test_rigid_substrate_is_the_stiff_limit():
    """k_n -> infinity: the first break of SMALL's push converges to the rigid substrate's, as 1/k_n.

    All at one time step (below the k_n = 1e4 limit), stepped one by one near the break, so the
    difference is the substrate's compliance alone: it adds a series compliance proportional to 1/k_n,
    so tripling k_n divides the difference by about 3, and at 1e4 it is within one step."""
    dt = 0.0075

    def first_break(**over):
        sim = simulation(SMALL, **{"output.snapshots": 0, "time.dt": dt, **over})
        st = sim.setup
        sim.run(until=st.n_drive_start + int(1.0 * st.t_unit / dt))     # the first break comes later
        assert sim.counters[0] == 0
        while sim.n < st.n_steps and sim.counters[0] == 0:
            sim.step()
        return sim.n - st.n_drive_start
    rigid = first_break(**{"lattice.substrate": "rigid"})
    steps = {k: first_break(**{"material.bottom_kn": k}) - rigid for k in (100.0, 300.0, 1e3, 1e4)}
    assert steps[100.0] >= 10, steps                                # the elastic substrate delays it
    assert 2.0 <= steps[100.0] / steps[300.0] <= 4.5, steps          # ~ 1/k_n
    assert abs(steps[1e3]) <= 2 and abs(steps[1e4]) <= 1, steps


def test_a_changed_kernel_gets_a_fresh_numba_cache(tmp_path):
    """numba checks a cached function against its own file only: the compiled loop would keep an old
    interface kernel after engine/kernels/interface.py changed.  The cache folder is keyed by the kernels'
    sources (io.cache.kernel_sources: the modules with compiled code and every module they import), so
    changing interface.py alone moves it, as does a module whose constants the loop freezes in
    (parallel/codes.py); a change to what only Python runs (the analysis, the run's orchestration in
    engine/simulation.py) does not."""
    import shutil
    import subprocess
    import sys
    pkg = pathlib.Path(__file__).resolve().parents[1] / "parslip"
    copy = tmp_path / "parslip"
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    code = "from parslip.io.cache import kernel_cache_dir; print(kernel_cache_dir())"
    env = {**os.environ, "PYTHONPATH": str(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "nc")}

    def where():
        return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=tmp_path,
                              check=True).stdout.strip()
    first = where()
    assert first.startswith(str(tmp_path / "nc"))
    for name in ("analysis/fronts.py", "engine/simulation.py", "engine/runner.py", "parallel/layout.py"):
        (copy / name).write_text((copy / name).read_text() + "\n# x\n")
        assert where() == first, name
    (copy / "engine" / "kernels" / "interface.py").write_text(
        (copy / "engine" / "kernels" / "interface.py").read_text() + "\n# a change\n")
    second = where()
    assert second != first
    (copy / "parallel" / "codes.py").write_text((copy / "parallel" / "codes.py").read_text() + "\n# a change\n")
    assert where() not in (first, second)


@pytest.mark.parametrize("mode,rows", [("push", ()), ("push", (1, 2)), ("pull", ()), ("shear", ()), ("none", ())])
def test_the_memory_prediction_counts_the_frame_buffer_the_engine_holds(mode, rows):
    """``scene.memory.frame_bytes`` against the engine's own frame arrays (one rank), and the count of a
    slab's driven nodes it uses (``Lattice.driven_in_columns``, closed form) against ``Lattice.kinds`` over
    every slab of a split into 1 to 4 column ranges."""
    from parslip.model.lattice import DRIVEN
    from parslip.scene import memory
    sim = simulation(SMALL, **{"drive.mode": mode, "drive.rows": list(rows)})
    st, fr = sim.setup, sim.frames
    held = sum(a.nbytes for name, a in zip(fr._fields, fr) if name != "cursor")
    sites = fr.intact.shape[1]
    assert held == memory.frame_bytes(sim.buffer_frames, sites, fr.fdrive.shape[1])
    lat = st.lattice
    for n in range(1, 5):
        cuts = np.linspace(0, lat.ncols, n + 1).astype(int)
        for c0, c1 in zip(cuts[:-1], cuts[1:]):
            nodes = lat.nodes_in_columns(int(c0), int(c1))
            want = int((lat.kinds(nodes, mode, rows) == DRIVEN).sum())
            assert lat.driven_in_columns(mode, rows, int(c0), int(c1)) == want, (mode, rows, c0, c1)
    if mode != "none":
        assert fr.fdrive.shape[1] == lat.driven_in_columns(mode, rows, 0, lat.ncols) > 0


def test_a_runaway_at_an_interface_site_without_contact_names_the_sinking():
    """A runaway flagged at an interface site of a run without contact names the sinking as a cause (a block
    under F_N whose bonds broke has nothing holding it up; at l = 500 under F_N = 30 that ended a run which
    completes with a contact), with the command that adds one; in the bulk, or with a contact, it does not: with a
    contact, a site's runaway names the contact's switches."""
    from parslip.engine import loop as L
    from parslip.parallel.layout import PAD

    def message(row, block=TOP, **over):
        sim = simulation(SMALL, **over)
        f = np.zeros(L.L_SIZE, np.int64)
        f[[L.L_BITS, L.L_STEP, L.L_BLOCK, L.L_ROW, L.L_COL, L.L_VALUE]] = (
            L.FLAG_RUNAWAY, 100, block, row + PAD, sim.setup.lattice.top.col0 + 3, 500_000)
        return sim._describe_node(f, 1.0)

    top_site = message(0)
    assert "moved 0.5 a in one step" in top_site and "a time step above the stability limit" in top_site
    assert "interface.contact = 0" in top_site and "--set interface.contact=0.3" in top_site
    rows = SMALL["lattice.bottom_rows"]
    assert "interface.contact = 0" in message(rows - 1, block=BOTTOM)
    assert "interface.contact" not in message(1)
    # With a contact the site's cause is the contact's switches (docs/guide/interfaces.md), not a missing contact.
    with_contact = message(0, **{"interface.contact": 0.3})
    assert "a contact that slides (interface.contact)" in with_contact
    assert "interface.contact = 0" not in with_contact and "--set interface.contact" not in with_contact
    assert "a contact that slides" not in message(1, **{"interface.contact": 0.3})
