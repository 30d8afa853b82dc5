"""The front detector against drawn bond-state patterns with known fronts, and on a real short run.

Each drawn front has a nucleation frame and site, a direction, a whole
number of frames per site (so its arrival times are exactly linear), a width
in sites, a pulse-or-crack kind and a slip it adds to u at every site it
crosses; the detector must give them back exactly.
"""
import importlib
import json

import numpy as np
import pytest

import parslip
from helpers import DT, NS, blank, draw
from parslip.analysis.results import Run
from parslip.cli import main

F = importlib.import_module("parslip.analysis.fronts")   # the module (parslip.analysis.fronts is also the function)


def catalogue(iface, **kw):
    """The front catalogue of a drawn record (a run held in memory)."""
    return Run.from_arrays(iface).fronts(**kw)


def test_two_opposite_pulses_recovered_exactly():
    iface = blank(300)
    a_arr = draw(iface, 10, 0, +1, 2, 3, 0.01, sites=40, slip_v=0.002)
    b_arr = draw(iface, 40, NS - 1, -1, 3, 2, 0.02, sites=30)
    fr = catalogue(iface)
    assert len(fr) == 2
    a, b = fr
    dx = 1 / NS
    assert (a.nucleation_time, a.nucleation_x, a.direction, a.kind) == (10 * DT, iface["x"][0], 1, "pulse")
    assert (b.nucleation_time, b.nucleation_x, b.direction, b.kind) == (40 * DT, iface["x"][-1], -1, "pulse")
    for f, fps, d, w, s, arr in ((a, 2, 1, 3, 0.01, a_arr), (b, 3, -1, 2, 0.02, b_arr)):
        v = d * dx / (fps * DT)
        assert f.mean_speed == pytest.approx(v, rel=1e-9)
        assert f.max_speed == pytest.approx(v, rel=1e-9) and f.steady_speed == pytest.approx(abs(v), rel=1e-9)
        np.testing.assert_allclose(f.tip["v"], v, rtol=1e-9)
        np.testing.assert_allclose(f.tip["t"], arr * DT, rtol=1e-12)
        assert f.width == w and f.tip["w"][-1] == w
        assert f.slip_u == pytest.approx(s, abs=1e-15)
        np.testing.assert_allclose(f.tip["du"], s, atol=1e-15)
        assert f.accel_x is None
    assert a.slip_v == pytest.approx(0.002) and b.slip_v == 0.0
    assert a.sites == 40 and b.sites == 30


def test_trailing_pulses_from_one_edge_stay_separate():
    iface = blank(400)
    for k0 in (0, 60, 120):                         # three pulses from x = 0, 60 frames apart
        draw(iface, k0, 0, +1, 3, 2, 0.01)
    fr = catalogue(iface)
    assert [f.nucleation_time for f in fr] == pytest.approx([0.0, 3.0, 6.0])
    assert all(f.direction == 1 and f.kind == "pulse" and f.sites == NS and f.width == 2 for f in fr)
    assert all(f.mean_speed == pytest.approx((1 / NS) / (3 * DT)) for f in fr)
    # at a site they all crossed, each front carried 0.01: together the whole change in u
    s = NS // 2
    assert sum(f.tip["du"][s] for f in fr) == pytest.approx(iface["ux"][-1, s] - iface["ux"][0, s])


def test_crack_keeps_everything_behind_broken():
    iface = blank(150)
    arr = draw(iface, 20, 0, +1, 1, 1, 0.03, crack=True)
    (f,) = catalogue(iface)
    assert f.kind == "crack" and f.direction == 1
    assert f.mean_speed == pytest.approx((1 / NS) / DT)
    np.testing.assert_array_equal(f.tip["w"], np.arange(1, NS + 1))     # the broken zone grows with the tip
    np.testing.assert_allclose(f.tip["du"], 0.03)
    np.testing.assert_allclose(f.tip["t"], arr * DT)


def test_fast_backward_crack_is_one_front():
    """Three sites per frame toward x = 0: runs of new breaks that grow down from the tip."""
    iface = blank(60)
    k0, s0 = 10, NS - 1
    for k in range(k0, 60):
        iface["intact"][k, max(0, s0 - 3 * (k - k0) - 2):] = 0
    fr = catalogue(iface)
    assert len(fr) == 1
    f = fr[0]
    assert f.direction == -1 and f.kind == "crack" and f.sites == NS
    assert f.nucleation_x == iface["x"][-1] and f.nucleation_time == k0 * DT  # three broke at once: the rear one
    assert f.mean_speed == pytest.approx(-3 * (1 / NS) / DT, rel=0.05)
    assert np.all(np.abs(f.tip["v"]) <= 5 * (1 / NS) / DT + 1e-9)            # capped at a window per frame


def test_acceleration_site():
    """Four frames per site up to site 30, then one: the local speed quadruples there."""
    iface = blank(300)
    t_arr = [4 * j for j in range(31)] + [120 + j for j in range(1, 30)]
    for j, k in enumerate(t_arr):
        iface["intact"][k:k + (4 if j <= 30 else 1), j] = 0
    (f,) = catalogue(iface)
    dx = 1 / NS
    assert f.tip["v"][5] == pytest.approx(dx / (4 * DT)) and f.tip["v"][-5] == pytest.approx(dx / DT)
    assert iface["x"][29] <= f.accel_x <= iface["x"][33]
    assert f.max_speed == pytest.approx(dx / DT)
    assert f.mean_speed == pytest.approx(59 * dx / (149 * DT))


def test_short_flicker_is_not_a_front():
    iface = blank(50)
    iface["intact"][5:8, 10:13] = 0                 # three sites, below min_sites
    assert catalogue(iface) == []
    tb, xb = F.first_break(iface)
    assert tb == 5 * DT and list(xb) == list(iface["x"][10:13])


def test_real_run_catalogue(small_run):
    """The SMALL push run: pulses from the rear edge toward x = 1, slower than c_r, each carrying slip;
    the tip trajectory sits on the first broken bond of the space-time map."""
    run = parslip.open(small_run)
    fr = run.fronts()
    assert len(fr) >= 3
    it = run.interface
    for f in fr:
        assert f.direction == 1 and f.nucleation_x < 0.05 and f.kind == "pulse"
        assert 0 < f.mean_speed < 1.0 and f.slip_u > 0
        assert 1 <= f.width <= 3
        # Each arrival is a break event of that site at that step, exact to dt, and the last frame before
        # it shows the bond intact.
        ev = run.events
        assert f.resolution == pytest.approx(run.attrs["dt"] * run.attrs["c_r"] / run.attrs["l"])
        for step, tj, xj in zip(f.tip["step"], f.tip["t"], f.tip["x"]):
            s = int(np.argmin(np.abs(run.x - xj)))
            hit = (ev["step"] == step) & (ev["site"] == s) & (ev["kind"] == 1)
            assert hit.sum() == 1 and ev["time"][hit][0] == tj
            k = int(np.searchsorted(it["step"], step, side="right")) - 1
            assert it["intact"][k, s] == 1
    # Each pulse moves the bonds it passes on by one substrate site (the partner index),
    # so the slip it carries is about one lattice spacing, 1/24 l here.
    # The first carries more (its window starts at t = 0, with the loading: Sec. 3.4).
    p = it["partner"]
    du = [float(np.median(f.tip["du"][(f.tip["x"] > 0.2) & (f.tip["x"] < 0.8)])) for f in fr[:-1]]
    assert du[1:] == pytest.approx([1 / 24] * (len(du) - 1), rel=0.25)
    assert du[0] > max(du[1:])
    s = len(run.x) // 2
    hops = np.diff(p[:, s][p[:, s] >= 0]).sum()
    passed = sum(1 for f in fr if f.tip["x"].max() >= run.x[s])
    assert hops == passed


def test_cli_json_fields(small_run, capsys):
    assert main(["fronts", small_run, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)["fronts"]
    fr = parslip.open(small_run).fronts()
    assert len(out) == len(fr)
    keys = {"nucleation_time", "nucleation_x", "direction", "kind", "mean_speed", "max_speed",
            "width", "slip_u", "slip_v", "tip", "fate", "arrest_length"}
    assert keys <= set(out[0]) and {"t", "x", "v"} <= set(out[0]["tip"])
    assert out[0]["tip"]["x"] == pytest.approx(list(fr[0].tip["x"]))
    assert main(["fronts", small_run]) == 0
    text = capsys.readouterr().out
    assert "pulse" in text and "l/c_r" in text


@pytest.mark.parametrize("argv,message", [
    (["fronts", "/nonexistent.vtkhdf"], "RUN '/nonexistent.vtkhdf': no such file"),
    (["fronts", "RUN", "--min-sites", "0"], "--min-sites 0: out of range"),
])
def test_cli_bad_input_one_line(argv, message, small_run, capsys):
    argv = [small_run if a == "RUN" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err
