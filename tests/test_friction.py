"""The friction record and its observables: the block's momentum balance on real runs, and the static
peak, the slip onset, the fronts' fates and the precursors on drawn records with known answers."""
import json
import pathlib
import math

import h5py
import numpy as np
import pytest

import parslip
from helpers import DT, NS, SMALL, blank, draw
from parslip.analysis import friction as FR
from parslip.analysis.results import Run
from parslip.cli import main
from parslip.io.contract import read_snapshot_arrays
from parslip.model.lattice import TOP
from parslip.scene.derive import derive
from parslip.scene.load import load


# --------------------------------------------------------------------------- the block's momentum balance --

def _block_balance(tmp_path, mode):
    """A SMALL run in quasi-static creep (v0/c_r = 2e-3: no bond breaks within 10 l/c_r), a frame at every
    step and 10 snapshots; per interval between snapshots: the recorded forces, and the top block's mass,
    mean displacement and half-step velocity at both ends (from the snapshots)."""
    over = {**SMALL, "drive.mode": mode, "drive.v0": 2e-3, "drive.duration": 10.0, "output.snapshots": 10,
            "output.interface_dt": 1e-9}
    run = parslip.run(over, out=tmp_path / f"{mode}.vtkhdf", progress=False)
    st = derive(load(run.scene))
    lat = st.lattice
    nodes = lat.nodes_in_columns(0, lat.ncols)
    top = nodes["block"] == TOP
    with h5py.File(run.path, "r") as f:
        snaps = int(f["VTKHDF/Steps"].attrs["NSteps"])
    got = [read_snapshot_arrays(str(run.path), k) for k in range(snaps)]
    pts, vel = np.array([g["points"][:, 0] for g in got]), np.array([g["velocity"][:, 0] for g in got])
    X = pts[:, top].mean(axis=1) - nodes["x"][top].mean()      # mean x-displacement of the block, a
    V = vel[:, top].mean(axis=1)                               # mean (u(n) - u(n-1))/dt, internal units
    assert st.frame_every == 1 and len(run.times) == st.n_drive + 1
    assert run.first_break[0] is None                          # creep: nothing broke
    return run, st, int(top.sum()), X, V


@pytest.mark.parametrize("mode", ["push", "pull", "shear"])
def test_drive_and_friction_balance_the_damping_drag_on_the_block(tmp_path, mode):
    """The x-forces on the top block are the interface bonds' (F_T), the drive's and the damping drag
    -zeta m v on every node (the block's own bonds cancel; the load is vertical).  The damped Verlet step
    u+ - 2u + u- + (zeta dt/2)(u+ - u-) = dt^2 F/m summed over the block and over the steps n1..n2-1
    between two snapshots telescopes to
        dt^2 sum_n (F_T(n) + F_drive(n)) = M dt (v(n2) - v(n1)) + (zeta dt/2) M (X(n2) + X(n2-1) - X(n1) - X(n1-1)),
    exact up to rounding with the recorded forces (F_T at frame n is the force of step n; F_drive at frame
    n + 1 the drive's force in step n).  In creep the inertia term vanishes and F_drive + F_T = zeta M V."""
    run, st, M, X, V = _block_balance(tmp_path, mode)
    zeta, dt = run.scene["time.zeta"], st.dt
    steps = list(st.snapshot_steps)
    ft, fd = run.friction_force, run.drive_force
    assert np.all(ft[1:] < 0) and np.all(fd[1:] > 0)        # the interface holds the block back
    creep = 0
    for a in range(len(steps) - 1):
        n1, n2 = steps[a], steps[a + 1]
        impulse = dt * dt * (ft[n1:n2].sum() + fd[n1 + 1:n2 + 1].sum())
        inertia = M * dt * (V[a + 1] - V[a])
        drag = 0.5 * zeta * dt * M * (2 * X[a + 1] - dt * V[a + 1] - 2 * X[a] + dt * V[a])
        assert impulse == pytest.approx(inertia + drag, rel=1e-9, abs=1e-15), (a, impulse, inertia, drag)
        if run.times[n1] >= 3.0:                            # the drive's start-up transient has died out
            creep += 1
            mean_v = (X[a + 1] - X[a]) / ((n2 - n1) * dt)
            balance = ft[n1:n2].mean() + fd[n1 + 1:n2 + 1].mean()
            assert abs(inertia) < 0.01 * abs(drag)
            assert balance == pytest.approx(zeta * M * mean_v, rel=0.01)
            # ... and the drag is no rounding error: F_drive = -F_T would miss it by more than 1 %
            assert zeta * M * mean_v > 0.01 * fd[n1 + 1:n2 + 1].mean()
    assert creep >= 6


# --------------------------------------------------------------------------------------- drawn records --

def _record(crack=True, edge=True):
    """Two precursors from x = 0 (10 and 25 sites), one from x = 1 (12 sites), a pulse from inside the
    contact that leaves through the far edge, then (``crack``) a crack across the contact at frame 200
    and a pulse still running at the end.  mu rises 0.01 per frame to 2.0 at frame 200, falls to 0.5 by
    frame 259, then rises to 3.5 at the end: above mu_s, in the sliding regime."""
    nf = 400
    it = blank(nf)
    arr = {"p1": draw(it, 20, 0, +1, 2, 2, 0.001, sites=10),
           "p2": draw(it, 90, 0, +1, 2, 2, 0.001, sites=25),
           "p3": draw(it, 40, NS - 1, -1, 2, 2, 0.001, sites=12)}
    if edge:
        arr["edge"] = draw(it, 140, 30, +1, 1, 2, 0.001)
    if crack:
        arr["crack"] = draw(it, 200, 0, +1, 1, 1, 0.01, crack=True)
        it["intact"][270:] = 1                                  # the contact re-bonds after the crack
        for j in range(14):                                     # a one-site pulse, at site 13 in frame 398
            it["intact"][385 + j, j] = 0
    k = np.arange(nf)
    mu = np.where(k <= 200, 0.01 * k, np.where(k <= 259, 2.0 - 1.5 * (k - 200) / 59, 0.5 + 3.0 * (k - 259) / 140))
    it["mu"] = mu
    return it, arr


def test_static_peak_is_the_largest_mu_before_the_contact_has_slipped_everywhere():
    it, arr = _record()
    pk = FR.static_peak(Run.from_arrays(it, scene={"load.FN": 2.0}))
    # Every site broke once when the crack reached site 29: sites 0-24 and 48-59 broke in precursors,
    # 30-59 in the pulse that left through the edge, 25-29 only in the crack.
    assert FR.slip_onset(Run.from_arrays(it)) == 229
    assert pk.slip_onset == pytest.approx(229 * DT) and pk.window == "slip onset"
    assert pk.mu_s == pytest.approx(2.0) and pk.frame == 200 and pk.time == pytest.approx(200 * DT)
    assert it["mu"].max() > 3 * pk.mu_s / 2                  # the sliding regime rises higher: not counted
    assert pk.force == pytest.approx(4.0)
    assert pk.first_break_time == pytest.approx(20 * DT) and pk.first_break_x == it["x"][0]
    assert pk.mu_first_break == pytest.approx(0.2)
    assert pk.after_first_break == pytest.approx(180 * DT) and pk.place == "after"


def test_without_slip_onset_the_peak_is_the_record_maximum_and_a_bound():
    it, _ = _record(crack=False)
    pk = FR.static_peak(Run.from_arrays(it))
    assert FR.slip_onset(Run.from_arrays(it)) is None and pk.slip_onset is None and pk.window == "record"
    assert pk.mu_s == it["mu"].max() and pk.frame == 399 and math.isnan(pk.force)


@pytest.mark.parametrize("k_peak,place", [(10, "before"), (20, "at"), (21, "at"), (23, "after")])
def test_place_of_the_peak_relative_to_the_first_break(k_peak, place):
    it, _ = _record()
    it["mu"] = np.exp(-((np.arange(len(it["t"])) - k_peak) / 5.0) ** 2)   # one bump, first break at frame 20
    pk = FR.static_peak(Run.from_arrays(it))
    assert pk.frame == k_peak and pk.place == place
    assert pk.after_first_break == pytest.approx((k_peak - 20) * DT)


def test_fates_and_precursors_with_their_arrest_lengths():
    it, arr = _record()
    run = Run.from_arrays(it, scene={"load.FN": 1.0})
    fr = run.fronts()
    got = {(round(f.nucleation_time / DT), FR.fate(run, f)) for f in fr}
    assert got == {(20, "arrested"), (90, "arrested"), (40, "arrested"), (140, "edge"), (200, "crossed"),
                   (385, "running")}
    pre = FR.precursors(run)
    assert [(round(p.nucleation_time / DT), p.kind) for p in pre] == [(20, "pulse"), (40, "pulse"), (90, "pulse")]
    x = it["x"]
    for p, sites, tip, last in zip(pre, (10, 12, 25), (9, NS - 12, 24), (arr["p1"], arr["p3"], arr["p2"])):
        assert p.arrest_length == pytest.approx(sites / NS, rel=1e-12)
        assert p.arrest_x == x[tip] and p.arrest_time == pytest.approx(last[-1] * DT)
        assert fr[p.index].nucleation_time == p.nucleation_time
    obs = FR.observables(run)
    assert (obs["n_fronts"], obs["n_precursors"], obs["n_crossed"], obs["n_running"]) == (6, 3, 1, 1)
    assert obs["rupture_kind"] == "crack" and obs["n_crack"] == 1 and obs["n_pulse"] == 5
    assert obs["precursor_arrest_max"] == pytest.approx(25 / NS)
    assert obs["precursor_arrest_mean"] == pytest.approx((10 + 12 + 25) / 3 / NS)
    assert obs["front_speed"] == pytest.approx((1 / NS) / DT)          # the crack: one site per frame
    assert obs["mu_s"] == pytest.approx(2.0) and obs["mu_s_place"] == "after"


def test_a_pulse_finished_by_an_edge_burst_was_relayed_and_the_burst_merged():
    """As under pull: a slow pulse from x = 1 reaches site 6 at frame 169 while the last six bonds at
    x = 0 break from the edge toward it (frames 166-171).  The detector sees two fronts; the pulse was
    relayed (its own tip stopped, the rest of the contact broke as it arrived: the contact was crossed,
    and it counts as the crossing front), the burst ran into the pulse: neither is a precursor."""
    it = blank(400)
    draw(it, 10, NS - 1, -1, 3, 2, 0.001, sites=NS - 6)
    draw(it, 166, 0, +1, 1, 1, 0.001, sites=6, crack=True)
    it["intact"][200:] = 1
    it["mu"] = np.zeros(400)
    run = Run.from_arrays(it)
    fr = run.fronts()
    assert [(f.direction, f.sites) for f in fr] == [(-1, NS - 6), (1, 6)]
    assert [f.fate for f in fr] == ["relayed", "merged"]
    assert [FR.crossed_contact(run, f) for f in fr] == [True, False]
    assert FR.precursors(run) == []
    obs = FR.observables(run)
    assert obs["rupture_kind"] == "pulse" and obs["n_crossed"] == 1 and FR.slip_onset(run) == 171


def test_a_front_still_moving_when_the_record_ends_is_not_a_precursor():
    """The same pulse, stopping at site 18 at frame 94: in a record of 100 frames it may still be moving;
    in one of 200, quiet for 5 l/c_r after it stopped, it arrested (the detector's patience is 3 l/c_r)."""
    for nf, want in ((100, "running"), (200, "arrested")):
        it = blank(nf)
        draw(it, 40, 0, +1, 3, 2, 0.0, sites=19)
        run = Run.from_arrays(it)
        (f,) = run.fronts()
        assert f.fate == want
        pre = FR.precursors(run)
        assert len(pre) == (want == "arrested")
        if pre:
            assert pre[0].arrest_length == pytest.approx(19 / NS) and pre[0].arrest_time == pytest.approx(94 * DT)


def test_the_run_object_exposes_the_friction_record():
    it, _ = _record()
    run = Run.from_arrays(it, scene={"load.FN": 0.5, "drive.mode": "push", "drive.v0": 0.01})
    assert run.mu is it["mu"] and run.mu_s == pytest.approx(2.0)
    assert run.static_peak.force == pytest.approx(1.0) and run.slip_onset == pytest.approx(229 * DT)
    assert run.fates() == ["arrested", "arrested", "arrested", "edge", "crossed", "running"]
    assert [p.index for p in run.precursors()] == [0, 1, 2]
    assert run.observables()["n_precursors"] == 3
    with pytest.raises(parslip.ConfigError, match="friction_force"):
        run.friction_force                                               # drawn without forces: one line


# ------------------------------------------------------------------------------------ a real short run --

def test_real_run_friction_record(small_run):
    """The SMALL push run: mu = -F_T/F_N in the file; mu_s is the largest mu up to the slip onset, the first
    frame by which every bond (but the edges') has broken once (on this coarse lattice a bond can break
    and re-form between two frames, so that is not always the first crossing's end); the peak comes after
    the first break (slow pulses)."""
    run = parslip.open(small_run)
    fn = run.scene["load.FN"]
    np.testing.assert_array_equal(run.mu, -run.friction_force / fn)
    pk = run.static_peak
    assert pk.window == "slip onset" and pk.slip_onset is not None
    k = run.frame_at(pk.slip_onset)
    assert pk.mu_s == run.mu[:k + 1].max() and pk.mu_s > run.mu[0]
    first = run.fronts()[0]
    assert run.fates()[0] == "crossed" and first.t_end <= pk.slip_onset <= run.times[-1]
    broken = np.maximum.accumulate(run.interface["intact"] == 0, axis=0)         # broken once by then
    inner = slice(1, broken.shape[1] - 1)                                         # 2 % of 24 sites: one a side
    assert broken[k, inner].all() and not broken[k - 1, inner].all()
    assert pk.first_break_time == pytest.approx(first.nucleation_time)
    assert pk.place == "after" and pk.after_first_break > 0


def test_fronts_command_prints_the_friction_record(small_run, capsys):
    assert main(["fronts", small_run]) == 0
    text = capsys.readouterr().out
    assert "fate" in text and "crossed" in text and "static peak mu_s = " in text and "slip onset" in text
    assert main(["fronts", small_run, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    run = parslip.open(small_run)
    assert out["static_peak"]["mu_s"] == pytest.approx(run.mu_s)
    assert out["static_peak"]["place"] == run.static_peak.place
    assert [f["fate"] for f in out["fronts"]] == run.fates()
    assert out["precursors"] == [p.to_dict() for p in run.precursors()]
    assert out["first_break"]["time"] == pytest.approx(run.first_break[0])


def test_friction_figure_is_written(small_run, tmp_path):
    assert main(["figures", small_run, "-o", str(tmp_path), "--only", "friction"]) == 0
    png = tmp_path / "friction.png"
    assert png.stat().st_size > 10_000 and (tmp_path / "friction.pdf").exists()


def test_a_record_without_forces_gets_no_friction_figure(tmp_path):
    from parslip.plot import figures
    run = Run.from_arrays(blank(20), {"drive.mode": "push", "drive.v0": 0.01})
    assert figures.fig_friction(run, str(tmp_path)) == [] and not list(tmp_path.iterdir())


def test_slip_events_are_the_drops_of_mu_with_the_precursors_before_them():
    """The drawn record: mu rises to 2.0 at frame 200 and falls to 0.5 at frame 259 (a drop of 75 % of the
    largest mu, 3.5), then rises to the end: one slip event, from frame 200 to 259, preceded by the three
    precursors (arrested at frames before 200) with their arrest lengths and mu at their arrests.  A
    threshold above the drop finds none; a record that falls at its end holds an open event."""
    it, arr = _record()
    it["loader"] = np.arange(400) * 1e-3
    run = Run.from_arrays(it)
    ev = FR.slip_events(run)
    assert len(ev) == 1
    e = ev[0]
    assert (round(e.t_start / DT), round(e.t_end / DT)) == (200, 259)
    assert (e.mu_before, e.mu_after) == (pytest.approx(2.0), pytest.approx(0.5)) and e.drop == pytest.approx(1.5)
    assert e.loader == pytest.approx(0.2)
    pre = FR.precursors(run)
    assert e.precursors == [p.index for p in pre] and len(pre) == 3
    assert e.precursor_lengths == pytest.approx([p.arrest_length for p in pre])
    assert e.precursor_mu == pytest.approx([0.01 * round(p.arrest_time / DT) for p in pre])
    assert FR.slip_events(run, min_drop=0.45) == []               # 1.5 < 0.45 * 3.5
    it2 = {k: (v[:240] if isinstance(v, np.ndarray) and v.shape[:1] == (400,) else v) for k, v in it.items()}
    open_ev = FR.slip_events(Run.from_arrays(it2))
    assert len(open_ev) == 1 and round(open_ev[0].t_end / DT) == 239     # still falling when the record ends


def test_fronts_command_lists_the_slip_events(small_run, capsys):
    assert main(["fronts", small_run, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    run = parslip.open(small_run)
    assert out["slip_events"] == [e.to_dict() for e in run.slip_events()]
    assert main(["fronts", small_run]) == 0
    assert "slip event" in capsys.readouterr().out
    assert main(["figures", small_run, "-o", str(pathlib.Path(small_run).parent / "ss"), "--only", "stick_slip"]) == 0


def test_sinking_is_the_deepest_site_below_its_start_in_lattice_spacings():
    """A drawn record of 4 sites on l = 40 a: one site sinks at 0.5 a per frame, one rises; the depth per
    frame is the sinking site's, in a, and a record where every site rises stays negative."""
    t = np.arange(5.0)
    uy = np.zeros((5, 4)) + 0.01                             # a common offset: heights count from the start
    uy[:, 1] -= 0.5 * t / 40                                # 0.5 a per frame, in l
    uy[:, 3] += 2.0 * t / 40
    run = Run.from_arrays({"time": t, "uy": uy, "x": np.arange(4) / 4}, scene={"lattice.top_cols": 40})
    assert np.allclose(FR.sinking(run), 0.5 * t, rtol=0, atol=1e-12)
    up = Run.from_arrays({"time": t, "uy": 0.01 + np.outer(t, [1, 2, 3, 4]) / 40, "x": np.arange(4) / 4},
                         scene={"lattice.top_cols": 40})
    assert np.allclose(FR.sinking(up)[1:], -t[1:], rtol=0, atol=1e-12)
