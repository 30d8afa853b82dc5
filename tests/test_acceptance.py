"""The paper's three rupture modes from the shipped scenes (shortened in time only).

T-  push : first break at the rear edge x/l = 0 near t c_r/l = 5; new pulses
           nucleate there about every 10 l/c_r and run forward at v << c_r.
T+  pull : the mirror image, from x/l = 1 backward.
T0  shear: no break for a long time (paper: about 65 l/c_r), then one front
           from the rear edge across the whole interface near c_r.
"""
import os

import pytest

import parslip
from parslip import analysis
from parslip.cli import main

RUN = os.path.join(os.path.dirname(__file__), "..", "run")


def _run(tmp_path, name, *sets):
    out = tmp_path / f"{name}.vtkhdf"
    args = ["run", os.path.join(RUN, f"{name}.toml"), "--out", str(out), "--quiet", "--no-png"]
    for s in sets:
        args += ["--set", s]
    assert main(args) == 0
    return parslip.open(str(out))


# The push scene in float64 for 33 l/c_r (three pulses), run once for the module: the pulses' test and the
# float32 test's reference.
PUSH_64 = ("drive.duration=33.0", "output.snapshots=0")


@pytest.fixture(scope="module")
def push_float64(tmp_path_factory):
    return _run(tmp_path_factory.mktemp("push_float64"), "push", *PUSH_64, "time.precision=float64")


@pytest.mark.slow
@pytest.mark.parametrize("name,edge,direction", [("push", 0.0, 1), ("pull", 1.0, -1)])
def test_pulses_nucleate_at_the_driven_edge(tmp_path, request, name, edge, direction):
    if name == "push":
        run = request.getfixturevalue("push_float64")
    else:
        run = _run(tmp_path, name, "drive.duration=27.0", "output.snapshots=0")
    t0, x0 = analysis.first_break(run.interface)
    assert 4.0 < t0 < 6.5
    assert all(abs(x - edge) < 0.02 for x in x0)
    fr = [f for f in run.fronts() if abs(f.x_start - edge) < 0.05]
    assert len(fr) >= 2
    assert all(f.direction == direction for f in fr)
    assert all(f.speed < 0.05 for f in fr)                         # slow: v << c_r
    period = fr[1].t_start - fr[0].t_start
    assert 7.0 < period < 13.0                                      # about every 10 l/c_r


@pytest.mark.slow
def test_shear_gives_one_late_fast_crack(tmp_path):
    run = _run(tmp_path, "shear", "drive.duration=73.0", "output.snapshots=0")
    t0, x0 = analysis.first_break(run.interface)
    assert 55.0 < t0 < 75.0
    assert min(x0) < 0.05                                           # starts at the rear edge
    fr = run.fronts()
    assert fr and fr[0].direction == 1 and fr[0].sites == 100
    assert fr[0].speed > 0.7                                        # near c_r


@pytest.mark.slow
def test_float32_keeps_the_push_scene_within_one_percent(tmp_path, push_float64):
    """Displacements in float32 (differences formed first) keep the push scene's first break and
    nucleation interval within 1 % of float64, over the first three pulses."""
    res = {}
    for prec in ("float64", "float32"):
        run = push_float64 if prec == "float64" else _run(tmp_path, "push", *PUSH_64, f"time.precision={prec}")
        assert run.scene["time.precision"] == prec
        t0, _ = analysis.first_break(run.interface)
        fr = [f for f in run.fronts() if f.x_start < 0.05]
        res[prec] = (t0, fr[1].t_start - fr[0].t_start, fr[2].t_start - fr[1].t_start)
    for a, b in zip(res["float64"], res["float32"]):
        assert b == pytest.approx(a, rel=0.01), res
