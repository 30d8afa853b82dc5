"""Interfaces beyond the paper: per-site bond properties (patches, a seeded random field) and healing.

Each law is checked against what it must reproduce exactly (the uniform run, the 1-rank run, the
uninterrupted run) and against what it promises physically (no bond re-forms before heal_time; a heal
speed no slip reaches changes nothing; a strong patch holds bonds that break elsewhere).
"""
import numpy as np
import pytest

import parslip
from helpers import SMALL, datasets, require, run_cli, run_small, scene, small_toml
from parslip.cli import main
from parslip.io.contract import EVENT_BREAK, EVENT_FORM
from parslip.model.interface import InterfaceLaw, random_field
from parslip.scene.derive import derive

STRONG = [{"x": [0.4, 0.6], "delta_b": 0.9}]
RANDOM = {"interface.random.key": "delta_b", "interface.random.cv": 0.1, "interface.random.correlation": 5.0,
          "interface.random.seed": 7}


def _interface(path) -> dict:
    data, attrs = datasets(path)
    assert attrs["status"] == "complete", attrs["status"]
    return {k: v for k, v in data.items() if k.startswith("interface/")}


def _run(tmp_path, name, n=1, **sets):
    return run_small(tmp_path, name, n, timeout=150, **sets)[1]


def test_a_patch_with_the_scenes_own_values_is_the_uniform_run(tmp_path):
    """A patch over the whole contact that sets kx, ky and delta_b to the scene's values changes no bit."""
    whole = [{"x": [0.0, 1.0], "kx": 0.1, "ky": 0.3, "delta_b": 0.7}]
    a = _interface(_run(tmp_path, "uniform"))
    b = _interface(_run(tmp_path, "patched", **{"interface.patch": whole}))
    assert a.keys() == b.keys() and len(a["interface/events/step"]) > 10
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name


@pytest.mark.parametrize("law", ["strong patch", "random field"])
def test_heterogeneous_interfaces_are_rank_invariant(tmp_path, law):
    """A strong patch and a random delta_b field: the 3-rank run is the 1-rank run, bit for bit, and the
    file records the values that ran."""
    sets = {"interface.patch": STRONG} if law == "strong patch" else dict(RANDOM)
    one, three = (_interface(_run(tmp_path, "h", n, **sets)) for n in (1, 3))
    for name in one:
        assert one[name].tobytes() == three[name].tobytes(), name
    want = derive(scene(**SMALL, **sets)).law.site_values(len(one["interface/x"]))
    for key in ("kx", "ky", "delta_b"):
        np.testing.assert_array_equal(one[f"interface/{key}"], want[key])
    assert one["interface/delta_b"].max() > 0.7 and one["interface/delta_b"].min() > 0.5


def test_a_strong_patch_holds_its_bonds_longer():
    """Bonds whose delta_b is 0.9 a instead of 0.7 a break later under the same push: the first break in the
    patch comes after the first break outside it (an independent reading of the same events)."""
    base = {**SMALL, "output.snapshots": 0, "drive.duration": 8.0}
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        parslip.run({**base, "interface.patch": [{"x": [0.0, 1.0], "delta_b": 0.9}]}, out=f"{d}/s.vtkhdf",
                    progress=False)
        parslip.run(base, out=f"{d}/u.vtkhdf", progress=False)
        strong, uniform = parslip.open(f"{d}/s.vtkhdf"), parslip.open(f"{d}/u.vtkhdf")
        tb = [r.first_break[0] for r in (strong, uniform)]
    assert tb[1] is not None and (tb[0] is None or tb[0] > tb[1])


def test_the_random_field_has_its_statistics_on_the_shipped_contact():
    """100 sites, cv 0.1, correlation 5 a, seed 7: the sample cv within 0.05-0.15 and the mean within 5 % of
    the scene's delta_b, every value above delta0; the same seed gives the same field; the field's lag-1
    correlation is that of a correlated field (well above white noise's 0)."""
    law = derive(scene(**RANDOM)).law
    v = law.site_values(100)["delta_b"]
    assert 0.05 <= v.std() / v.mean() <= 0.15 and abs(v.mean() / 0.7 - 1) < 0.05 and v.min() > 0.5
    np.testing.assert_array_equal(v, derive(scene(**RANDOM)).law.site_values(100)["delta_b"])
    g = np.log(random_field(2000, 0.3, 5.0, 3))
    g = (g - g.mean()) / g.std()
    lag1 = float(np.mean(g[1:] * g[:-1]))
    assert lag1 == pytest.approx(np.exp(-1 / (2 * 5.0 ** 2)), abs=0.05)      # C(r) = exp(-r^2 / 2 xi^2)


def test_a_correlation_beyond_ten_contact_lengths_is_ten_contact_lengths():
    """Correlation 1e9 a on 100 sites (once a 42 GiB kernel) is the field of 1e3 a = 10 contact lengths, as
    is 1e6 a, built in well under a megabyte; its statistics are those of any field (mean about 1, cv about
    cv), and its g is nearly the straight ramp +-sqrt(3) (2x - 1) the docstring gives: median rms distance
    0.026 and 90th percentile 0.14 over seeds 0-299, against 0.21 and 0.74 at one contact length."""
    import tracemalloc
    tracemalloc.start()
    far = random_field(100, 0.1, 1e9, 7)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 2 ** 20
    np.testing.assert_array_equal(far, random_field(100, 0.1, 1e6, 7))
    np.testing.assert_array_equal(far, random_field(100, 0.1, 1e3, 7))
    assert far.mean() == pytest.approx(1.0, abs=0.002) and far.std() / far.mean() == pytest.approx(0.1, rel=0.05)
    x = (np.arange(100) + 0.5) / 100
    ramp = (x - x.mean()) / x.std()

    def off_ramp(correlation):
        d = []
        for seed in range(300):
            g = np.log(random_field(100, 0.1, correlation, seed))
            g = (g - g.mean()) / g.std()
            d.append(np.sqrt(max(0.0, 1 - (g @ ramp / 100) ** 2)))     # rms of g off its best ramp
        return np.median(d), np.quantile(d, 0.9)
    assert off_ramp(1e9) == pytest.approx((0.026, 0.14), abs=0.005)
    assert off_ramp(100.0) == pytest.approx((0.21, 0.74), abs=0.01)


def test_heal_time_delays_every_re_formation():
    """heal_time = 0.5 l/c_r under shear: no bond re-forms sooner than 0.5 l/c_r after it broke, measured from
    the exact events; without healing some re-form within the step they broke or soon after."""
    import tempfile
    base = {**SMALL, "drive.mode": "shear", "drive.v0": 0.05, "drive.duration": 8.0, "output.snapshots": 0}
    gaps = {}
    with tempfile.TemporaryDirectory() as d:
        for ht in (0.0, 0.5):
            parslip.run({**base, "interface.heal_time": ht}, out=f"{d}/{ht}.vtkhdf", progress=False)
            ev = parslip.open(f"{d}/{ht}.vtkhdf").events
            g = []
            for s in np.unique(ev["site"]):
                m = ev["site"] == s
                k, t = ev["kind"][m], ev["time"][m]
                g += [t[i + 1] - t[i] for i in range(len(k) - 1) if k[i] == EVENT_BREAK and k[i + 1] == EVENT_FORM]
            gaps[ht] = np.array(g)
    assert len(gaps[0.5]) > 5 and gaps[0.5].min() >= 0.5
    assert gaps[0.0].min() < 0.5


def test_a_heal_speed_no_slip_reaches_changes_nothing(tmp_path):
    """heal_speed = 1e9 c_r is never reached: bitwise the default run; a heal speed below the slip speeds of
    the pulses holds bonds back from re-forming."""
    a = _interface(_run(tmp_path, "default"))
    b = _interface(_run(tmp_path, "fast", **{"interface.heal_speed": 1e9}))
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name
    c = _interface(_run(tmp_path, "slow", **{"interface.heal_speed": 1e-4}))
    forms = lambda d: int((d["interface/events/kind"] == EVENT_FORM).sum())        # noqa: E731
    assert forms(c) < forms(a)


def test_the_float32_heal_clock_limit_counts_the_steps_the_loop_counts():
    """float32 counts the healing clock (up to n_heal + 1) exactly below 2^24: the limit refuses a heal_time
    by the loop's own n_heal = ceil(heal_time / dt), so the largest accepted heal_time, which the message
    names, is accepted, half a step longer (2^24 - 1 steps once rounded up) is refused, and the loop is given
    the same n_heal."""
    import re

    from parslip.errors import ConfigError
    base = derive(scene(**{"time.precision": "float32"}))
    hi = (2 ** 24 - 2) * base.dt / base.t_unit
    ok = derive(scene(**{"time.precision": "float32", "interface.heal_time": hi}))
    assert ok.law.heal_steps(ok) == ok.law.rules(np.float32, ok).n_heal == 2 ** 24 - 2
    with pytest.raises(ConfigError, match=re.escape(f"accepted: interface.heal_time <= {hi:.4g} l/c_r")):
        derive(scene(**{"time.precision": "float32", "interface.heal_time": (2 ** 24 - 1.5) * base.dt / base.t_unit}))


def test_healing_and_a_random_field_survive_a_restart_on_another_rank_count(tmp_path):
    """heal_time and a random field: 3 l/c_r on 2 ranks, continued to 6 on 3 ranks, equals 6 at once on one
    rank: the clocks and candidates travel with the checkpoint and the halo."""
    require("gather")
    sets = {"interface.heal_time": 0.3, **RANDOM, "checkpoint.every": 1.0, "output.snapshots": 0,
            "drive.mode": "shear", "drive.v0": 0.05}
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**sets))
    ref, out = tmp_path / "ref.vtkhdf", tmp_path / "o.vtkhdf"
    assert run_cli(1, "run", sc, "--out", ref, "--no-png", "--quiet").returncode == 0
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "drive.duration=3.0")
    assert p.returncode == 0, p.stderr
    p = run_cli(3, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", str(out) + ".ckpt.h5", timeout=150)
    assert p.returncode == 0, p.stderr
    a, b = _interface(ref), _interface(out)
    assert (a["interface/events/kind"] == EVENT_FORM).sum() > 0
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name


@pytest.mark.parametrize("setting,message", [
    ("interface.patch=[{x=[0.6,0.4], delta_b=0.9}]", "interface.patch[0].x = [0.6, 0.4]: reversed"),
    ("interface.patch=[{x=[0.4,1.2]}]", "outside the contact"),
    ("interface.patch=[{x=[0.4,0.6], delta_b=0.5}]", "interface.patch[0].delta_b = 0.5: at or below delta0"),
    ("interface.random.cv=-0.1", "interface.random.cv = -0.1: out of range"),
    ("interface.random.correlation=-1", "interface.random.correlation = -1.0: out of range"),
    ("interface.random.key=k_y", "interface.random.key = 'k_y': out of range; accepted: 'kx', 'ky', 'delta_b' or "
                                 "'softening'"),
    ("interface.heal_time=-1", "interface.heal_time = -1.0: out of range"),
    ("interface.heal_speed=-1", "interface.heal_speed = -1.0: out of range"),
])
def test_bad_interface_laws_get_one_line_and_exit_2(tmp_path, capsys, setting, message):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml())
    assert main(["run", str(sc), "--out", str(tmp_path / "o.vtkhdf"), "--set", setting]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and "unknown key" not in err


def test_the_reference_engine_refuses_laws_it_does_not_have():
    from parslip.engine.reference_engine import Simulation as Reference
    for sets in ({"interface.heal_time": 0.5}, {"interface.patch": STRONG}):
        with pytest.raises(NotImplementedError, match="interface"):
            Reference(derive(scene(**SMALL, **sets)))
    assert InterfaceLaw.from_scene(scene()).unlike_reference() == []


# ------------------------------------------------------------------------ loading through springs, rows --

def _first_break(tmp_path, name, **sets):
    import tempfile  # noqa: F401
    base = {**SMALL, "output.snapshots": 0, "drive.duration": 8.0, **sets}
    out = tmp_path / f"{name}.vtkhdf"
    parslip.run(base, out=str(out), progress=False)
    return parslip.open(str(out))


def test_a_stiff_loader_is_the_prescribed_drive_and_a_soft_one_breaks_later(tmp_path):
    """drive.spring = 100 (far stiffer than the block's k_n = 2.8) breaks first within 2 % of the prescribed
    drive; 0.05 breaks later; the drive force is the springs' force, and the loader moves at v0."""
    ref = _first_break(tmp_path, "ref")
    stiff = _first_break(tmp_path, "stiff", **{"drive.spring": 100.0})
    soft = _first_break(tmp_path, "soft", **{"drive.spring": 0.05})
    t0 = ref.first_break[0]
    assert abs(stiff.first_break[0] / t0 - 1) < 0.02
    assert soft.first_break[0] is None or soft.first_break[0] > 1.1 * t0
    it = stiff.interface
    np.testing.assert_allclose(it["loader"], it["time"] * stiff.v0, rtol=1e-9, atol=1e-15)
    # The springs carry the load the prescribed face took (on average: a stiff spring rings at sqrt(k_s)).
    assert it["drive_force"].mean() == pytest.approx(ref.interface["drive_force"].mean(), rel=0.05)


def test_driven_rows_change_where_the_block_is_pushed(tmp_path):
    """drive.rows = [0, 1]: only the two lowest rows of the rear face are pushed; the first break moves."""
    ref = _first_break(tmp_path, "ref")
    low = _first_break(tmp_path, "low", **{"drive.rows": [0, 1]})
    assert low.first_break[0] != ref.first_break[0]
    assert low.first_break[0] is not None


def test_a_spring_stiffer_than_the_lattice_sets_the_time_step_and_stays_stable(tmp_path):
    """A loader spring of 1e4 on a rigid substrate: omega_max grows to at least sqrt(k_s), dt follows, and the
    run stays finite (the extreme case the stability limit must cover)."""
    st = derive(scene(**SMALL, **{"lattice.substrate": "rigid", "drive.spring": 1e4}))
    assert st.omega_max >= 100.0 and st.dt < 2 / 100.0
    run = _first_break(tmp_path, "extreme", **{"lattice.substrate": "rigid", "drive.spring": 1e4,
                                                "drive.duration": 2.0})
    assert np.isfinite(run.interface["ux"]).all() and run.status == "complete"


def test_springs_and_rows_are_rank_invariant_across_a_restart(tmp_path):
    """A soft loader on the two lowest rows: 3 l/c_r on 3 ranks continued to 6 on 2 equals 6 at once on one."""
    require("gather")
    sets = {"drive.spring": 0.5, "drive.rows": [0, 1], "checkpoint.every": 1.0, "output.snapshots": 0}
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**sets))
    ref, out = tmp_path / "ref.vtkhdf", tmp_path / "o.vtkhdf"
    assert run_cli(1, "run", sc, "--out", ref, "--no-png", "--quiet").returncode == 0
    p = run_cli(3, "run", sc, "--out", out, "--no-png", "--quiet", "--set", "drive.duration=3.0", timeout=150)
    assert p.returncode == 0, p.stderr
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", str(out) + ".ckpt.h5")
    assert p.returncode == 0, p.stderr
    a, b = _interface(ref), _interface(out)
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name


@pytest.mark.parametrize("settings,message", [
    (("drive.mode=shear", "drive.rows=[0,1]"), "drive.rows = [0, 1]: only a push or a pull"),
    (("drive.rows=[2,9]",), "drive.rows = [2, 9]: out of range"),
    (("drive.rows=[1,0]",), "drive.rows = [1, 0]: out of range"),
    (("drive.spring=-1",), "drive.spring = -1.0: out of range"),
])
def test_bad_drives_get_one_line_and_exit_2(tmp_path, capsys, settings, message):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml())
    argv = ["run", str(sc), "--out", str(tmp_path / "o.vtkhdf")]
    for s in settings:
        argv += ["--set", s]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err
