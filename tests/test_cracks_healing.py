"""The healing study's prediction (parslip.studies.cracks.healing.rebond_window): how long a site held up by
the contact and sliding at the drive's speed stays within delta0 of one substrate site, against the path
walked step by step through the delta0 disc."""
import math

import numpy as np
import pytest

from parslip.studies.cracks.healing import rebond_window


@pytest.mark.parametrize("kc, cols, fn", [(0.1, 100, 1.0), (0.3, 100, 1.0), (1.0, 100, 2.0), (0.3, 500, 1.0)])
def test_the_rebond_window_is_the_time_a_sliding_site_spends_in_the_delta0_disc(kc, cols, fn):
    d0, v0 = 0.5, 1e-3
    scene = {"interface.contact": kc, "drive.v0": v0, "lattice.top_cols": cols, "load.FN": fn,
             "interface.delta0": d0}
    height = d0 - fn / cols / kc                  # where the contact's spring carries the site's share of F_N
    t = np.linspace(-20.0, 20.0, 2_000_001)       # l/c_r; the site passes over the substrate site at t = 0
    x = v0 * cols * t                             # a: v0 (c_r) times l = cols a per l/c_r
    inside = np.hypot(x, height) < d0
    walked = inside.sum() * (t[1] - t[0])
    assert rebond_window(scene) == pytest.approx(walked, abs=2 * (t[1] - t[0]))


def test_no_window_without_contact_or_drive():
    base = {"interface.contact": 0.3, "drive.v0": 1e-3, "lattice.top_cols": 100, "load.FN": 1.0,
            "interface.delta0": 0.5}
    assert math.isnan(rebond_window({**base, "interface.contact": 0.0}))
    assert math.isnan(rebond_window({**base, "drive.v0": 0.0}))
