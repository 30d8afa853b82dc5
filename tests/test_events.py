"""The exact event record (/interface/events) and the fronts read off it.

Checked against independent computations: the frames' own bond state (replaying the events from the
initial state must give every frame's ``intact`` and ``partner``), the engine's event counters, the
1-rank run on 3 ranks with an event buffer that fills at almost every agreement, and, for the fronts,
event records written by hand whose tip speeds are known exactly.
"""
import importlib

import numpy as np
import pytest

import parslip
from helpers import SMALL, blank, datasets, require, run_cli, small_toml
F = importlib.import_module("parslip.analysis.fronts")
from parslip.io.contract import EVENT_BREAK, EVENT_FORM

MODES = ("push", "pull", "shear")
# Shear breaks late: drive it faster so that the SMALL run sees its rupture.
DRIVE = {"push": {}, "pull": {}, "shear": {"drive.v0": 0.05, "drive.duration": 8.0}}


@pytest.fixture(scope="module")
def mode_runs(tmp_path_factory):
    """SMALL runs of the three drives on one rank, in-process: {mode: (Run, outcome counters)}."""
    d = tmp_path_factory.mktemp("events")
    out = {}
    for mode in MODES:
        sets = {**SMALL, "drive.mode": mode, "output.snapshots": 0, **DRIVE[mode]}
        r = parslip.run(sets, out=str(d / f"{mode}.vtkhdf"), progress=False)
        out[mode] = (parslip.open(str(d / f"{mode}.vtkhdf")), r.outcome.counters)
    return out


@pytest.mark.parametrize("mode", MODES)
def test_replaying_the_events_gives_every_frame(mode_runs, mode):
    """From the initial state (site s bonded to column site_column0 + s), the events before each frame's
    step give that frame's intact and partner, for every frame of the run."""
    run, _ = mode_runs[mode]
    ev = run.events
    assert (ev["kind"] == EVENT_BREAK).sum() > 10 and (ev["kind"] == EVENT_FORM).sum() > 0
    intact, partner = run.replay()
    np.testing.assert_array_equal(intact, run.interface["intact"])
    np.testing.assert_array_equal(partner, run.interface["partner"])


@pytest.mark.parametrize("mode", MODES)
def test_events_are_sorted_counted_and_timed_as_the_frames(mode_runs, mode):
    run, counters = mode_runs[mode]
    ev = run.events
    key = np.stack([ev["step"], ev["site"], ev["kind"]])
    order = np.lexsort(key[::-1])
    assert np.array_equal(order, np.arange(len(order)))                    # by step, site, then kind
    same = (np.diff(ev["step"]) == 0) & (np.diff(ev["site"]) == 0)
    assert (ev["kind"][:-1][same] == EVENT_BREAK).all()                   # a break before a re-formation
    assert ((ev["kind"] == EVENT_BREAK).sum(), (ev["kind"] == EVENT_FORM).sum()) == tuple(counters)
    # A site alternates: it breaks while bonded and re-forms while broken.
    for s in np.unique(ev["site"]):
        k = ev["kind"][ev["site"] == s]
        assert (k[::2] == EVENT_BREAK).all() and (k[1::2] == EVENT_FORM).all()
    # Time is computed from the step as the frames' time is: equal bits where a frame has the same step.
    common, i_ev, i_fr = np.intersect1d(ev["step"], run.interface["step"], return_indices=True)
    assert len(common) > 0
    np.testing.assert_array_equal(ev["time"][i_ev], run.times[i_fr])
    assert ev["dt"] == pytest.approx(run.attrs["dt"] * run.attrs["c_r"] / run.attrs["l"])
    assert (np.diff(run.interface["step"]) > 0).all()
    np.testing.assert_allclose(run.times, run.interface["step"] * ev["dt"], rtol=1e-12)


def test_events_cover_every_phase(mode_runs):
    """Under load and while it settles the interface already moves: events before the drive carry negative
    steps, and the drive's own start at step 0."""
    run, _ = mode_runs["push"]
    steps = run.events["step"]
    n_before = int(round((run.scene["load.ramp"] + run.scene["load.settle"]) * run.attrs["l"] / run.attrs["c_r"]
                         / run.attrs["dt"]))
    assert steps.min() >= -n_before - 1
    assert run.interface["step"][0] == 0


def test_events_identical_on_1_and_3_ranks_with_a_buffer_that_fills(tmp_path):
    """On 3 ranks, with output.buffer_events = 2 the ranks agree to write their events out at nearly every
    agreement (some rank holds more than 2): the record must still be the 1-rank run's, bit for bit."""
    require("gather")
    files = {}
    for n, sets in ((1, ()), (3, ("--set", "output.buffer_events=2"))):
        sc = tmp_path / f"s{n}.toml"
        sc.write_text(small_toml(**{"drive.duration": 8.0, "output.snapshots": 0}))
        out = tmp_path / f"r{n}.vtkhdf"
        p = run_cli(n, "run", sc, "--out", out, "--no-png", "--quiet", "--watchdog", "30", *sets, timeout=150)
        assert p.returncode == 0, p.stderr
        files[n] = datasets(out)[0]
    ev = {n: {k: v for k, v in d.items() if k.startswith("interface/")} for n, d in files.items()}
    assert ev[1].keys() == ev[3].keys() and len(ev[1]["interface/events/step"]) > 100
    for name in ev[1]:
        assert ev[1][name].tobytes() == ev[3][name].tobytes(), name


# ---------------------------------------------------------------------- fronts from hand-made events --

L_SITES = 200
DT = 1e-3           # l/c_r per step


def _record(breaks, n_sites=L_SITES, frames=50, t_end=None):
    """An interface record with events: ``breaks`` [(step, site)], each bond staying broken."""
    steps = np.array([b[0] for b in breaks], np.int64)
    sites = np.array([b[1] for b in breaks], np.int32)
    order = np.lexsort((sites, steps))
    steps, sites = steps[order], sites[order]
    iface = blank(frames)
    t_end = t_end or (steps.max() + 10) * DT
    iface["t"] = iface["time"] = np.linspace(0, t_end, frames)
    iface["step"] = np.round(iface["t"] / DT).astype(np.int64)
    iface["x"] = (np.arange(n_sites) + 0.5) / n_sites
    iface["intact"] = np.ones((frames, n_sites), np.uint8)
    for k, s in enumerate(iface["step"]):
        iface["intact"][k, sites[steps < s]] = 0
    iface.pop("ux", None), iface.pop("uy", None)
    iface["events"] = {"step": steps, "time": steps * DT, "site": sites,
                       "kind": np.full(len(steps), EVENT_BREAK, np.uint8), "partner": sites.copy(),
                       "site_column0": 0, "dt": DT, "c_s": 1.1, "c_l": 1.8}
    return iface


def test_a_front_at_a_known_speed_is_measured_to_the_time_step():
    """A tip that reaches site s at step round(s dx / (v dt)): every local fit over 5 sites gives v to
    within the step's rounding, while the frames (every 1/50 of the run) cannot resolve it."""
    v, dx = 0.37, 1.0 / L_SITES
    iface = _record([(int(round(s * dx / (v * DT))), s) for s in range(20, 180)])
    (f,) = F.fronts(iface)
    assert f.direction == 1 and f.resolution == DT and f.fit_sites == 5
    assert f.steady_speed == pytest.approx(v, rel=2e-3)
    assert np.abs(f.tip["v"] - v).max() < 0.02 * v
    assert f.nucleation_time == pytest.approx(20 * dx / v, abs=DT)
    assert not f.supershear and not f.bursts


def test_supershear_is_flagged_and_a_burst_is_no_speed():
    """A front that runs at 0.5 c_r, then at 1.5 c_r (between c_s = 1.1 and c_l = 1.8) over sites 100-139,
    then breaks 10 sites in one step: the fast stretch is flagged supershear with its sites and speed; the
    burst is reported with its sites and steps and enters no speed."""
    dx = 1.0 / L_SITES
    t, breaks = 0.0, []
    for s in range(10, 140):
        breaks.append((int(round(t / DT)), s))
        t += dx / (0.5 if s < 100 else 1.5)
    burst_step = int(round(t / DT))
    breaks += [(burst_step, s) for s in range(140, 150)]
    t += 40 * DT
    for s in range(150, 170):
        breaks.append((int(round(t / DT)), s))
        t += dx / 0.5
    (f,) = F.fronts(_record(breaks))
    (ss,) = [b for b in f.supershear if b["sites"][0] <= 120 <= b["sites"][1]]
    assert ss["max_speed"] == pytest.approx(1.5, rel=0.05) and ss["n_sites"] >= 20
    assert f.bursts and all(136 <= b["sites"][0] and b["sites"][1] <= 153 for b in f.bursts)   # fits that hold it
    assert any(b["n_steps"] <= 2 for b in f.bursts)
    assert np.nanmax(np.abs(f.tip["v"])) < 1.8 and abs(f.max_speed) < 1.8
    text = F.table([f])
    assert "supershear" in text and "burst" in text and "exact break steps" in text


def test_event_and_frame_catalogues_agree_on_a_real_run(small_run):
    """The SMALL push run: the same fronts from the events as from the frames, each nucleating within one
    frame of the other; the events' tips never outrun c_l."""
    run = parslip.open(small_run)
    ev_fr = run.fronts()
    frame_fr = F.fronts({**run.interface, "events": None})
    assert len(ev_fr) == len(frame_fr) >= 3
    dt_frame = float(np.median(np.diff(run.times)))
    for a, b in zip(ev_fr, frame_fr):
        assert a.direction == b.direction and abs(a.nucleation_x - b.nucleation_x) < 1e-9
        assert b.nucleation_time - dt_frame <= a.nucleation_time <= b.nucleation_time + 1e-12
        assert abs(a.max_speed) < run.events["c_l"]


def test_event_energy_and_traction_are_those_of_the_bond_at_its_step():
    """Each event's energy and traction, recomputed in NumPy from u(n) of its step and the bond it left
    (break) or formed (re-formation, with the rest offset it took): 1/2 k_x (x_ij - x0)^2 + 1/2 k_y
    (y_ij - delta0)^2 in m c_r^2, and k_x (x_ij - x0)/(a rho c_r^2)."""
    from helpers import simulation
    from parslip.engine import loop as L
    from parslip.model.interface import KX, KY, X0
    from parslip.model.physics import DENSITY
    sim = simulation(SMALL, **{"drive.mode": "shear", "drive.v0": 0.05, "output.snapshots": 0})
    st, s = sim.setup, sim.state
    it, g, fr = s.iface, s.iface.geom, sim.frames
    c_r = st.material.c_r
    sim.run(until=st.n_drive_start)
    checked = {EVENT_BREAK: 0, EVENT_FORM: 0}
    for _ in range(st.n_drive):
        n = sim.n
        sim.advance(n + 1)                          # the loop alone: its event record stays for us to read
        fr.cursor[L.C_BASE] += fr.cursor[L.C_COUNT]
        fr.cursor[L.C_COUNT] = 0
        ev, m = it.events, int(it.events.count[0])
        bx, by, tx, ty = (a.astype(float) for a in s.level(n))
        for e in range(m):
            if (ev.site[:m] == ev.site[e]).sum() > 1:
                continue                            # broke and re-formed in one step: the old x0 is gone
            j = int(ev.site[e]) + g.tfirst - g.tbase
            q = int(ev.partner[e])
            i = q - g.bbase
            sx = (j + g.tbase - q) + (tx[1, j] - bx[g.brow, i]) - it.bonds[X0, j]
            sy = ty[1, j] - by[g.brow, i]              # y_ij - delta0
            kx, ky = it.bonds[KX, j], it.bonds[KY, j]
            assert ev.energy[e] == pytest.approx((0.5 * kx * sx ** 2 + 0.5 * ky * sy ** 2) / c_r ** 2, rel=1e-9)
            assert ev.traction[e] == pytest.approx(kx * sx / (DENSITY * c_r ** 2), rel=1e-9, abs=1e-15)
            checked[int(ev.kind[e])] += 1
        it.events.count[0] = 0
    assert checked[EVENT_BREAK] > 10 and checked[EVENT_FORM] > 10, checked
