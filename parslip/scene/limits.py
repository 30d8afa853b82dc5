"""Scenes parslip refuses before a run, and the physical reason for each limit.

A refusal is a ``ConfigError``: one line naming the key, its value and what
is accepted (exit code 2).  ``check_scene`` needs the resolved scene only
(``scene.load._cross_checks`` calls it); ``check_setup`` needs the time step
(``scene.derive.derive`` calls it).  Warnings for scenes that run but may not
mean what the user expects live in ``scene.advice``.

Normal load, F_N < N k_y delta0 (N = top_cols interface sites, m c^2/a):
    at rest the interface springs carry the whole load, sum_i k_y (delta0 -
    gap_i) = F_N, so the mean gap is delta0 - F_N/(N k_y).  At F_N = N k_y
    delta0 it is zero: the block's interface row stands on the substrate's
    and any more load pushes one body into the other, which two bodies in
    adhesive contact cannot mean.  Further on, a bond compressed past gap =
    -delta_b "breaks" by length and no longer holds the block, which then
    falls through the substrate.  Below the limit even a sudden load (no
    ramp, no damping: twice the static compression at its deepest) keeps the
    mean gap above -delta0 > -delta_b, so no bond breaks in compression.

Drive speed, v0 < c of the wave the drive launches (c_l for a push or a pull,
which move a face along its normal; c_s for a shear, which moves the top face
along itself):
    the block answers a face moved at v0 with a wave that carries the strain
    v0/c away from it.  At v0 = c that strain is 1: a push compresses the
    bonds behind the front to zero length, a pull doubles them, a shear tilts
    the rows by 45 degrees and slides the driven row a whole spacing over the
    row below; beyond c no wave can get out of the face's way at all.  The
    linear Born lattice, whose bonds act about their reference directions,
    describes none of that.  Speeds well below the limit are already fast:
    ``scene.advice`` warns above 0.1 c_r.

Driven move per step, v0 dt < RUNAWAY_JUMP:
    the engine takes a node that moves RUNAWAY_JUMP = 0.5 a in one step for
    a blow-up (``engine.simulation``) and stops the run; a driven face that
    moves that far by prescription would be stopped as one.  It matters only
    for fast drives with the long time step of a rigid substrate.

The other refusals of the model (delta_b <= delta0, a Poisson ratio with
k_t < 0, dt above 2/omega_max) sit beside the code they protect
(``scene.load``, ``scene.derive``).
"""
from __future__ import annotations

from ..errors import ConfigError
from ..model.interface import InterfaceLaw
from ..model.physics import cl_over_cs, rayleigh_ratio

# A node moving this far in one step (a) is taken for a blow-up by the engine's health check.
RUNAWAY_JUMP = 0.5


def closing_load(scene: dict) -> float:
    """N k_y delta0 (m c^2/a): the total normal load that closes the interface gap at rest."""
    return InterfaceLaw.from_scene(scene).closing_load(scene["lattice.top_cols"])


def drive_wave(mode: str) -> str:
    """The wave a drive launches: 'c_l' (push, pull: the face moves along its normal) or 'c_s' (shear)."""
    return "c_s" if mode == "shear" else "c_l"


def max_v0(scene: dict) -> tuple[float, str]:
    """(the drive speed limit in c_r, the name of its wave speed) for the scene's drive mode and material."""
    r = cl_over_cs(scene["material.nu"], scene["material.model"])     # c_l/c_s
    cr = rayleigh_ratio(r)                                           # c_r/c_s
    wave = drive_wave(scene["drive.mode"])
    return (r if wave == "c_l" else 1.0) / cr, wave


def check_scene(s: dict) -> None:
    """Refuse a normal load that closes the gap and a drive faster than the wave it launches."""
    if s["lattice.bottom_rows"] > 0:          # a free block carries no interface, and F_N does not act
        lim = closing_load(s)
        fn = s["load.FN"]
        if fn >= lim:
            law = InterfaceLaw.from_scene(s)
            n, ky, d0 = s["lattice.top_cols"], law.ky, law.delta0
            raise ConfigError(
                f"load.FN = {fn!r}: closes the interface gap (mean gap delta0 - F_N/(N k_y) = "
                f"{d0 - fn / (n * ky):.4g} a with N = {n} sites, k_y = {ky:g}, delta0 = {d0:g}); "
                f"accepted: 0 <= load.FN < N k_y delta0 = {lim:.6g} (in m c^2/a)")
    _check_prestress(s)
    if s["drive.mode"] != "none":
        lim, wave = max_v0(s)
        v0 = s["drive.v0"]
        if v0 >= lim:
            raise ConfigError(
                f"drive.v0 = {v0!r}: a {s['drive.mode']} drive cannot outrun the {wave} waves it launches "
                f"(the strain v0/{wave} they carry would be {v0 / lim:.4g}, not below 1); accepted: 0 < drive.v0 < "
                f"{wave} = {lim:.6g} (in c_r)")


def _check_prestress(s: dict) -> None:
    """Refuse a held prestress no drive can load, or read over a stretch that is not part of the contact."""
    from ..model.interface import zone_sites
    tau0, x = s["drive.prestress.tau0"], s["drive.prestress.x"]
    if tau0 == 0:
        return
    if s["drive.mode"] == "none" or s["lattice.bottom_rows"] == 0:
        why = "no drive (drive.mode = 'none')" if s["drive.mode"] == "none" else "no contact (a free block)"
        raise ConfigError(f"drive.prestress.tau0 = {tau0!r}: {why} can load the interface to it; accepted: 0, or "
                          f"tau0 > 0 with a drive and a substrate")
    ok = (isinstance(x, list) and len(x) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                      for v in x) and 0.0 <= x[0] < x[1] <= 1.0)
    if not ok or zone_sites(x, s["lattice.top_cols"])[1] == 0:
        raise ConfigError(f"drive.prestress.x = {x!r}: not a stretch of the contact holding a site; accepted: "
                          f"[from, to] in l with 0 <= from < to <= 1")


def check_prestress_reach(st) -> None:
    """Refuse a prestress at or above the mean peak strength of the stretch it is read over (the bonds' tau_p
    at rest under F_N, ``model.interface.InterfaceLaw.strength``): the bonds would break before the drive
    could hold it."""
    held = st.drive.prestress
    if held is None:
        return
    from ..model.physics import DENSITY
    n = st.lattice.n_top_sites
    lo, hi = held.sites(n)
    unit = DENSITY * st.material.c_r ** 2                   # a traction of 1 rho c_r^2, as a force per a
    strongest = float(st.law.strength(n, st.scene["load.FN"])["tau_p"][lo:hi].mean()) / unit
    if held.tau0 >= strongest:
        raise ConfigError(f"drive.prestress.tau0 = {held.tau0!r}: at or above the interface's mean peak strength "
                          f"{strongest:.6g} rho c_r^2 over drive.prestress.x = {list(held.x)} (k_x sqrt(delta_b^2 - "
                          f"gap^2) at rest under F_N), which no drive holds; accepted: 0 < tau0 < {strongest:.6g}")


# The bond table holds the healing clock in the state's float type: float32 counts steps exactly to 2^24.
FLOAT32_STEPS = 2 ** 24


def check_setup(st) -> None:
    """Refuse a drive that moves its face RUNAWAY_JUMP or more per step, and a healing clock the state's
    float type cannot count (both need dt, so after derive)."""
    n_heal = st.law.heal_steps(st)          # the clock counts to n_heal + 1
    if st.precision == "float32" and n_heal + 1 >= FLOAT32_STEPS:
        hi = (FLOAT32_STEPS - 2) * st.dt / st.t_unit
        raise ConfigError(f"interface.heal_time = {st.law.heal_time!r}: {n_heal:.4g} steps of dt, more than a float32 "
                          f"state counts exactly (2^24); accepted: interface.heal_time <= {hi:.4g} l/c_r, or "
                          f"time.precision = 'float64'")
    check_prestress_reach(st)
    if st.scene["drive.mode"] == "none":
        return
    step = st.v0 * st.dt
    if step >= RUNAWAY_JUMP:
        hi = RUNAWAY_JUMP / st.dt / st.material.c_r
        raise ConfigError(
            f"drive.v0 = {st.scene['drive.v0']!r}: moves the driven face v0 dt = {step:.3g} a per step "
            f"(dt = {st.dt:.4g} a/c), which the engine's health check takes for a blow-up (>= {RUNAWAY_JUMP} a "
            f"per step); accepted: drive.v0 < {hi:.4g} (in c_r) at this dt, or a smaller time.dt or time.safety")
