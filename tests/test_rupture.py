"""The interface studies' measures (``analysis.rupture``) on records drawn by hand, where each answer is
known: a daughter front born ahead of a running one, a front that slows in a patch and stops at it, and
Andrews' S of a traction history made to give S = 1.5."""
import json
import math

import numpy as np
import pytest

from helpers import DT, NS, blank, draw
from parslip.analysis import rupture
from parslip.analysis.fronts import FIELDS, table
from parslip.analysis.results import Run


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


def test_andrews_s_of_a_known_traction_history():
    """Every site sits at tau_0 = 1 until the tip comes, peaks at 2.5 the frame before it breaks (but the
    nucleation site, which breaks first), and is at 0 once the front has passed: tau_peak = (1 + 59 x 2.5)
    / 60 and S = (tau_peak - 1) / (1 - 0), with either sign of the traction."""
    it = blank(120)
    arr = draw(it, 20, 0, +1, 1, 1000, 0.001, crack=True)
    sxy = np.ones((120, NS))
    for s, k in enumerate(arr):
        if s:
            sxy[k - 1, s] = 2.5
        sxy[k:, s] = 0.0
    peak = (1 + (NS - 1) * 2.5) / NS
    for sign in (1.0, -1.0):
        it["sxy"] = sign * sxy
        run = Run.from_arrays(it)
        got = rupture.andrews_s(run, run.fronts()[0])
        assert got["S"] == pytest.approx(peak - 1.0) and got["tau_0"] == pytest.approx(1.0)
        assert got["tau_peak"] == pytest.approx(peak) and got["tau_res"] == pytest.approx(0.0)


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
