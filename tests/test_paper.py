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
