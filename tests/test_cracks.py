"""Fronts as cracks (``analysis.cracks``) on fields and records drawn by hand, where each answer is known.

Route 1 (the energy flux into a lattice contour) is checked on the near-tip field of a mode II crack steady
at speed v laid on a triangular lattice: the flux, a sum over the bonds the contour cuts, must return the G
of the continuum field (Freund's closed form where k_t = 0, the Born continuum's where k_t != 0) at two radii,
and nothing for a contour that holds no tip.  Route 2 recovers K_II from a drawn traction profile; Gamma
comes from a drawn event record and from a drawn frame.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from parslip.analysis import cracks
from parslip.model.physics import DENSITY, ROW_HEIGHT, born_stiffness, born_wave_speeds

CAUCHY = (8.0 / 3.0, 0.0)                                   # k_t = 0: c_s = 1, c_l = sqrt(3), nu = 1/4
BORN = born_stiffness(math.sqrt(8.0 / 3.0), 1.0)           # nu = 0.2 plane strain, c_s = 1: k_t = 1/9


def crack_lattice(half: int = 40):
    """A triangular lattice of 2 half x 2 half nodes, the crack plane y = 0 between two rows, the bonds across
    it cut for x < 0 (the crack), kept ahead (the tip between x = -1/4 and 1/4).  (ref (N, 2), i, j)."""
    ref, index = [], {}
    for r in range(-half, half):
        for c in range(-half, half):
            index[(r, c)] = len(ref)
            ref.append((c + 0.5 * (r % 2) + 0.25, (r + 0.5) * ROW_HEIGHT))
    ref = np.array(ref)
    i, j = [], []
    for (r, c), k in index.items():
        s = r % 2
        for dr, dc in ((0, 1), (1, s), (1, s - 1)):
            m = index.get((r + dr, c + dc))
            if m is None or (r == -1 and dr == 1 and ref[k, 0] + ref[m, 0] < 0):
                continue
            i.append(k)
            j.append(m)
    return ref, np.array(i), np.array(j)


def laid_crack(kn, kt, v, K=0.05, dt=0.1, half=40):
    """The lattice, its bonds and two consecutive states (dt apart) of the steady crack field."""
    ref, i, j = crack_lattice(half)
    d0 = ref[j] - ref[i]
    bonds = {"i": i, "j": j, "K": cracks.bulk_bond_stiffness(d0, np.full(len(i), kn), np.full(len(i), kt)), "d0": d0}
    u, _ = cracks.crack_field(ref[:, 0], ref[:, 1], v, K, kn, kt)
    u_prev, _ = cracks.crack_field(ref[:, 0] + v * dt, ref[:, 1], v, K, kn, kt)
    return ref, bonds, ref + u, ref + u_prev, dt


@pytest.mark.parametrize("v", [0.05, 0.4, 0.8])
def test_born_velocity_function_is_freunds_for_a_cauchy_solid(v):
    kn, kt = CAUCHY
    c_l, c_s = born_wave_speeds(kn, kt)
    assert cracks.mode2_compliance(v, kn, kt) == pytest.approx(
        cracks.freund_mode2(v, c_s, c_l, DENSITY * c_s ** 2), rel=1e-9)


def test_the_laid_field_is_a_mode_2_crack():
    """Traction K_II / sqrt(2 pi x) ahead on the crack plane, none on the upper face (Born stress of the field,
    by finite differences just above the plane)."""
    kn, kt = BORN
    C = cracks.born_moduli(kn, kt)
    h = 1e-6
    for x, want in ((3.0, 0.05 / math.sqrt(2 * math.pi * 3.0)), (-3.0, 0.0)):
        grad = np.zeros((2, 2))
        for l, (dx, dy) in enumerate(((h, 0.0), (0.0, h))):
            up, _ = cracks.crack_field(np.array([x + dx]), np.array([1e-5 + dy]), 0.5, 0.05, kn, kt)
            dn, _ = cracks.crack_field(np.array([x - dx]), np.array([1e-5 - dy]), 0.5, 0.05, kn, kt)
            grad[:, l] = (up[0] - dn[0]) / (2 * h)
        sigma = np.einsum("abkl,kl->ab", C, grad)
        assert sigma[0, 1] == pytest.approx(want, abs=1e-5) and sigma[1, 1] == pytest.approx(0.0, abs=1e-5)


@pytest.mark.parametrize("solid,v", [(CAUCHY, 0.5), (CAUCHY, 0.85), (BORN, 0.3), (BORN, 0.8)])
def test_the_contour_flux_returns_the_g_laid_on_the_lattice(solid, v):
    kn, kt = solid
    ref, bonds, p, p_prev, dt = laid_crack(kn, kt, v)
    want = cracks.field_g(0.05, v, kn, kt)
    if kt == 0:
        c_l, c_s = born_wave_speeds(kn, kt)
        assert want == pytest.approx(0.5 * cracks.freund_mode2(v, c_s, c_l, DENSITY * c_s ** 2) * 0.05 ** 2)
    for r in (12.0, 30.0):
        got = cracks.contour_flux(ref, p, p_prev, dt, bonds, (0.0, 0.0, r), v)
        assert got["G"] == pytest.approx(want, rel=0.01)
        assert got["cut"] > 0 and got["flux"] > 0


def test_a_contour_without_the_tip_takes_nothing_and_damping_is_subtracted():
    kn, kt = BORN
    ref, bonds, p, p_prev, dt = laid_crack(kn, kt, 0.5)
    want = cracks.field_g(0.05, 0.5, kn, kt)
    away = cracks.contour_flux(ref, p, p_prev, dt, bonds, (-20.0, 12.0, 8.0), 0.5)
    assert abs(away["G"]) < 0.01 * want
    damped = cracks.contour_flux(ref, p, p_prev, dt, bonds, (0.0, 0.0, 12.0), 0.5, zeta=0.01)
    vel = (p - p_prev) / dt
    inside = (np.abs(ref[:, 0]) <= 12) & (np.abs(ref[:, 1]) <= 12)
    assert damped["damping"] == pytest.approx(0.01 * np.sum(vel[inside] ** 2))
    assert damped["G"] == pytest.approx(damped["flux"] / 0.5 - damped["dEdt"] / 0.5 - damped["damping"] / 0.5)


def test_the_born_velocity_function_is_not_the_classical_one():
    """k_t != 0: the lattice's own crack needs the Born continuum's H(v); the classical one with mu = rho c_s^2
    is off by about 8 % at rest and diverges at c_R instead of the lattice's surface speed."""
    kn, kt = BORN
    c_l, c_s = born_wave_speeds(kn, kt)
    classical = cracks.freund_mode2(1e-3, c_s, c_l, DENSITY * c_s ** 2)
    assert cracks.mode2_compliance(0.0, kn, kt) / classical == pytest.approx(0.922, abs=0.002)


def test_process_zone_of_a_cauchy_solid():
    """k_t = 0: M = mu / (1 - nu), nu = 1/4, mu = rho c_s^2; Lambda = 9 pi/16 M a / (2 k_x)."""
    kn, kt = CAUCHY
    mu = DENSITY * born_wave_speeds(kn, kt)[1] ** 2
    assert cracks.palmer_rice_length(0.1, kn, kt) == pytest.approx(9 * math.pi / 16 * mu / 0.75 * 5.0, rel=1e-5)


def test_mode2_fit_recovers_a_drawn_profile():
    rng = np.random.default_rng(0)
    xi = np.arange(15.0, 46.0)
    tau = 0.2 + 0.8 / np.sqrt(2 * math.pi * xi) + 1e-4 * rng.standard_normal(len(xi))
    K, tau0 = cracks.mode2_fit(xi, tau)
    assert K == pytest.approx(0.8, rel=0.01) and tau0 == pytest.approx(0.2, rel=0.01)
    assert math.isnan(cracks.mode2_fit(xi[:2], tau[:2])[0])


def drawn_front(n=20, frame_every=3):
    steps = 10 * np.arange(n)
    x = (np.arange(n) + 0.5) / n
    return SimpleNamespace(tip={"x": x, "t": steps * 0.01, "step": steps, "frame": steps // frame_every + 1})


def test_gamma_from_a_drawn_event_record():
    f = drawn_front()
    energy = np.linspace(0.01, 0.02, 20)
    ev = {"site": np.arange(20), "step": f.tip["step"], "kind": np.ones(20, np.uint8), "energy": energy}
    run = SimpleNamespace(events=ev, attrs={"c_r": 1.0}, interface={}, x=f.tip["x"], scene={})
    g = cracks.gamma_run(run, f)
    assert g["source"] == "events" and np.allclose(g["Gamma"], energy[4:16])


def test_gamma_from_a_drawn_frame():
    """A bond with gap y breaks at length delta_b: stored energy 1/2 k_x (delta_b^2 - y^2) + 1/2 k_y (y - delta0)^2,
    read back from the normal traction the frame before shows (c_r = 1.1: units of rho c_r^2)."""
    f = drawn_front()
    kx, ky, d0, db, c_r = 0.1, 0.3, 0.5, 0.7, 1.1
    y = np.linspace(0.45, 0.55, 20)
    syy = np.zeros((int(f.tip["frame"].max()) + 1, 20))
    syy[f.tip["frame"] - 1, np.arange(20)] = ky * (y - d0) / (DENSITY * c_r ** 2)
    iface = {"syy": syy, "kx": np.full(20, kx), "ky": np.full(20, ky), "delta_b": np.full(20, db)}
    run = SimpleNamespace(events=None, attrs={"c_r": c_r}, interface=iface, x=f.tip["x"],
                          scene={"interface.delta0": d0})
    g = cracks.gamma_run(run, f)
    want = (0.5 * kx * (db ** 2 - y ** 2) + 0.5 * ky * (y - d0) ** 2) / c_r ** 2
    assert g["source"] == "frames" and np.allclose(g["Gamma"], want[4:16])


def test_what_the_interface_takes_inside_each_contour():
    """A front one site per 0.002 l/c_r along 500 sites; each site breaks at the tip (0.01 m c_r^2), re-forms 10
    sites behind it (0.004 put back) and breaks again 40 sites behind it (0.005): inside the inner contour
    (1.5 Lambda, about 25 a) the interface takes 0.006 per a of advance, inside the outer (3 Lambda) 0.011."""
    n, dt0 = 500, 0.002
    s = np.arange(n)
    x = (s + 0.5) / n
    f = SimpleNamespace(tip={"x": x, "t": s * dt0, "step": s, "frame": s})
    site = np.concatenate([s, s, s])
    time = np.concatenate([s * dt0, (s + 10) * dt0, (s + 40) * dt0])
    kind = np.concatenate([np.ones(n), 2 * np.ones(n), np.ones(n)]).astype(np.uint8)
    energy = np.concatenate([np.full(n, 0.01), np.full(n, 0.004), np.full(n, 0.005)])
    scene = {"material.nu": 0.2, "material.model": "plane_strain", "material.velocity_unit": "c_r",
             "material.bottom_kn": 10.0, "material.bottom_kt": 0.0}
    run = SimpleNamespace(events={"site": site, "time": time, "kind": kind, "energy": energy},
                          attrs={"l": float(n)}, interface={"kx": np.full(n, 0.1)}, x=x, scene=scene)
    lam = cracks.process_zone(run)
    assert 15 < lam < 18                                       # "about 15 a at k_x = 0.1"
    inner, outer = cracks.interface_take(run, f)
    assert inner == pytest.approx(0.006, rel=0.02) and outer == pytest.approx(0.011, rel=0.02)


def test_field_route_on_a_drawn_run():
    """Frames of a tip running at 0.6 c_r over 400 sites with tau = tau_0 + K_II / sqrt(2 pi xi) ahead of it:
    every frame of the steady stretch returns K_II, tau_0 and G = 1/2 H(v) K_II^2 of the Born continuum."""
    n, v, K, tau0 = 400, 0.6, 0.15, 0.014
    x = (np.arange(n) + 0.5) / n
    t = np.arange(0.0, 0.6, 0.01)
    tip_t = x / v                                     # the tip reaches each site centre at x / v
    f = SimpleNamespace(tip={"x": x, "t": tip_t})
    xi = (x[None, :] - v * t[:, None]) * n
    sxy = np.where(xi > 0, tau0 + K / np.sqrt(2 * math.pi * np.maximum(xi, 1e-9)), 0.0)
    scene = {"material.nu": 0.2, "material.model": "plane_strain", "material.velocity_unit": "c_r",
             "material.bottom_kn": 2.81154, "material.bottom_kt": 0.133883}
    run = SimpleNamespace(attrs={"c_r": 1.0, "l": float(n)}, interface={"kx": np.full(n, 0.1), "sxy": sxy}, x=x,
                          times=t, scene=scene)
    rows = cracks.field_g_run(run, f)
    assert len(rows) >= 20
    m = cracks._material(run)
    want = cracks.field_g(K * DENSITY, v, m.kn_top, m.kt_top)
    for r in rows:
        assert r["K_II"] == pytest.approx(K, rel=1e-6) and r["tau_0"] == pytest.approx(tau0, rel=1e-6)
        assert r["G"] == pytest.approx(want, rel=1e-6)


def test_gamma_falls_back_to_the_frames_when_the_events_predate_their_energies():
    f = drawn_front()
    ev = {"site": np.arange(20), "step": f.tip["step"], "kind": np.ones(20, np.uint8), "energy": np.full(20, np.nan)}
    syy = np.zeros((int(f.tip["frame"].max()) + 1, 20))
    iface = {"syy": syy, "kx": np.full(20, 0.1), "ky": np.full(20, 0.3), "delta_b": np.full(20, 0.7)}
    run = SimpleNamespace(events=ev, attrs={"c_r": 1.0}, interface=iface, x=f.tip["x"], scene={"interface.delta0": 0.5})
    g = cracks.gamma_run(run, f)
    assert g["source"] == "frames" and np.allclose(g["Gamma"], 0.5 * 0.1 * (0.49 - 0.25))


def drawn_crack_run(K=0.02, tau0=0.01, kx=0.5):
    """A crack from site 0 at frame 20, one site a frame (0.33 c_r), with its event record: each break at the
    step before the frame that first shows it, carrying a drawn stored energy; /interface/sxy ahead of the
    tip tau_0 + K_II / sqrt(2 pi xi) (xi in a, l = NS a), nothing behind it.  (run, the drawn energies)."""
    from helpers import DT, NS, blank, draw
    from parslip.analysis.results import Run
    from parslip.io.contract import EVENT_BREAK
    nf = NS + 40
    it = blank(nf)
    arr = draw(it, 20, 0, +1, 1, 1000, 0.001, crack=True)
    energy = np.linspace(0.01, 0.03, NS)
    step = arr - 1
    it["events"] = {"step": step, "time": step * DT, "site": np.arange(NS), "kind": np.full(NS, EVENT_BREAK, np.uint8),
                    "partner": np.arange(NS), "site_column0": 0, "dt": DT, "c_s": math.inf, "c_l": math.inf,
                    "energy": energy}
    it["step"] = np.arange(nf)
    x_tip = (np.arange(nf) + 1 - 20 + 0.5) / NS            # the tip's line through its arrivals, l
    xi = (it["x"][None, :] - x_tip[:, None]) * NS
    it["sxy"] = np.where(xi > 0, tau0 + K / np.sqrt(2 * math.pi * np.maximum(xi, 1e-9)), 0.0)
    it["kx"] = np.full(NS, kx)
    scene = {"material.nu": 0.2, "material.model": "plane_strain", "material.velocity_unit": "c_r",
             "material.bottom_kn": 2.81154, "material.bottom_kt": 0.133883, "interface.kx": kx,
             "lattice.top_rows": 100, "lattice.bottom_rows": 100}
    return Run.from_arrays(it, scene, {"c_r": 1.0, "l": float(NS)}), energy


def test_the_crack_fields_of_a_drawn_front():
    """The registered fields on a drawn crack: Gamma the mean of the drawn break energies over the middle 60 %
    of the path (sites 12-47 of 60), G_field the Born continuum's G of the drawn K_II at 1/3 c_r, route 1 null
    (no snapshots); all in the JSON of the catalogue, defined in analysis.cracks; null on a record without
    the material."""
    from helpers import DT, NS
    from parslip.analysis.fronts import FIELDS
    run, energy = drawn_crack_run()
    (f,) = run.fronts()
    assert f.Gamma == pytest.approx(energy[12:48].mean(), rel=1e-12) and f.Gamma_source == "events"
    m = cracks._material(run)
    assert f.G_field == pytest.approx(cracks.field_g(0.02 * DENSITY, 1 / (NS * DT), m.kn_top, m.kt_top), rel=1e-6)
    assert f.G_contour_inner is None and f.G_contour_outer is None
    d = f.to_dict()
    for name in ("G_contour_inner", "G_contour_outer", "G_field", "Gamma", "Gamma_source"):
        assert FIELDS[name].source == "analysis.cracks" and name in d
    thin = type(run).from_arrays(run.interface, {**run.scene, "lattice.top_rows": 10}, run.attrs)
    assert thin.fronts()[0].G_field is None                     # 10 rows < 3 Lambda: no near-tip field to fit
    assert thin.fronts()[0].Gamma == pytest.approx(f.Gamma, rel=1e-12)
    bare = type(run).from_arrays(run.interface)                 # no material: nothing to measure G with
    assert all(bare.fronts()[0].field(name) is None for name in ("G_field", "Gamma", "G_contour_inner"))


def test_mode2_fit_fits_each_stacked_profile_on_its_own_points():
    xi = np.tile(np.arange(5.0, 25.0), (3, 1))
    tau = np.stack([0.1 + k / np.sqrt(2 * math.pi * xi[0]) for k in (0.2, 0.4, 0.6)])
    xi[1, :10] = np.nan                                          # row 1 fits its last 10 points only
    xi[2, 2:] = np.nan                                           # row 2 has 2 points: no fit
    K, tau0 = cracks.mode2_fit(xi, tau)
    assert K[:2] == pytest.approx([0.2, 0.4], rel=1e-9) and tau0[:2] == pytest.approx([0.1, 0.1], rel=1e-9)
    assert math.isnan(K[2]) and math.isnan(tau0[2])


@pytest.mark.parametrize("k2,xp", [(0.3, 0.02), (-0.05, 0.005), (1.7, 0.11)])
def test_mode2_fit_shifted_recovers_an_exact_square_root_field(k2, xp):
    xi = np.arange(1, 9) / 100.0                        # eight sites ahead, l = 100 a
    sigma = k2 / np.sqrt(2 * np.pi * (xi + xp))
    k_fit, xp_fit = cracks.mode2_fit_shifted(xi, sigma)
    assert k_fit == pytest.approx(k2, rel=1e-9) and xp_fit == pytest.approx(xp, rel=1e-8)


def test_mode2_fit_shifted_refuses_a_rising_profile():
    xi = np.arange(1, 6) / 100.0
    assert all(math.isnan(v) for v in cracks.mode2_fit_shifted(xi, 0.1 + xi))
