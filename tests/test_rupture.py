"""The interface studies' measures (``analysis.rupture``) on records drawn by hand, where each answer is
known: a daughter front born ahead of a running one, a front that slows in a patch and stops at it,
Andrews' S of traction histories made to give S = 2 and 2/0.7, and the shear-traction drop along a path."""
import json
import math

import numpy as np
import pytest

from helpers import DT, NS, blank, draw
from parslip.analysis import rupture
from parslip.analysis.fronts import FIELDS, table
from parslip.analysis.results import Run
from parslip.io.contract import EVENT_BREAK, EVENT_FORM


def test_a_front_born_ahead_of_a_running_tip_is_its_daughter():
    it = blank(4 * NS + 40)
    draw(it, 10, 0, +1, 4, 2, 0.001)                 # the mother: a site every 4 frames from x = 0
    draw(it, 30, 30, +1, 1, 2, 0.001, sites=10)      # born at site 30 at frame 30, the mother's tip at site 5
    run = Run.from_arrays(it)
    fr = run.fronts()
    d = rupture.daughters(run)
    assert len(d) == 1
    mother, daughter = fr[d[0]["mother"]], fr[d[0]["daughter"]]
    assert round(mother.nucleation_time / DT) == 10 and round(daughter.nucleation_time / DT) == 30
    assert d[0]["ahead"] == pytest.approx((30 - 5) / NS)
    assert rupture.daughters(run, min_gap=0.5) == []


def test_a_front_slowed_and_stopped_by_a_patch():
    it = blank(300)
    arr = draw(it, 0, 0, +1, 1, 2, 0.001, sites=int(0.5 * NS))    # one site a frame: 1 site/DT
    f = Run.from_arrays(it).fronts()[0]
    res = rupture.through_patch(f, 0.4, 0.6)
    assert res["through"] is False and math.isnan(res["after"])
    assert res["before"] == pytest.approx(res["inside"]) == pytest.approx((1 / NS) / DT)
    assert len(arr) == int(0.5 * NS)
    slow = rupture.through_patch(f, 0.4, 0.6, c_l=0.5 * (1 / NS) / DT)   # a "speed" above c_l is a burst
    assert math.isnan(slow["inside"]) and slow["bursts"] == 2


def _history(pulse_width=None, tau_0=1.0, ramp=2.5, tau_after=0.4):
    """A front from site 0 at frame 20, one site a frame (a crack, or a pulse ``pulse_width`` frames wide);
    each site carries ``tau_0`` until the frame before its break, ``ramp`` in that frame, nothing while
    its bond is broken and ``tau_after`` once it re-forms.  With its event record: each break at the step
    just before the frame that first shows it (frame k holds step k)."""
    it = blank(120)
    crack = pulse_width is None
    arr = draw(it, 20, 0, +1, 1, 1000 if crack else pulse_width, 0.001, crack=crack)
    sxy = np.full((120, NS), tau_0)
    for s, k in enumerate(arr):
        sxy[k - 1, s] = ramp if s else tau_0
        sxy[k:, s] = tau_after
    it["sxy"] = sxy * it["intact"]                         # the interface traction of a broken bond is 0
    it["step"] = np.arange(120)
    broken = it["intact"] == 0
    k, site = np.nonzero(broken[1:] != broken[:-1])        # every change the frames show, one step earlier
    kind = np.where(broken[k + 1, site], EVENT_BREAK, EVENT_FORM).astype(np.uint8)
    it["events"] = {"step": k, "time": k * DT, "site": site, "kind": kind, "partner": site, "site_column0": 0,
                    "dt": DT, "c_s": math.inf, "c_l": math.inf}
    return it, arr


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_andrews_s_from_the_break_traction_of_a_known_history(sign):
    """tau_0 = 1 before the front, 3.0 at each break step (the event's traction; the frames show only the
    2.5 of the frame before), nothing behind a crack's tip: S = (3 - 1) / (1 - 0) = 2, recovered within 2 %
    per site and as the median, whichever the sign of the traction; without the events' traction the
    frames give (2.5 - 1) / 1 and say so."""
    it, arr = _history()
    it["sxy"] *= sign
    it["events"]["traction"] = np.where(it["events"]["kind"] == EVENT_BREAK, 3.0 * sign, 0.0)
    run = Run.from_arrays(it)
    (f,) = run.fronts()
    got = rupture.andrews_s(run, f)
    assert got["peak_from"] == "events" and got["S"] == pytest.approx(2.0, rel=0.02)
    assert (got["tau_0"], got["tau_peak"], got["tau_res"]) == (pytest.approx(1.0), pytest.approx(3.0), 0.0)
    assert np.nanmedian(got["sites"]["S"]) == pytest.approx(2.0, rel=0.02) and f.andrews_s == got["S"]
    it["sxy"][:15] *= 0.5                                  # tau_0 = 0.5 until frame 15: S = (3 - 0.5)/0.5
    (f,) = Run.from_arrays(it).fronts()
    assert rupture.andrews_s(f.run, f)["S"] == pytest.approx(2.0, rel=0.02)
    assert rupture.andrews_s(f.run, f, t0=10 * DT)["S"] == pytest.approx(5.0, rel=0.02)
    it["sxy"][:15] *= 2.0
    del it["events"]["traction"]
    (f,) = Run.from_arrays(it).fronts()
    got = rupture.andrews_s(f.run, f)
    assert got["peak_from"] == "frames" and got["S"] == pytest.approx(1.5, rel=0.02)


def test_andrews_s_residual_is_the_mean_behind_the_tip_with_broken_bonds_at_zero():
    """A pulse 5 frames wide: over the window of 1 l/c_r = 20 frames behind the tip a site is broken for 5
    frames (0) and re-formed at 0.4 for 15: tau_res = 0.4 x 15/20 = 0.3, so S = (3 - 1) / (1 - 0.3)."""
    it, arr = _history(pulse_width=5)
    it["events"]["traction"] = np.where(it["events"]["kind"] == EVENT_BREAK, 3.0, 0.0)
    (f,) = Run.from_arrays(it).fronts()
    got = rupture.andrews_s(f.run, f)
    assert got["tau_res"] == pytest.approx(0.3) and got["S"] == pytest.approx(2.0 / 0.7, rel=0.02)
    assert f.kind == "pulse" and f.andrews_s == pytest.approx(2.0 / 0.7, rel=0.02)


def test_traction_drop_of_a_known_traction_history():
    """Each site carries tau_0 = 1 + s/100 until the frame that shows its bond broken, then 0.25: the drop
    at site s is 0.75 + s/100, and its mean over the crack's path (sites 0-59) is 0.75 + 0.295, whichever
    the sign of the traction.  The field is registered: it reads as front.traction_drop, is a key of the
    front's JSON and a column of the table."""
    it = blank(120)
    arr = draw(it, 20, 0, +1, 1, 1000, 0.001, crack=True)
    sxy = np.empty((120, NS))
    for s, k in enumerate(arr):
        sxy[:k, s], sxy[k:, s] = 1 + s / 100, 0.25
    want = 0.75 + np.mean(np.arange(NS)) / 100
    for sign in (1.0, -1.0):
        it["sxy"] = sign * sxy
        (f,) = Run.from_arrays(it).fronts()
        assert f.traction_drop == pytest.approx(want, rel=1e-12)
        assert json.loads(json.dumps(f.to_dict()))["traction_drop"] == pytest.approx(want, rel=1e-12)
    assert FIELDS["traction_drop"].units == "rho c_r^2" and "dtau" in table([f])
    it.pop("sxy")
    assert Run.from_arrays(it).fronts()[0].traction_drop is None


def test_andrews_lc_is_xia_et_al_form_for_the_central_force_lattice():
    """With k_t = 0 the Born continuum is isotropic with plane-stress nu = 1/3 and mu = (sqrt 3 / 4) k_n, so
    the static mode II modulus of ``cracks.mode2_compliance`` makes ``andrews_lc`` Xia et al.'s (Science
    2004) L_c = (1 + nu)/pi mu (tau_p - tau_r) D_c / (tau_0 - tau_r)^2; f(S) = 9.8 (1.77 - S)^-3, none
    from S = 1.77 up."""
    from parslip.analysis.cracks import mode2_compliance
    kn = 2.7
    M = 1.0 / mode2_compliance(0.0, kn, 0.0)
    mu, nu = math.sqrt(3) / 4 * kn, 1.0 / 3.0
    tau_p, tau_0, tau_r, d_c = 0.05, 0.031, 0.004, 0.42
    xia = (1 + nu) / math.pi * mu * (tau_p - tau_r) * d_c / (tau_0 - tau_r) ** 2
    # H(0) is taken at v = 1e-3 c: 1e-6 off the static value
    assert rupture.andrews_lc(M, tau_p, tau_0, tau_r, d_c) == pytest.approx(xia, rel=1e-5)
    assert rupture.andrews_f(0.77) == pytest.approx(9.8) and math.isnan(rupture.andrews_f(1.77))
    assert rupture.andrews_f(0.3) == pytest.approx(9.8 / 1.47 ** 3)


def test_transition_of_a_drawn_daughter_against_andrews():
    """The daughter record of the first test, as cracks, with tractions: tau_0 = 1 before the fronts, 2 at each break
    (S = (2 - 1)/(1 - 0) = 1), on a 60-site contact of 60 a.  The daughter is born 30 sites from the mother's
    first site: L_trans = 30 a (20 a from an origin at site 10; none when only what is beyond site 40 counts);
    L_andrews = f(1) L_c with L_c computed here from the block's modulus."""
    from parslip.analysis.cracks import mode2_compliance
    from parslip.model.physics import DENSITY, Material
    it = blank(4 * NS + 40)
    draw(it, 10, 0, +1, 4, 2, 0.001, crack=True)
    draw(it, 30, 30, +1, 1, 2, 0.001, crack=True)         # the daughter runs to the far edge
    nf = len(it["t"])
    broken = it["intact"] == 0
    it["sxy"] = np.where(broken, 0.0, 1.0)
    it["step"] = np.arange(nf)
    k, site = np.nonzero(broken[1:] != broken[:-1])
    kind = np.where(broken[k + 1, site], EVENT_BREAK, EVENT_FORM).astype(np.uint8)
    it["events"] = {"step": k, "time": k * DT, "site": site, "kind": kind, "partner": site, "site_column0": 0,
                    "dt": DT, "c_s": math.inf, "c_l": math.inf, "traction": np.where(kind == EVENT_BREAK, 2.0, 0.0)}
    scene = {"lattice.top_cols": NS, "interface.kx": 0.1, "material.nu": 0.2, "material.model": "plane_strain",
             "material.velocity_unit": "c_r", "material.bottom_kn": 2.81154, "material.bottom_kt": 0.133883}
    run = Run.from_arrays(it, scene=scene)
    fr = run.fronts()
    got = rupture.transition(run, fr[0])
    m = Material.from_scene(0.2, "plane_strain", "c_r", 2.81154, 0.133883, "along")
    unit = DENSITY * m.c_r ** 2
    L_c = (2.0 * unit) * (2.0 * unit / 0.1) / (math.pi * mode2_compliance(0.0, m.kn_top, m.kt_top) * unit ** 2)
    assert got["S"] == pytest.approx(1.0) and got["L_trans"] == pytest.approx(30.0)
    assert got["L_c"] == pytest.approx(L_c, rel=1e-9) and got["L_andrews"] == pytest.approx(9.8 / 0.77 ** 3 * L_c)
    assert got["daughter"] == 1 and got["v_super"] == pytest.approx((1 / NS) / DT, rel=1e-6)
    moved = rupture.transition(run, fr[0], origin=10.5 / NS)     # counted from site 10: 20 sites to the daughter
    assert moved["L_trans"] == pytest.approx(20.0) and moved["daughter"] == 1
    late = rupture.transition(run, fr[0], beyond=40.5 / NS)       # a daughter born before x = 40 sites is not one
    assert math.isnan(late["L_trans"]) and late["daughter"] is None


def test_transition_where_a_drawn_tip_goes_above_c_s_and_stays():
    """A crack from site 0 at 1/4 site a frame (1/12 c_r on this record) for 20 sites, then one site a frame
    (1/3 c_r) to the far edge, with c_s = 0.25 c_r: no daughter, and the tip is above c_s from site 20 on, so
    L_fast = 20 a on a 60 a contact (within the window's resolution) and the speed it settled at is 1/3 c_r
    (within 2 %: the fit starts a site early); with c_s = 0.4 c_r it never is."""
    it = blank(200)
    draw(it, 10, 0, +1, 4, 2, 0.001, sites=20, crack=True)
    draw(it, 10 + 4 * 20, 20, +1, 1, 2, 0.001, crack=True)
    it["sxy"] = np.where(it["intact"] == 0, 0.0, 1.0)
    scene = {"lattice.top_cols": NS, "interface.kx": 0.1, "material.nu": 0.2, "material.model": "plane_strain",
             "material.velocity_unit": "c_r", "material.bottom_kn": 2.81154, "material.bottom_kt": 0.133883}
    for c_s, want in ((0.25, 20.0), (0.4, math.nan)):
        run = Run.from_arrays(it, scene=scene, attrs={"c_s": c_s, "c_l": 2 * c_s, "c_r": 1.0})
        (f,) = run.fronts()
        got = rupture.transition(run, f, min_sites=4)
        assert got["daughter"] is None and math.isnan(got["L_trans"])
        if math.isnan(want):
            assert math.isnan(got["L_fast"]) and math.isnan(got["v_super"])
        else:        # a window of 4 sites fits above c_s once 3 of them are fast: one site early
            assert got["L_fast"] == pytest.approx(want, abs=1.0)
            assert got["v_super"] == pytest.approx((1 / NS) / DT, rel=0.02)
        wide = rupture.transition(run, f)                 # 20 sites: the window straddles the change longer
        assert math.isnan(want) or want - 10 <= wide["L_fast"] <= want
