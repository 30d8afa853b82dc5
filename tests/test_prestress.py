"""A held prestress (``drive.prestress``) and a nucleation (``interface.nucleation``) in it.

The drive stops at the first reading of the interface's mean shear traction at or above tau_0 and the
loader holds; the nucleation's zone breaks at the steps its rule gives, counted from the held prestress;
both are decided from exact sums, so 1 and 3 ranks, and a restart on another rank count, give the same bits.
Bad values of the new keys are refused with one line (exit 2).
"""
import math

import h5py
import numpy as np
import pytest

from helpers import SMALL, datasets, run_cli, run_small, scene, small_toml
from parslip.cli import main
from parslip.io.contract import EVENT_BREAK
from parslip.scene.derive import derive

# SMALL sheared slowly, with weakening bonds, strong edges (delta_b 1.0 outside [0.2, 0.8]), and the mean read
# between them: held at 0.03 rho c_r^2 (0.58 of the bonds' mean peak there), settled 1 l/c_r.
HELD = {"drive.mode": "shear", "drive.v0": 0.01, "drive.duration": 6.0, "output.snapshots": 0,
        "output.energy": "checked", "interface.softening": 0.3,
        "drive.prestress.tau0": 0.03, "drive.prestress.settle": 1.0, "drive.prestress.x": [0.2, 0.8],
        "interface.patch": [{"x": [0.0, 0.2], "delta_b": 1.0}, {"x": [0.8, 1.0], "delta_b": 1.0}]}
NUCLEATED = {**HELD, "interface.nucleation.kind": "forced", "interface.nucleation.x": [0.3, 0.7],
             "interface.nucleation.speed": 0.5, "interface.nucleation.duration": 0.2}


def _held(path) -> tuple[float, float]:
    with h5py.File(path, "r") as f:
        return float(f.attrs["prestress_time"]), float(f.attrs["prestress_tau"])


def test_the_drive_stops_at_the_prestress_and_holds_it(tmp_path):
    """The loader stops at the first reading at or above tau_0 = 0.03 (overshooting it by less than 0.5 %)
    and holds still from there (/interface/loader); the mean shear traction over [0.2, 0.8] rings within
    10 % of it as the lattice settles, and settles within 2 %; no bond breaks."""
    _, out = run_small(tmp_path, "held", **HELD)
    t_hold, tau = _held(out)
    assert 0 < t_hold < 6.0 and 0.03 <= tau < 0.03 * 1.005
    data, _ = datasets(out)
    t, loader, sxy = data["interface/time"], data["interface/loader"], data["interface/sxy"]
    after = t >= t_hold
    assert after.sum() > 50 and np.ptp(loader[after]) == 0 and loader[~after].max() < loader[after][0]
    inside = sxy[:, 5:19].mean(axis=1)                      # sites 5-18: 0.2 <= x < 0.8 on 24 sites
    assert np.all(np.abs(inside[after] - 0.03) < 0.1 * 0.03)
    assert np.all(np.abs(inside[t >= t_hold + 3.0] - 0.03) < 0.02 * 0.03)
    assert not (data["interface/events/kind"] == EVENT_BREAK).any()


def test_the_nucleation_breaks_its_zone_on_its_schedule(tmp_path):
    """Forced from the zone's centre at 0.5 c_r over [0.3, 0.7], each site weakening over 0.2 l/c_r: every site
    of the zone breaks at n_hold + settle + ceil(|x_s - x_c| / (v dt)) + duration, in steps counted from the
    hold (``prestress_time``), exactly."""
    _, out = run_small(tmp_path, "forced", **NUCLEATED)
    st = derive(scene(**{**SMALL, **NUCLEATED}))
    per = st.t_unit / st.dt                                  # steps per l/c_r
    t_hold, _ = _held(out)
    hold = round(t_hold * per)
    ev = datasets(out)[0]
    lo, hi = st.law.nucleation.sites(24)
    assert (lo, hi) == (7, 17)
    centre = 0.5 * 24
    for s in range(lo, hi):
        want = hold + round(1.0 * per) + math.ceil(abs(s + 0.5 - centre) / (0.5 * st.material.c_r * st.dt)) \
            + round(0.2 * per)
        first = ev["interface/events/step"][(ev["interface/events/site"] == s)
                                            & (ev["interface/events/kind"] == EVENT_BREAK)]
        assert len(first) and first[0] == want, (s, first[:1], want)


def _compare(a, b):
    (da, aa), (db, ab) = datasets(a), datasets(b)
    names = [n for n in da if n.startswith(("interface/", "energy/"))]
    assert names and set(names) <= set(db)
    for name in names:
        assert da[name].tobytes() == db[name].tobytes(), name
    assert (aa["prestress_time"], aa["prestress_tau"]) == (ab["prestress_time"], ab["prestress_tau"])


def test_a_held_nucleated_run_is_rank_invariant_and_restarts_on_another_rank_count(tmp_path):
    """The forced nucleation in the held prestress with weakening bonds: 3 ranks write the 1-rank run's bits
    (the hold's step and mean included); so does a run stopped on 2 ranks after the hold, before the
    nucleation, and continued on 3."""
    sc, one = run_small(tmp_path, "n", 1, **NUCLEATED, **{"checkpoint.every": 1.0})
    # A thin halo skin makes the 3 ranks rebuild their halos, which must keep the nucleation the hold set.
    _, three = run_small(tmp_path, "n", 3, **NUCLEATED, **{"checkpoint.every": 1.0, "interface.halo_skin": 0.2})
    _compare(one, three)
    t_hold, _ = _held(one)
    stop = round(t_hold + 0.5, 3)                         # after the hold, before the nucleation (+1 l/c_r)
    out = tmp_path / "restarted.vtkhdf"
    p = run_cli(2, "run", sc, "--out", out, "--no-png", "--quiet", "--set", f"drive.duration={stop}", timeout=200)
    assert p.returncode == 0, p.stderr
    p = run_cli(3, "run", sc, "--out", out, "--no-png", "--quiet", "--restart", str(out) + ".ckpt.h5", timeout=200)
    assert p.returncode == 0, p.stderr
    _compare(one, out)
    assert (datasets(one)[0]["interface/events/kind"] == EVENT_BREAK).sum() >= 9


@pytest.mark.parametrize("setting,message", [
    ("interface.softening=-0.1", "interface.softening = -0.1: out of range (in a); accepted: >= 0"),
    ("interface.patch=[{x=[0.4,0.6], softening=-1.0}]", "interface.patch[0].softening = -1.0: out of range; "
                                                        "accepted: >= 0 (in a)"),
    ("interface.contact_friction=-0.5", "interface.contact_friction = -0.5: out of range"),
    ("interface.contact_friction=0.5", "interface.contact_friction = 0.5: friction needs the contact's normal "
                                       "force"),
    ("drive.prestress.tau0=0.2", "drive.prestress.tau0 = 0.2: at or above the interface's mean peak strength"),
    ("drive.prestress.x=[0.5,0.5]", "drive.prestress.x = [0.5, 0.5]: not a stretch of the contact"),
    ("interface.nucleation.x=[0.8,1.3]", "interface.nucleation.x = [0.8, 1.3]: outside the contact [0, 1]"),
    ("interface.nucleation.x=[0.51,0.52]", "interface.nucleation.x = [0.51, 0.52]: holds no interface site"),
    ("interface.nucleation.kind='slip'", "interface.nucleation.kind = 'slip': out of range; accepted: 'none', "
                                         "'time' or 'forced'"),
])
def test_bad_values_of_the_new_keys_get_one_line_and_exit_2(tmp_path, capsys, setting, message):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**{"drive.prestress.tau0": 0.01, "interface.nucleation.kind": "time",
                                "interface.nucleation.x": [0.4, 0.6]}))
    assert main(["run", str(sc), "--out", str(tmp_path / "o.vtkhdf"), "--set", setting]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err


def test_a_prestress_without_a_drive_is_refused(tmp_path, capsys):
    sc = tmp_path / "s.toml"
    sc.write_text(small_toml(**{"drive.mode": "none", "drive.prestress.tau0": 0.01}))
    assert main(["run", str(sc), "--out", str(tmp_path / "o.vtkhdf")]) == 2
    err = capsys.readouterr().err.strip()
    assert "drive.prestress.tau0 = 0.01: no drive (drive.mode = 'none') can load the interface" in err


def test_info_json_gives_the_law_scales_and_andrews_numbers_of_a_held_prestress(tmp_path, capsys):
    """`parslip info --json` carries S, L_c and Lambda where a prestress is held, as the law's own formulas
    give them from the scene (``analysis.rupture.law_scales``: S = (tau_p - tau_0)/(tau_0 - tau_r),
    L_c = 2 M Gamma/(pi (tau_0 - tau_r)^2), whose units the function keeps), and null S and L_c without one."""
    import json

    from parslip.analysis.rupture import law_scales
    sc = tmp_path / "held.toml"
    sc.write_text(small_toml(**NUCLEATED))
    assert main(["info", str(sc), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    k = law_scales(derive(scene(**{**SMALL, **NUCLEATED})))
    assert got["S"] == pytest.approx((k["tau_p"] - 0.03) / (0.03 - k["tau_r"]), rel=1e-12)
    assert got["L_c"] == k["L_c"] and got["L_c"] > 0
    assert got["Lambda"] == k["Lambda"] and 0 < got["S"] < 1.77
    plain = tmp_path / "plain.toml"
    plain.write_text(small_toml())
    assert main(["info", str(plain), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["S"] is None and got["L_c"] is None and got["Lambda"] > 0
