"""The paper's claims: the table's shape, the verdict logic, tolerances fixed before measurement, and each
measurement on drawn interface records whose answer is known beforehand."""
import dataclasses
import math

import numpy as np
import pytest

from helpers import DT, NS, blank, draw
from parslip.studies.paper import claims as cl
from parslip.studies.paper import measures as m
from parslip.analysis.fronts import crack_speed, crossing_time, first_break_frame, peak_speed, section_width
from parslip.analysis.slip import front_slip, passage_slip, peak_slip_velocity, slip_share_in_passages
from parslip.analysis.results import Run

DX = 1 / NS


def as_run(iface, mode="push", v0=1e-3, **scene):
    return Run.from_arrays(iface, {"drive.mode": mode, "drive.v0": v0, **scene})


def pulses(k0s, d, fps, width=2, slip=0.01, nf=1000, mode="push", v0=1e-3, crack=False):
    iface = blank(nf)
    for k0 in k0s:
        draw(iface, k0, 0 if d > 0 else NS - 1, d, fps, width, slip, crack=crack)
    return as_run(iface, mode, v0)


@pytest.fixture(scope="module")
def runs():
    k0s = [100, 300, 500, 700]                           # 5, 15, 25, 35 l/c_r
    return {
        "push": pulses(k0s, +1, 2),
        "pull": pulses(k0s, -1, 4, mode="pull"),         # half the speed
        "shear": pulses([1300], +1, 1, slip=0.008, nf=1400, mode="shear", v0=1e-4, crack=True),
        "push_v0_1e-2": pulses(k0s, +1, 1, v0=2e-3),     # twice v0, twice the speed
    }


# --- the table --------------------------------------------------------------------------

def test_claims_table_shape():
    from parslip.studies.paper.study import ORDER
    assert len(cl.CLAIMS) >= 35
    keys = [c.key for c in cl.CLAIMS]
    assert len(set(keys)) == len(keys)
    for c in cl.CLAIMS:
        assert c.claim and c.paper and c.units, c.key
        assert c.source.split()[0] in ("Sec.", "App.", "Fig."), c.key
        assert "\"" in c.source or ":" in c.source, c.key          # a short quote or the numbers it gives
        assert set(c.needs) <= set(ORDER), c.key
        assert c.accept.why, c.key                                   # every tolerance says why
    # the items the issue lists are all there
    for k in ("shear_crossing", "shear_later_speed", "push_same_speed", "shear_syy_edge", "push_mode2_first",
              "push_mode2_later", "push_udot_mid", "push_udot_far", "shear_sharp", "push_width_jump",
              "pull_secondary", "l300_push", "l300_pull", "l300_shear", "l500_crack", "l500_uneven", "slip_ratio",
              "shear_crack"):
        assert k in keys, k


def test_rows_have_the_keys_and_missing_runs_are_not_measured(runs):
    rows = cl.evaluate(runs)
    assert len(rows) == len(cl.CLAIMS)
    for r in rows:
        assert set(r) == {"key", "claim", "source", "paper", "parslip", "value", "units", "tolerance", "verdict"}
        assert r["verdict"] in cl.VERDICTS
    by = {r["key"]: r for r in rows}
    assert by["push_v0"]["verdict"] == cl.NOT_MEASURED and "push_v0_1e-4" in by["push_v0"]["parslip"]
    assert by["l500_crack"]["verdict"] == cl.NOT_MEASURED
    assert by["push_first"]["value"] == pytest.approx(5.0) and by["push_first"]["verdict"] == cl.AGREES
    assert by["pull_push_speed"]["value"] == pytest.approx(0.5) and by["pull_push_speed"]["verdict"] == cl.AGREES
    assert by["shear_first"]["value"] == pytest.approx(65.0) and by["shear_first"]["verdict"] == cl.AGREES
    # not measured counts against the share
    c = cl.counts(rows)
    assert cl.share_agreeing(rows) == pytest.approx(c[cl.AGREES] / len(rows))
    assert c[cl.NOT_MEASURED] > 0 and cl.share_agreeing(rows) < c[cl.AGREES] / (len(rows) - c[cl.NOT_MEASURED])
    md = cl.to_markdown(rows, "t")
    assert md.count("\n| ") == len(rows) + 2 and f"of {len(rows)} claims agree" in md
    import json
    js = json.loads(cl.to_json(rows, reading={}))
    assert len(js["claims"]) == len(rows) and js["share_agreeing"] == pytest.approx(cl.share_agreeing(rows))


def test_tolerances_are_fixed_before_measurement(runs):
    """A claim's tolerance is a frozen object built with the claim: the same text whatever the runs say,
    and no measurement can change it."""
    c = cl.CLAIMS[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.accept.lo = 0.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.accept = cl.at_least(0)
    before = [cc.tolerance for cc in cl.CLAIMS]
    a = {r["key"]: r["tolerance"] for r in cl.evaluate(runs)}
    b = {r["key"]: r["tolerance"] for r in cl.evaluate({"push": runs["pull"], "shear": runs["push"]})}
    assert a == b == {cc.key: t for cc, t in zip(cl.CLAIMS, before)}


@pytest.mark.parametrize("accept, value, verdict", [
    (cl.near(5.1, rel=0.03), 5.2, cl.AGREES),
    (cl.near(5.1, rel=0.03), 5.3, cl.DISAGREES),
    (cl.near((15.1, 25.2), abs=1.0), [15.5, 24.3], cl.AGREES),
    (cl.near((15.1, 25.2), abs=1.0), [15.5, 24.1], cl.DISAGREES),
    (cl.near((15.1, 25.2), abs=1.0), [15.5], cl.DISAGREES),          # a missing nucleation
    (cl.near((15.1, 25.2), abs=1.0), [], cl.NOT_MEASURED),
    (cl.between(0.65, 0.85), 0.85, cl.AGREES),
    (cl.between(0.65, 0.85), 0.86, cl.DISAGREES),
    (cl.at_least(1.0), 1.0, cl.AGREES),
    (cl.at_least(1.0), 0.99, cl.DISAGREES),
    (cl.at_most(0.1), math.nan, cl.NOT_MEASURED),
    (cl.at_most(0.1), None, cl.NOT_MEASURED),
    (cl.at_most(0.1), math.inf, cl.NOT_MEASURED),
    (cl.between(3, 3), 3, cl.AGREES),
    (cl.between(3, 3), 2, cl.DISAGREES),
])
def test_verdict_logic(accept, value, verdict):
    assert cl.verdict(accept, value) == verdict


def test_tolerance_texts():
    assert cl.near(5.1, rel=0.03).text == "within 3% of 5.1"
    assert cl.near((1, 2), abs=1.0).text == "each within 1 of 1, 2"
    assert cl.between(3, 3).text == "exactly 3"
    assert cl.at_least(2.0).text == ">= 2" and cl.at_most(0.1).text == "<= 0.1"


def test_a_failing_measurement_is_not_measured(runs):
    bad = cl.Claim("x", "x", "Sec. 1: \"x\"", "1", "-", cl.at_least(1, why="w"), ("push",),
                   lambda r: [][0])
    (row,) = cl.evaluate(runs, [bad])
    assert row["verdict"] == cl.NOT_MEASURED and row["parslip"].startswith("IndexError")


# --- measurements on drawn records --------------------------------------------------------

def test_nucleations_speeds_and_intervals(runs):
    push, pull = runs["push"], runs["pull"]
    assert m.nucleation_times(push) == pytest.approx([5, 15, 25, 35])
    assert m.nucleation_time(push, 5) != m.nucleation_time(push, 5)          # NaN: no sixth
    assert m.interval(push) == pytest.approx(10) and m.interval_spread(push) == pytest.approx(0)
    assert m.nucleation_site(push) == pytest.approx(0.5 / NS) and m.nucleation_site(pull) == pytest.approx(1 - 0.5 / NS)
    assert m.directions(push) == 1.0 and m.directions(pull) == 1.0
    assert m.pulse_share(push) == 1.0 and m.pulse_share(runs["shear"]) == 0.0
    assert m.mean_steady_speed(push) == pytest.approx(DX / (2 * DT))
    assert m.speed_spread(push) == pytest.approx(1.0) and m.speed_constancy(push) == pytest.approx(0.0)
    assert m.speed_ratio(pull, push) == pytest.approx(0.5)
    assert m.v_over_v0_spread([runs["push_v0_1e-2"], push]) == pytest.approx(1.0)
    assert m.v_over_v0_spread([runs["push_v0_1e-2"], pulses([100], +1, 2, v0=2e-3)]) == pytest.approx(2.0)


def test_speed_spread_of_unequal_pulses():
    iface = blank(1400)
    for k0, fps in ((100, 2), (300, 2), (500, 3), (700, 2)):
        draw(iface, k0, 0, +1, fps, 2, 0.01)
    assert m.speed_spread(as_run(iface)) == pytest.approx(1.5)


def test_acceleration_of_the_leading_pulse_and_its_followers():
    """A leading pulse at 1 site per 4 frames that speeds up to 1 per frame from site 45 (x = 0.758): its
    5-site local speed first exceeds twice the early one there; a follower that, from that frame on, speeds
    up from 1 site per 4 frames to 1 per 2."""
    nf = 700
    iface = blank(nf)
    it = iface["intact"]
    arr1 = [10 + 4 * j for j in range(45)] + [10 + 4 * 44 + j for j in range(1, 16)]     # leading
    ta = arr1[45]
    arr2 = []
    k = 60
    for j in range(60):
        arr2.append(k)
        k += 4 if k < ta else 2
    for arr in (arr1, arr2):
        for j, k0 in enumerate(arr):
            it[k0:k0 + 6, j] = 0                          # broken for 6 frames from the tip's arrival
    run = as_run(iface)
    assert m.accel_x(run) == pytest.approx(iface["x"][45])
    assert m.leading_accel_time(run) == pytest.approx(ta * DT)
    assert m.trailing_speedup(run, window=1.0) == pytest.approx(2.0)
    assert m.max_speed_near_far_edge(run) == pytest.approx(DX / DT, rel=0.01)


def test_widths():
    """Width 3 all the way (no variation, no widening, no jump); then one widened to 6 past 0.85 l."""
    iface = blank(1000)
    for k0 in (100, 300):
        draw(iface, k0, 0, +1, 2, 3, 0.01)
    run = as_run(iface)
    assert m.steady_width(run) == 3 and m.width_variation(run) == 0 and m.far_edge_widening(run) == 0
    iface = blank(1000)
    for k0 in (100, 300):
        draw(iface, k0, 0, +1, 2, 3, 0.01)
    it = iface["intact"]
    for k0 in (100, 300):
        for j in range(52, NS):                             # x > 0.85: three more sites broken behind the tip
            k = k0 + 2 * j
            it[k:k + 2, j - 5:j - 2] = 0
    assert m.far_edge_widening(as_run(iface)) == 3


def test_width_jump_of_the_trailing_pulse():
    """The leading pulse accelerates near site 47; the trailing one is 2 wide before that moment, 5 after."""
    nf = 600
    iface = blank(nf)
    it = iface["intact"]
    for j in range(NS):
        k = 10 + 4 * j if j <= 47 else 10 + 4 * 47 + (j - 47)
        it[k:k + 4, j] = 0
    ta = int(round(m.leading_accel_time(as_run(iface)) / DT))
    assert 10 + 4 * 44 <= ta <= 10 + 4 * 47 + 1
    for j in range(NS):
        k = 150 + 2 * j
        w = 2 if k <= ta else 5
        it[k:k + 2, max(0, j - w + 1):j + 1] = 0
    run = as_run(iface)
    assert m.leading_accel_time(run) == pytest.approx(ta * DT)
    assert m.width_jump(run, window=1.0) == 3


def test_live_pulses_and_secondary_fronts():
    iface = blank(1000)
    for k0 in (100, 300, 500, 700):                       # each takes 60 x 4 = 240 frames (12 l/c_r) to cross
        draw(iface, k0, NS - 1, -1, 4, 2, 0.01)
    run = as_run(iface, mode="pull")
    assert m.live_pulses(run, 35.1) == 2                   # the fourth and the third (born 25, leaves 36.8)
    assert m.live_pulses(run, 16.0) == 2 and m.live_pulses(run, 17.0) == 1 and m.live_pulses(run, 4.0) == 0
    assert m.secondary_fronts(run) == 0
    draw(iface, 850, 6, +1, 2, 2, 0.0, sites=5)           # born at x = 0.108, toward the driven edge
    assert m.secondary_fronts(as_run(iface, mode="pull")) == 1
    iface2 = blank(1000)
    for k0 in (100, 150, 200):                             # slow pulses: 60 x 10 frames to cross
        draw(iface2, k0, 0, +1, 10, 2, 0.01)
    assert m.live_pulses(as_run(iface2), 12.0) == 3


def test_crack_crossing_rebond_and_unevenness():
    """A crack at 1 site per frame from frame 100 (crosses 57 sites = 0.95 l in 57 frames); every site
    re-bonds 10 frames after the tip's last arrival, except sites 20-24, which take 40 frames more."""
    nf = 400
    iface = blank(nf)
    draw(iface, 100, 0, +1, 1, NS, 0.008, crack=True)
    it = iface["intact"]
    end = 100 + NS - 1
    for s in range(NS):
        back = end + 10 + (40 if 20 <= s <= 24 else 0)
        it[back:, s] = 1
    run = as_run(iface, mode="shear", v0=1e-4)
    assert crossing_time(run) == pytest.approx(57 * DT)
    assert m.rebond_after_crossing(run) == pytest.approx(10 * DT)
    assert m.broken_share_at_crossing(run) == 1.0
    # detachment per site: (end + 10 - (100 + s)) frames, 40 more at 20-24; the median site is 29.5 frames
    d = np.array([end + 10 - (100 + s) + (40 if 20 <= s <= 24 else 0) for s in range(NS)])
    assert m.rebond_unevenness(run) == pytest.approx(d.max() / np.median(d))
    assert crack_speed(run) == pytest.approx(DX / DT) and peak_speed(run) == pytest.approx(DX / DT)
    pulse = pulses([100], +1, 1, width=3, nf=400)
    assert m.rebond_after_crossing(pulse) < 0


def test_front_slip_is_bounded_by_the_neighbouring_fronts_not_the_record():
    """Three cracks carrying 0.008 l each over a record that creeps 1e-4 l per frame everywhere.  The
    middle front's slip is its own jump plus the creep between the midpoints to its neighbours' passages;
    the last front, whose window would run to the end of the record, is not used (the T0 artefact: a lone
    front's slip grew with the run's length); the jump while a front passes excludes the creep."""
    nf = 1400
    iface = blank(nf)
    for k0 in (100, 500, 900):
        draw(iface, k0, 0, +1, 1, NS, 0.008, crack=True)
    it = iface["intact"]
    it[:] = 1
    for k0 in (100, 500, 900):
        for s in range(NS):
            it[k0 + s:k0 + NS + 5, s] = 0                      # broken from the tip's arrival to 5 frames past
    creep = 1e-4 * np.arange(nf)[:, None]
    iface["ux"] += creep
    run = as_run(iface, mode="shear", v0=1e-4)
    assert len(run.fronts()) == 3
    s = 30
    a1, a2, a3 = 100 + s, 500 + s, 900 + s
    expect = 0.008 + 1e-4 * ((a2 + a3) // 2 - (a1 + a2) // 2)
    assert run.fronts()[1].tip["du"][s] == pytest.approx(expect)
    assert front_slip(run, 1) == pytest.approx(0.008 + 1e-4 * 400, rel=0.01)
    assert math.isnan(front_slip(run, 2))
    assert m.median_front_slip(run, 3) == pytest.approx(front_slip(run, 1))
    jump = passage_slip(run, 1)
    assert 0.008 < jump < 0.008 + 1e-4 * (NS + 5 + 10)


def test_slip_per_pulse_first_excess_and_spread():
    iface = blank(1400)
    for i, k0 in enumerate((100, 300, 500, 700, 900, 1100)):
        draw(iface, k0, 0, +1, 2, 2, 0.015 if i == 0 else 0.01)
    run = as_run(iface)
    assert front_slip(run, 1) == pytest.approx(0.01)
    assert m.first_front_excess(run) == pytest.approx(1.5)
    assert m.slip_spread(run) == pytest.approx(0.0, abs=1e-12)
    assert m.median_front_slip(run) == pytest.approx(0.01)


def test_slip_share_in_passages_and_slip_velocity_contrast():
    """Pulses carry 0.01 l each (added when a site re-bonds); between them a creep of 1e-4 l per frame: at
    the middle site the share of slip in passages is the pulses' plus the creep inside the windows."""
    nf = 1000
    iface = blank(nf)
    for k0 in (100, 300, 500, 700):
        draw(iface, k0, 0, +1, 2, 2, 0.01)
    run = as_run(iface)
    assert slip_share_in_passages(run, 0.5) == pytest.approx(1.0)
    assert m.passage_contrast(run, 0.35) == math.inf             # no slip at all outside the passages
    iface["ux"] += 1e-5 * np.arange(nf)[:, None]
    run = as_run(iface)
    s = int(np.argmin(np.abs(iface["x"] - 0.5)))
    total = iface["ux"][-1, s] - iface["ux"][0, s]
    share = slip_share_in_passages(run, 0.5)
    assert 0.04 / total < share < 1.0
    assert m.passage_contrast(run, 0.35) > 3


def test_slip_velocity_peaks_and_stationary_far_edge():
    nf = 1400
    iface = blank(nf)
    draw(iface, 1300, 0, +1, 1, NS, 0.008, crack=True)
    run = as_run(iface, mode="shear", v0=1e-4)
    assert m.sharp_peaks(run) == math.inf                        # the record is flat but for the jumps
    assert peak_slip_velocity(run, 0.35) == pytest.approx(0.008 / (2 * DT))   # central difference
    assert m.same_slip_everywhere(run) == pytest.approx(1.0)
    assert m.stationary_before_arrival(run, 0.98) == pytest.approx(0.0)
    iface["ux"][:, -2] += np.where(np.arange(nf) < 1300 + NS - 2, 0.004 * np.arange(nf) / 1300, 0.0)
    assert m.stationary_before_arrival(as_run(iface, mode="shear"), 0.98) > 0.2


def test_vertical_displacement_and_lift():
    iface = blank(1000)
    for k0 in (100, 300):
        draw(iface, k0, 0, +1, 2, 2, 0.01, slip_v=0.0005)
    run = as_run(iface)
    assert m.net_vertical_over_slip(run) == pytest.approx(0.05)
    it = iface["intact"]
    iface["uy"][:, :3] += np.where(it[:, :3] == 0, 0.002, 0.0)   # lifted while broken at the edge
    f = m.edge_fronts(as_run(iface))[0]
    assert m.lift_at_nucleation(as_run(iface)) == pytest.approx(
        float(np.median(f.tip["v_behind"][np.abs(f.tip["x"] - f.nucleation_x) <= 0.05])))


def test_interface_stress_profiles_before_the_first_break():
    iface = blank(200)
    x = iface["x"]
    iface["sxy"] = np.tile(1 + 0.5 * np.sin(np.pi * x), (200, 1))       # rises from the edges to the centre
    iface["syy"] = np.tile(np.where(x < 0.03, 0.3, -0.1), (200, 1))      # tensile at the rear edge
    iface["intact"][50, 0] = 0
    run = as_run(iface)
    assert first_break_frame(run) == 50
    assert m.argmax_before_break(run, "syy") == pytest.approx(x[0])
    assert m.argmax_before_break(run, "sxy") == pytest.approx(x[int(np.argmax(np.sin(np.pi * x)))])
    edges = np.mean(iface["sxy"][49][(x < 0.1) | (x > 0.9)])
    centre = np.mean(iface["sxy"][49][(x >= 0.3) & (x <= 0.7)])
    assert m.centre_over_edges(run) == pytest.approx(centre / edges)
    assert m.min_before_break(run) == pytest.approx(-0.1)


def _with_mode2_stress(iface, k2=0.02, xp=0.01, noise=None):
    """sxy ahead of each front's tip set to K / sqrt(2 pi (xi + x_p)) in every frame."""
    run = as_run(iface)
    iface["sxy"] = np.zeros_like(iface["ux"])
    for f in run.fronts():
        for k in range(len(iface["t"])):
            t = iface["t"][k]
            if not f.nucleation_time <= t <= f.tip["t"][-1]:
                continue
            xi = f.direction * (iface["x"] - f.tip_at(t))
            ahead = xi > 0
            iface["sxy"][k, ahead] = np.maximum(iface["sxy"][k, ahead], k2 / np.sqrt(2 * np.pi * (xi[ahead] + xp)))
    if noise is not None:
        iface["sxy"] *= noise
    return as_run(iface)


def test_mode2_fit_quality_and_tip_peaks():
    iface = blank(1500)
    for k0 in (100, 300, 500, 700):
        draw(iface, k0, 0, +1, 12, 2, 0.01)                # 720 frames to cross: four pulses in flight
    run = _with_mode2_stress(iface)
    assert m.mode2_first_pulse(run) == pytest.approx(1.0, abs=1e-9)
    assert m.mode2_later_pulses(run) == pytest.approx(1.0, abs=1e-9)
    assert m.tip_peak_constancy(run) == pytest.approx(1.0)
    rng = np.random.default_rng(1)
    flat = _with_mode2_stress(iface.copy() | {"ux": iface["ux"]}, noise=rng.uniform(0.3, 1.7, iface["ux"].shape))
    assert m.mode2_first_pulse(flat) < 0.9


def test_tip_carries_both_peaks():
    nf = 400
    iface = blank(nf)
    draw(iface, 100, 0, +1, 1, NS, 0.008, crack=True)
    run = as_run(iface, mode="shear")
    f = run.fronts()[0]
    k = run.frame_at(float(f.tip["t"][len(f.tip["t"]) // 2]))
    tip = int(np.argmin(np.abs(iface["x"] - f.tip_at(run.times[k]))))
    iface["sxy"], iface["syy"] = np.zeros((nf, NS)), np.zeros((nf, NS))
    iface["sxy"][k, tip + 2] = 1.0
    iface["syy"][k, tip + 3] = 1.0
    assert m.tip_carries_both_peaks(as_run(iface, mode="shear")) == 1.0
    iface["syy"][k, NS - 1] = 2.0                           # the normal stress peaks at the far edge instead
    assert m.tip_carries_both_peaks(as_run(iface, mode="shear")) == 0.5


def test_block_sxx_needs_snapshots(runs):
    assert math.isnan(m.mean_block_sxx(runs["push"], 30.0))


def test_block_sxx_of_a_real_push_run(small_run):
    """A pushed block is in compression, on average, once the drive runs."""
    import parslip
    run = parslip.open(small_run)
    assert m.mean_block_sxx(run, float(run.snapshot_times[-1])) < 0


def test_section_width_is_the_median_interior_white_run():
    iface = blank(10)
    it = iface["intact"]
    it[5, 10:13] = 0
    it[5, 30:35] = 0
    it[5, 0:2] = 0
    it[5, NS - 1] = 0
    run = as_run(iface)
    assert section_width(run, 5 * DT) == 4.0
    assert np.isnan(section_width(run, 0.0))


def test_pulse_count_includes_a_young_front_cut_short_by_the_record():
    nf = 400
    iface = blank(nf)
    for k0 in (10, 110, 210):
        draw(iface, k0, 0, +1, 1, 2, 0.01, sites=30)
    draw(iface, 160, 0, +1, 1, 1, 0.0, sites=2)
    it = iface["intact"]
    it[nf - 3, 0] = it[nf - 2, 0:2] = it[nf - 1, 1:3] = 0
    run = as_run(iface)
    assert len(m.edge_fronts(run)) == 3
    got = [round(f.nucleation_time / DT) for f in m.edge_nucleations(run)]
    assert got == [10, 110, 210, nf - 3]


def test_in_flight_when_the_fourth_nucleates():
    """Slow pulses (720 frames to cross) born every 200 frames: three in flight as the fourth is born,
    counted the same whether the fourth comes a frame early or late."""
    iface = blank(1500)
    for k0 in (100, 300, 500, 700):
        draw(iface, k0, 0, +1, 12, 2, 0.01)
    run = as_run(iface)
    assert m.in_flight_at_nucleation(run, 3) == 3
    assert m.live_pulses(run, 700 * DT + 1e-9) == 4
    assert m.in_flight_at_nucleation(run, 7) == -1


def test_alternative_measurements_are_judged_by_the_claims_tolerance(runs):
    alts = cl.alternatives(runs)
    keys = {a["key"] for a in alts}
    assert "pull_push_speed" in keys and "push_width" in keys
    (speed,) = [a for a in alts if a["key"] == "pull_push_speed"]
    assert speed["parslip"] == "0.5" and speed["verdict"] == cl.AGREES          # drawn: half the speed
    for a in alts:
        assert a["verdict"] in cl.VERDICTS and a["key"] in {c.key for c in cl.CLAIMS}


def test_tip_peak_follows_the_leading_pulse_in_flight():
    """Fast pulses (240 frames to cross, one every 200): the first has left when the fourth is born, so
    the peak is read ahead of the earliest pulse still in flight; with none in flight it is not measured."""
    iface = blank(1300)
    for k0 in (100, 300, 500, 700):
        draw(iface, k0, 0, +1, 4, 2, 0.01)
    run = _with_mode2_stress(iface)
    assert m.tip_peak_constancy(run) == pytest.approx(1.0)
    iface = blank(1300)
    for k0 in (100, 400, 700, 1000):
        draw(iface, k0, 0, +1, 4, 2, 0.01)
    assert math.isnan(m.tip_peak_constancy(_with_mode2_stress(iface)))
