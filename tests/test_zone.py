"""The cohesive zone's width at an instant (``analysis.zone``) against fronts drawn with a known zone.

A synthetic interface record: a tail path x_t(t) (the sites reaching the residual: their breaks) and a head
path x_h(t) = x_t(t) + X(t) / l (the sites at their peak), each site's traction a tent that rises to tau_p at
the head's arrival and falls to 0 at the tail's, sampled at frames of one spacing.  The measure must give
X(t) at the breaks, from the frames alone (the peak times) and the break times, to the frames' resolution:
for a steady front and for one that accelerates while its zone shrinks (where a duration times a speed would
not give the width).
"""
import math

import numpy as np
import pytest

from parslip.analysis.zone import path_at, peak_times, zone_width

N = 400                  # sites; l = N a


def record(tail, width, t_end: float, dt_frame: float):
    """(x, t_peak, t_break, frames' times, sxy): sites at x_j = (j + 1/2)/N (l), the tail's path x_t(t) and
    the zone's width X(t) (a) given as functions, both sampled on a fine time grid and inverted by
    interpolation (each path moves forward)."""
    x = (np.arange(N) + 0.5) / N
    fine = np.linspace(0.0, t_end, 200001)
    xt = tail(fine)
    xh = xt + width(fine) / N
    t_break = np.interp(x, xt, fine, left=np.nan, right=np.nan)
    t_peak = np.interp(x, xh, fine, left=np.nan, right=np.nan)
    times = np.arange(0.0, t_end, dt_frame)
    rise, fall = 0.5, 1.0                                   # tau_p / time to the peak, and after it
    tp, tb = t_peak[None, :], t_break[None, :]
    before = 1.0 - (tp - times[:, None]) * rise
    after = 1.0 - (times[:, None] - tp) / (tb - tp) * fall
    sxy = np.where(times[:, None] <= tp, np.maximum(before, 0.3), np.maximum(after, 0.0))
    return x, t_peak, t_break, times, sxy


def test_path_at_interpolates_arrivals_and_is_nan_outside():
    x = np.array([0.1, 0.2, 0.3])
    assert path_at(x, [1.0, 2.0, 4.0], [1.5, 3.0]) == pytest.approx([0.15, 0.25])
    assert np.isnan(path_at(x, [1.0, 2.0, 4.0], [0.5, 4.5])).all()
    # a site reached out of turn counts as reached with the next
    assert path_at(x, [1.0, 3.0, 2.0], [2.5]) == pytest.approx([0.175])


def test_a_steady_front_gives_its_zone_width_to_a_fraction_of_a_frame():
    """v = 0.5 l per unit time (200 a per unit), X = 12 a: each site's peak comes X / v = 0.06 before its break;
    frames every 0.01 (2 a of travel).  The width at every break lies within 0.5 a of 12 a (a quarter of a
    frame's travel), and the peak times within a quarter frame."""
    v, X = 0.5, 12.0
    x, tp, tb, times, sxy = record(lambda t: 0.05 + v * t, lambda t: X + 0 * t, 1.6, 0.01)
    got = peak_times(times, sxy, tb)
    inside = np.isfinite(tb) & np.isfinite(tp) & (tp > 0.05) & (tb < 1.5)
    assert np.max(np.abs(got[inside] - tp[inside])) < 0.25 * 0.01
    w = zone_width(x, got, tb, +1, N)[inside]
    w = w[np.isfinite(w)]
    assert len(w) > 250
    assert np.max(np.abs(w - X)) < 0.5
    assert np.mean(w) == pytest.approx(X, abs=0.1)


def test_an_accelerating_front_gives_the_width_at_each_instant():
    """x_t = 0.02 + 0.25 t^2 (the speed 0.5 t grows from 0.1 to 0.75 l per unit time) while the zone shrinks as
    X(t) = 25 (1 - t/3) a: at each break the measure gives X at that instant within 0.5 a, where the peak-to-
    break duration times the tail's speed misses it by more than 1 a on most sites."""
    tail = lambda t: 0.02 + 0.25 * t * t                   # noqa: E731
    width = lambda t: 25.0 * (1.0 - t / 3.0)                # noqa: E731
    x, tp, tb, times, sxy = record(tail, width, 1.5, 0.005)
    got = peak_times(times, sxy, tb)
    w = zone_width(x, got, tb, +1, N)
    ok = np.isfinite(w) & (tb > 0.2) & (tb < 1.45)
    assert ok.sum() > 150
    assert np.max(np.abs(w[ok] - width(tb[ok]))) < 0.5
    duration = 0.5 * tb[ok] * (tb[ok] - got[ok]) * N         # the tail's speed times the zone's duration
    assert np.mean(np.abs(duration - width(tb[ok])) > 1.0) > 0.5


def test_a_front_running_the_other_way_gives_a_positive_width():
    x, tp, tb, times, sxy = record(lambda t: 0.05 + 0.5 * t, lambda t: 10.0 + 0 * t, 1.6, 0.01)
    mirrored = 1.0 - x
    w = zone_width(mirrored, peak_times(times, sxy, tb), tb, -1, N)
    assert np.nanmedian(w) == pytest.approx(10.0, abs=0.3)


def test_peak_times_ignores_frames_after_the_break():
    """A traction that rises again after the break (a re-formed bond) does not move the peak."""
    times = np.linspace(0, 1, 11)
    s = np.array([0.0, 0.5, 1.0, 0.6, 0.2, 0.0, 0.0, 2.0, 3.0, 0.0, 0.0])[:, None]
    assert peak_times(times, s, [0.45])[0] == pytest.approx(0.2, abs=0.05)
    assert math.isnan(peak_times(times, s, [-1.0])[0])


def test_the_local_static_zone_is_the_formula_at_the_peak_reached():
    """X_c0_local (``studies.weakening.cohesive_zone.local_zone``) is c M Gamma / tau_p^2 recomputed with the peak
    the sites reached: tau_p and x_b scaled by r, Gamma = tau_p (x_b + D_c) / 2, so X_c0 scales as
    (r x_b + D_c) / ((x_b + D_c) r); r = 1 gives the scene's X_c0, and with a residual it is not defined."""
    from parslip.studies.weakening.cohesive_zone import local_zone
    scales = {"tau_p": 0.17, "tau_r": 0.0, "x_b": 0.5, "D_c": 3.0, "X_c0": 24.0}
    assert local_zone(scales, 0.17)["X_c0"] == pytest.approx(24.0)
    for r in (0.9, 1.1):
        tp, xb = 0.17 * r, 0.5 * r
        ratio = (tp * (xb + 3.0) / 2 / tp ** 2) / (0.17 * 3.5 / 2 / 0.17 ** 2)
        got = local_zone(scales, tp)
        assert got["ratio"] == pytest.approx(r)
        assert got["X_c0"] == pytest.approx(24.0 * ratio)
    assert math.isnan(local_zone({**scales, "tau_r": 0.01}, 0.17)["X_c0"])
