"""Warnings for scenes that run but may not mean what the user expects.

``warnings(setup)`` returns one line per concern; `parslip info` prints them
and `parslip run` logs them at start-up (rank 0).  Scenes that cannot run at
all are refused instead (``scene.limits``).

Heavy damping, r > c_s/H (H = (top_rows - 1) sqrt(3)/2 a, the block's height; r = zeta for the body drag):
    the damping term -zeta du/dt is a drag against the laboratory frame; a
    wave's amplitude decays as exp(-zeta t/2).  Every load reaches the
    interface through the block's height (the normal load; the shear of a T0
    drive, carried by the slowest bulk wave, c_s; the tractions the interface
    sends back), so when the damping time 1/zeta is shorter than the time a
    shear wave needs to cross the height, stress no longer travels as waves
    but diffuses (diffusivity c_s^2/zeta: across H in about zeta H^2/c_s^2)
    and the block is frozen into quasi-static creep.  The paper's zeta = 0.1
    on its 10-row block (H = 7.8 a) gives zeta H/c_s = 0.78: waves cross the
    height before they decay, and the damping only removes ringing.  The
    contact length is the wrong yardstick: l/c_s = 100 a/c would flag the
    paper's own setting, and a rupture front is fed by the strain energy next
    to its tip, not by waves that crossed the whole contact.
    With time.damping = "bonds" the dashpots damp a mode of frequency omega at
    r = beta omega^2 (``model.damping``), so the test is on the slowest wave
    that crosses the height, omega = pi c_s/H: r = beta pi^2 c_s^2/H^2 > c_s/H,
    i.e. H < pi^2 beta c_s.  A tall block is freer, not more frozen: at zeta =
    0.1 (beta = 0.036 a/c) only blocks below 0.4 a are, so the warning is for
    extreme zeta only.

Fast drive, v0 > 0.1 c_r:
    a face moved at v0 sends out a wave carrying the strain v0/c (c = c_l
    for a push or pull, c_s for a shear): at 0.1 c_r that is a 5.6 % (push)
    or 9.1 % (shear) strain arriving as a front, so the interface is loaded
    by inertia, not quasi-statically as in the paper's v0 <= 1e-2 c_r.  The
    limit of what can be served at all (v0 < c) is in ``scene.limits``.

Heavy normal load, F_N > 1/2 N k_y delta0:
    the limit ``scene.limits`` sets is on the mean gap at rest, delta0 -
    F_N/(N k_y).  Single gaps spread about it: with an even number of rows
    the block's loaded top row sits half a spacing ahead of its interface
    row (alternating row offsets), so the load tilts it and its front sinks
    most (24 sites, 4 rows: at 0.99 of the limit the front gap is -0.09 a
    while the mean is +0.005 a).  Above half the limit parts of the
    interface may close before the mean does.

Short drive, v0 T < sqrt(delta_b^2 - delta0^2):
    the driven face moves v0 T over the drive time T; an interface bond at
    rest (gap delta0, less under load) breaks only once its top node has
    slid sqrt(delta_b^2 - gap^2) >= sqrt(delta_b^2 - delta0^2) over its
    partner, so a drive that moves its face less than that is unlikely to
    break any bond.
"""
from __future__ import annotations

import math

from ..model.physics import ROW_HEIGHT
from .limits import closing_load, drive_wave

# v0 in c_r above which the drive counts as fast: ten times the paper's fastest drive (1e-2 c_r).
FAST_DRIVE = 0.1
# Share of the closing load N k_y delta0 above which single interface gaps may close.
HEAVY_LOAD = 0.5


def block_height(setup) -> float:
    """H = (top_rows - 1) sqrt(3)/2, the height of the top block (a)."""
    return (setup.lattice.top.rows - 1) * ROW_HEIGHT


def _frozen(st) -> list[str]:
    """The heavy-damping warning (module docstring): the block's slowest wave across its height, omega =
    pi c_s/H, damped at r (``Damping.mode_rate``) faster than it crosses, r > c_s/H."""
    zeta, mat, damping = st.scene["time.zeta"], st.material, st.damping
    h = block_height(st)
    if zeta <= 0 or h <= 0:
        return []
    cross = mat.c_s / h
    rate = damping.mode_rate(math.pi * cross, mat.kn_top)
    if rate <= cross:
        return []
    if damping.rated:
        return [f"time.zeta = {zeta:g} with time.damping = 'bonds': the dashpots damp the slowest wave across the "
                f"block's height (omega = pi c_s/H, H = {h:.3g} a) at beta omega^2 = {rate:.3g} c/a, faster than "
                f"it crosses (c_s/H = {cross:.3g} c/a): the block is frozen; for a dynamic block use "
                f"time.zeta < k_n H/(pi^2 c_s) = {mat.kn_top * h / (math.pi ** 2 * mat.c_s):.3g}"]
    return [f"time.zeta = {zeta:g}: the damping time 1/zeta = {1 / zeta:.3g} a/c is shorter than the "
            f"{h / mat.c_s:.3g} a/c a shear wave needs to cross the block's height (H/c_s, H = {h:.3g} a): waves "
            f"die before they reach the interface, stress diffuses across H in about zeta H^2/c_s^2 = "
            f"{zeta * h * h / mat.c_s ** 2:.3g} a/c and the block is frozen; for a dynamic block use "
            f"time.zeta < c_s/H = {mat.c_s / h:.3g}"]


def warnings(setup) -> list[str]:
    """One line per concern about the scene of ``setup`` (empty when there is none)."""
    st, s, mat = setup, setup.scene, setup.material
    out = []
    out += _frozen(st)
    if st.lattice.has_interface and s["load.FN"] > HEAVY_LOAD * closing_load(s):
        close = closing_load(s)
        gap = st.law.delta0 * (1 - s["load.FN"] / close)
        out.append(
            f"load.FN = {s['load.FN']:g}: {s['load.FN'] / close:.0%} of the load that closes the mean gap "
            f"(N k_y delta0 = {close:.4g}); the mean gap at rest is {gap:.3g} a but single gaps spread about "
            f"it (the block tilts under its alternating row offsets), so parts of the interface may close")
    if st.lattice.has_interface and st.law.heal and st.law.contact == 0:
        out.append(
            "interface.contact = 0 with healing on (interface.heal_speed or heal_time): a site whose bond does "
            "not re-form at once feels no force from the substrate, so under load.FN unbonded sites can sink "
            "through the substrate; set interface.contact > 0 (e.g. the bonds' ky) to keep them above it")
    mode = s["drive.mode"]
    if mode != "none":
        v0 = s["drive.v0"]
        wave = drive_wave(mode)
        c = mat.c_l if wave == "c_l" else mat.c_s
        if v0 > FAST_DRIVE:
            out.append(
                f"drive.v0 = {v0:g} c_r: fast compared with the block's waves (above {FAST_DRIVE:g} c_r): the "
                f"driven face sends out a wave of strain v0/{wave} = {st.v0 / c:.3g}, so inertia dominates and "
                f"the interface is loaded by that wave, not quasi-statically (the paper drives at 1e-4 to "
                f"1e-2 c_r)")
        if st.lattice.has_interface:
            d0, db = st.law.delta0, st.law.delta_b
            need = math.sqrt(db * db - d0 * d0)
            moved = st.v0 * st.n_drive * st.dt
            if moved < need:
                out.append(
                    f"drive.duration = {s['drive.duration']:g} l/c_r: the driven face moves v0 T = {moved:.3g} a "
                    f"in all, less than the slip sqrt(delta_b^2 - delta0^2) = {need:.3g} a at which an interface "
                    f"bond at rest breaks: expect no rupture; accepted for one: drive.duration >= "
                    f"{need / st.v0 / st.t_unit:.3g} l/c_r at this v0")
    return out
