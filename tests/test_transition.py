"""The supershear transition read off a rupture-time field (``parslip.analysis.transition``): the daughter's
birth and the tip's speeds on drawn fields whose answer is known in closed form, and on a small real lattice
run against the interface frames (an independent record of when each site broke)."""
import math

import numpy as np
import pytest

from helpers import run_small
from parslip.analysis import transition as T
from parslip.analysis.fronts import wave_speeds
from parslip.analysis.results import Run

C_S = 1.0977          # the default block's c_s (c_r)
DT = 0.42             # a time step (a/c_r): the events' resolution


def _field(r, v_mother=0.95, birth=None, v_daughter=1.7, dt=DT):
    """Rupture times (a/c_r) at distances r (a) of a mother front at v_mother from r = 0 and, with birth =
    (r_d, t_d), a daughter born there that grows both ways at v_daughter; each site breaks at the first
    arrival, rounded up to a step."""
    t = r / v_mother
    if birth is not None:
        t = np.minimum(t, birth[1] + np.abs(r - birth[0]) / v_daughter)
    return np.ceil(t / dt) * dt


def test_the_daughters_birth_is_found_to_a_site():
    """A daughter born at r_d = 60.5 a, 12 a ahead of the mother's tip then: found there, by its birth."""
    r = np.arange(200) + 0.5
    for r_d in (60.5, 33.5, 121.5):
        t_d = (r_d - 12.0) / 0.95
        got = T.transition_distance(r, _field(r, birth=(r_d, t_d)), C_S, start=10.0)
        assert got["by"] == "daughter" and abs(got["L_trans"] - r_d) <= 1.0, (r_d, got)
        assert got["lead"] >= T.MIN_LEAD


def test_a_daughter_inside_the_zone_does_not_count_and_a_sub_rayleigh_front_has_none():
    r = np.arange(200) + 0.5
    assert T.daughter_birth(r, _field(r, birth=(8.5, 0.0)), start=20.0) is None
    plain = T.transition_distance(r, _field(r), C_S, start=10.0)
    assert plain["by"] is None and math.isnan(plain["L_trans"]) and plain["v_exit"] < C_S


def test_a_tip_that_speeds_up_without_a_daughter_is_found_within_its_window():
    """The tip runs at 0.95 c_r to r_k = 50 a, then at 1.6 c_r: no site breaks before a nearer one, and the
    first window above c_s starts within the window's length before r_k (a line through arrivals on both
    sides of the kink is faster than c_s once most of them are past it)."""
    r = np.arange(200) + 0.5
    t = np.where(r <= 50.0, r / 0.95, 50.0 / 0.95 + (r - 50.0) / 1.6)
    got = T.transition_distance(r, np.ceil(t / DT) * DT, C_S, start=10.0)
    assert got["by"] == "tip above c_s" and 50.0 - T.MIN_SITES <= got["L_trans"] <= 50.0 + 1.0, got
    mids, v = T.window_speeds(r, t, got["L_trans"] + T.MIN_SITES, 190.0)
    assert np.allclose(v, 1.6, rtol=1e-9) and np.all(np.diff(mids) == 10.0)


def test_a_side_is_cut_where_the_front_stopped():
    times = np.array([np.nan, 5.0, 4.0, 3.0, 1.0, 1.0, 2.0, np.nan, 9.0])
    r, t = T.side(times, 5.0, +1, unit=2.0)
    assert np.allclose(r, [0.5, 1.5]) and np.allclose(t, [0.0, 2.0])           # the NaN at site 7 stops it
    r, t = T.side(times, 5.0, -1, unit=2.0)
    assert np.allclose(r, [0.5, 1.5, 2.5, 3.5]) and np.allclose(t, [0.0, 4.0, 6.0, 8.0])
    assert [len(a) for a in T.side(np.full(5, np.nan), 2.0, 1)] == [0, 0]


# A held prestress at S = 0.3 on run/weakening.toml's law (k_x = 0.4, D_c = 0.5 a, Lambda = 8.35 a, L_c =
# 5.08 a), shrunk: 160 a, 46 + 46 rows, F_N per bond as there, the forced zone 1.5 L_c (7.6 a) wide each side.
TINY = {"lattice.top_rows": 46, "lattice.top_cols": 160, "lattice.bottom_rows": 46, "lattice.bottom_cols": 180,
        "material.bottom_kn": 2.81154, "material.bottom_kt": 0.133883, "interface.kx": 0.4, "interface.ky": 0.3,
        "interface.delta0": 0.5, "interface.delta_b": 0.7, "interface.softening": 0.5,
        "interface.patch": [{"x": [0.0, 0.1], "delta_b": 1.2}, {"x": [0.9, 1.0], "delta_b": 1.2}],
        "interface.nucleation.kind": "forced", "interface.nucleation.x": [0.4525, 0.5475],
        "interface.nucleation.speed": 0.5, "interface.nucleation.duration": 0.03, "load.FN": 0.4,
        "load.settle": 0.5, "time.damping": "bonds", "time.zeta": 0.01, "drive.mode": "shear",
        "drive.hold": "xy", "drive.v0": 5e-3, "drive.duration": 16.0, "drive.prestress.tau0": 0.13277,
        "drive.prestress.x": [0.25, 0.75], "drive.prestress.settle": 0.3, "output.interface_dt": 0.01,
        "output.fields": "interface"}


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The TINY run (a forced nucleation at S = 0.3), run once for the tests that read it."""
    _, out = run_small(tmp_path_factory.mktemp("tiny"), "tiny", **TINY)
    return Run(str(out))


@pytest.mark.timeout(300)
def test_a_lattice_rupture_times_agree_with_its_frames_and_turn_supershear(tiny):
    """On a real run: each site's first break after the hold (the events' exact steps) lies within the frame
    interval before the first frame that shows it broken (over the sites the fronts cross between the zone
    and the strong edges); both sides of the bilateral rupture give the same
    L_trans to a site; and a line through the frames' arrivals from the zone's edge to 60 a runs above c_s,
    as the events' windows do (to within the frames' resolution)."""
    run = tiny
    held = float(run.attrs["prestress_time"])
    times = T.rupture_times(run, held)
    it = run.interface
    t_frames = np.asarray(it["t"], float)
    after = t_frames >= held
    broken = (np.asarray(it["intact"]) == 0)[after]
    seen = np.where(broken.any(axis=0), t_frames[after][np.argmax(broken, axis=0)], np.nan)
    gap = float(np.max(np.diff(t_frames)))
    # the sites the spontaneous fronts crossed before they met the strong edges (inside the zone and at the
    # edges a bond may break and re-form within a frame)
    ok = (np.abs(np.arange(160) + 0.5 - 80.0) < 60.0) & (np.abs(np.arange(160) + 0.5 - 80.0) > 10.0)
    assert np.isfinite(seen[ok]).all() and np.isfinite(times[ok]).all()
    assert np.all(seen[ok] >= times[ok]) and np.all(seen[ok] - times[ok] <= gap + 1e-12)
    c_s = wave_speeds(run)["c_s"]
    got = [T.transition_distance(*T.side(times, 80.0, d, 160.0), c_s, start=7.6) for d in (1, -1)]
    assert all(g["by"] is not None for g in got) and abs(got[0]["L_trans"] - got[1]["L_trans"]) <= 1.0
    r, _ = T.side(times, 80.0, 1, 160.0)
    _, tf = T.side(seen, 80.0, 1, 160.0)
    keep = (r > 8.0) & (r < 60.0)
    assert np.polyfit(tf[keep], r[keep], 1)[0] > c_s


def test_the_rupture_runs_free_where_it_first_breaks_a_site_before_the_forcing_reaches_it():
    """A forced front at 0.5 c_r; the rupture lags it by 2 a/c_r to r = 10 a, then runs at c_r by itself: it
    breaks a site before the forcing arrives from r = 12 a on (22 + (r - 10) < 2 r), found at the first site
    past it; a zone that ends before that gives its own edge."""
    r = np.arange(100) + 0.5
    forced = r / 0.5
    t = np.where(r < 10.0, forced + 2.0, 22.0 + (r - 10.0))
    assert T.free_start(r, t, forced, half=30.0) == 12.5
    assert T.free_start(r, t, forced, half=12.0) == 12.0
    assert T.free_start(r, forced + 2.0, forced, half=30.0) == 30.0     # never ahead: the zone's edge


@pytest.mark.timeout(300)
def test_study_1_reads_the_transition_beyond_where_the_lattice_rupture_outran_its_forcing(tiny):
    """On the real run, study 1's reading (``andrews.remeasure``): the hypocentre's site breaks after the
    forcing reached it and within the forcing's weakening time (nucleation.duration), on the clock the
    reading puts the forcing on (the nucleation's start from the scene and the held prestress's time, the
    first break as t = 0); every site before a side's free start broke no earlier than the forcing reached
    it, the one at it earlier; the free start lies within the zone, and L_trans read from it is at most the
    zone-edge reading (a daughter or a supershear stretch beyond the edge is one beyond the free start too)."""
    from parslip.studies.weakening import andrews
    run = tiny
    m = andrews.remeasure(andrews.measure(run), run)
    g, sc, l = m["geometry"], run.scene, 160.0
    times = T.rupture_times(run, float(run.attrs["prestress_time"]))
    start = float(run.attrs["prestress_time"]) + float(sc["drive.prestress.settle"]) \
        + float(sc["interface.nucleation.start"])
    origin, v = (start - np.nanmin(times)) * l, float(sc["interface.nucleation.speed"])
    weaken = float(sc["interface.nucleation.duration"]) * l
    for side in m["sides"]:
        r, t = side["r"], side["t"]
        assert origin + r[0] / v <= t[0] <= origin + r[0] / v + weaken + DT
        before = r < side["free"]
        assert np.all(t[before] >= origin + r[before] / v)
        assert side["free"] <= g["half"]
        if side["free"] < g["half"]:
            assert t[r == side["free"]][0] < origin + side["free"] / v
    assert math.isfinite(m["L_trans"]) and m["L_trans"] <= m["L_zone"]


def test_the_tables_write_numpy_floats_as_numbers(tmp_path):
    """The study's rows carry numpy floats (``law_scales``): the CSV holds their digits, not their repr."""
    from parslip.analysis import table
    path = tmp_path / "t.csv"
    table.write_csv(str(path), ["S", "L"], [{"S": np.float64(0.3000122), "L": 8.5}])
    assert path.read_text().splitlines()[1] == "0.3000122,8.5"
