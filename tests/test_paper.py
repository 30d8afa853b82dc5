"""The paper-comparison table on drawn runs whose every measured quantity is known beforehand."""
import numpy as np
import pytest

from helpers import DT, NS, blank, draw
from parslip.analysis import paper
from parslip.analysis.results import Run

DX = 1 / NS


def pulses(k0s, d, fps, width=2, slip=0.01, nf=1000, mode="push", v0=1e-3, crack=False):
    iface = blank(nf)
    for k0 in k0s:
        draw(iface, k0, 0 if d > 0 else NS - 1, d, fps, width, slip, crack=crack)
    return Run.from_arrays(iface, {"drive.mode": mode, "drive.v0": v0})


@pytest.fixture(scope="module")
def runs():
    k0s = [100, 300, 500, 700]                           # 5, 15, 25, 35 l/c_r
    return {
        "push": pulses(k0s, +1, 2),
        "pull": pulses(k0s, -1, 4, mode="pull"),         # half the speed
        "shear": pulses([1300], +1, 1, slip=0.008, nf=1400, mode="shear", v0=1e-4, crack=True),
        "push_v0_1e-2": pulses(k0s, +1, 1, v0=2e-3),     # twice v0, twice the speed
    }


def row(rows, start):
    (r,) = [r for r in rows if r["quantity"].startswith(start)]
    return r


def test_measurements_of_drawn_runs(runs):
    push, pull, shear = runs["push"], runs["pull"], runs["shear"]
    assert paper.nucleation_times(push) == pytest.approx([5, 15, 25, 35])
    assert paper.interval(push) == pytest.approx(10) and paper.interval(pull) == pytest.approx(10)
    assert paper.mean_steady_speed(push) == pytest.approx(DX / (2 * DT))
    assert paper.mean_steady_speed(pull) == pytest.approx(DX / (4 * DT))
    assert paper.steady_width(push) == 2 and paper.median_slip(push) == pytest.approx(0.01)
    assert paper.first_break_time(shear) == pytest.approx(65.0)
    assert paper.crack_speed(shear) == pytest.approx(DX / DT)
    assert [f.kind for f in shear.fronts()] == ["crack"]


def test_comparison_table(runs):
    rows = paper.comparison(runs)
    assert len(rows) == len(paper.CLAIMS)
    assert row(rows, "T- first four nucleation times")["parslip"] == "5, 15, 25, 35"
    assert row(rows, "T- first four nucleation times")["paper"] == "5.1, 15.1, 25.2, 35.1"
    assert row(rows, "T+ / T- pulse speed")["parslip"] == "0.5"
    assert row(rows, "T0 first break")["parslip"] == "65"
    assert row(rows, "slip per front, T- / T0")["parslip"] == "1.25"
    assert row(rows, "T0 kind")["parslip"] == "0 pulse, 1 crack"
    assert row(rows, "T- pulse speed proportional")["parslip"].startswith("not run (push_v0_1e-4)")
    md = paper.markdown(rows)
    lines = md.strip().splitlines()
    assert lines[0].startswith("| quantity |") and len(lines) == 2 + len(paper.CLAIMS)
    assert all(line.count(" | ") == 4 for line in lines)


def test_v0_sweep_row_reports_the_spread(runs):
    full = dict(runs, **{"push_v0_1e-4": pulses([100, 300, 500, 700], +1, 4, v0=5e-4)})
    text = row(paper.comparison(full), "T- pulse speed proportional")["parslip"]
    v_over_v0 = DX / (2 * DT) / 1e-3
    assert text == f"v/v0 = {v_over_v0:.3g}, {v_over_v0:.3g}, {v_over_v0:.3g} (max/min 1)"


def test_scenes_exist():
    import os
    here = os.path.join(os.path.dirname(__file__), "..", "run")
    for name in paper.SCENES.values():
        assert os.path.exists(os.path.join(here, name)), name


def test_reproduce_from_a_directory_of_runs(small_run, tmp_path):
    """With only a push run present: its figure set, and a table that says what was not run."""
    import os
    runs_dir, out = tmp_path / "runs", tmp_path / "out"
    runs_dir.mkdir()
    os.symlink(small_run, runs_dir / "push.vtkhdf")
    runs = paper.reproduce(str(runs_dir), str(out))
    assert set(runs) == {"push"}
    assert (out / "push" / "spacetime.png").exists() and (out / "push" / "front_speed.pdf").exists()
    md = (out / "comparison.md").read_text()
    rows = paper.comparison(runs)
    assert md == paper.markdown(rows)
    assert row(rows, "T+ first four").get("parslip") == "not run (pull)"
    times = [f.nucleation_time for f in runs["push"].fronts() if f.nucleation_x < 0.05][:4]
    assert row(rows, "T- first four").get("parslip") == ", ".join(f"{t:.3g}" for t in times)


def test_section_width_is_the_median_interior_white_run():
    iface = blank(10)
    it = iface["intact"]
    it[5, 10:13] = 0            # 3 sites
    it[5, 30:35] = 0            # 5 sites
    it[5, 0:2] = 0              # touches the rear edge: a pulse being born, left out
    it[5, NS - 1] = 0           # touches the front edge
    run = Run.from_arrays(iface, {"drive.mode": "push", "drive.v0": 1e-3})
    assert paper.section_width(run, 5 * DT) == 4.0
    assert np.isnan(paper.section_width(run, 0.0))


def test_far_edge_width_and_speed_ratios(runs):
    assert paper.far_edge_width(runs["shear"]) == NS        # the drawn crack: every bond broken at the end
    assert paper.far_edge_width(runs["push"]) == 2          # the width-2 pulse
    assert paper.speed_ratio(runs["pull"], runs["push"]) == pytest.approx(0.5)
    assert paper.speed_ratio(runs["pull"], runs["push"], how="mean") == pytest.approx(0.5)


def test_unit_factors_are_the_surface_wave_speeds():
    """0.9475 c_s (the Born surface wave) and c_s over the classical 0.9110 c_s (README, Units)."""
    assert paper._unit_factor("c_r") == 1.0
    assert paper._unit_factor("born") == pytest.approx(0.9475 / 0.9110, abs=2e-4)
    assert paper._unit_factor("c_s") == pytest.approx(1 / 0.9110, abs=2e-4)
    key, value = paper._v0_in("c_s").split("=")
    assert key == "drive.v0" and float(value) == pytest.approx(1e-4 / 0.9110, rel=2e-4)


def test_variations_read_baseline_and_varied_runs(runs, small_run, tmp_path):
    """An analysis-only variation reads the baseline runs both ways; a scene variation reads its own
    file under run_dir/variations, or says it was not run."""
    import os
    import parslip
    os.makedirs(tmp_path / "variations")
    os.symlink(small_run, tmp_path / "variations" / "push__have.vtkhdf")
    small = parslip.open(small_run)
    vs = [paper.Variation("ana", "d", "r", ("push",), (), lambda r: paper.steady_width(r["push"]) + 1, "a",
                          "~1", baseline=lambda r: paper.steady_width(r["push"])),
          paper.Variation("have", "d", "r", ("push",), ("time.zeta=0.2",),
                          lambda r: paper.first_break_time(r["push"]), "l/c_r"),
          paper.Variation("missing", "d", "r", ("push",), ("time.zeta=0.3",),
                          lambda r: paper.first_break_time(r["push"]), "l/c_r"),
          paper.Variation("no_role", "d", "r", ("pull_x",), (), lambda r: 0)]
    rows = paper.run_variations(runs, str(tmp_path), variations=vs)
    t_push = paper._fmt(paper.first_break_time(runs["push"]))          # 5 l/c_r, the drawn first pulse
    assert [r["baseline"] for r in rows] == ["2", t_push, t_push]       # no_role: its run is absent, no row
    assert rows[0]["varied"] == "3" and rows[0]["change"] == "(analysis only)"
    assert rows[1]["varied"] == paper._fmt(paper.first_break_time(small))
    assert rows[2]["varied"] == "not run"
    md = paper.variations_markdown(rows)
    assert md.count("\n") == 2 + 3 and "time.zeta=0.2" in md


def test_pulse_count_includes_a_young_front_cut_short_by_the_record():
    """Three full pulses, a fourth born 3 frames before the end (two sites broken: young, counted) and
    a two-site blip at the edge that stopped long before the end (small, not counted)."""
    nf = 400
    iface = blank(nf)
    for k0 in (10, 110, 210):
        draw(iface, k0, 0, +1, 1, 2, 0.01, sites=30)
    draw(iface, 160, 0, +1, 1, 1, 0.0, sites=2)            # the blip: re-bonds at once, never grows
    it = iface["intact"]                                    # the young pulse, drawn by hand: no re-bond yet
    it[nf - 3, 0] = it[nf - 2, 0:2] = it[nf - 1, 1:3] = 0
    run = Run.from_arrays(iface, {"drive.mode": "push", "drive.v0": 1e-3})
    assert len(paper.edge_fronts(run)) == 3
    got = [round(f.nucleation_time / DT) for f in paper.edge_nucleations(run)]
    assert got == [10, 110, 210, nf - 3]
