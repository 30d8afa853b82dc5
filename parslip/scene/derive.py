"""From a resolved scene to the numbers every rank shares (``Setup``).

Responsible for the derived quantities of a scene: material constants, the
lattice, omega_max and the time step, the step counts of the load phases
(ramp F_N, settle, drive), the output cadence and the interface slip reach.
Time is internal (a/c_ref) inside; every time the user sees is in l/c_r.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ConfigError
from ..model.damping import Damping
from ..model.drive import Drive
from ..model.interface import InterfaceLaw
from ..model.lattice import Lattice
from ..model.physics import Material
from ..model.stability import omega_max as _omega_max
from ..parallel.layout import Reach, drift_reach, interface_reach, link_of, max_ranks, start_box
from . import limits


@dataclass
class Setup:
    """Everything a scene implies, before any rank builds arrays."""
    scene: dict
    material: Material
    lattice: Lattice
    l: float                 # contact length, a
    t_unit: float            # l/c_r in internal time
    omega_max: float
    omega_method: str        # "lanczos" (exact) or "bound" (rigorous upper bound)
    dt_limit: float          # the largest stable dt: 2/omega_max, less with the bonds' damping (``model.damping``)
    dt_paper: float          # a/c_l of the top block (the paper's criterion)
    dt: float
    n_ramp: int
    n_settle: int
    n_drive: int
    frame_every: int
    snapshot_steps: tuple     # drive steps of the snapshots, first at 0, last at n_drive
    v0: float                # internal units
    slip_reach: float        # a: the explicit slip reach (interface.slip_reach), 0 when the halos follow the slip
    reach: Reach             # halo widths that serve the slip reach, or the first drift box (``parallel.layout``)
    skin: tuple              # (behind, ahead) a: how far a drift box reaches beyond the slip reached
    precision: str           # "float64" or "float32"
    law: InterfaceLaw        # the interface bonds: parameters and rules (``model.interface``)
    drive: Drive             # the loading: mode, speed, phases (``model.drive``)
    damping: Damping         # zeta and its form (``model.damping``)

    @property
    def overlap(self) -> bool:
        """Whether several ranks overlap the halo exchange with the interior update (``run.overlap``)."""
        return bool(self.scene.get("run.overlap", False))

    @property
    def shared_memory(self) -> bool:
        """Whether ranks on one node exchange halos through shared windows (``run.exchange``)."""
        return self.scene.get("run.exchange", "auto") == "auto"

    @property
    def n_steps(self) -> int:
        return self.n_ramp + self.n_settle + self.n_drive

    @property
    def n_drive_start(self) -> int:
        return self.n_ramp + self.n_settle

    @property
    def n_frames(self) -> int:
        return self.n_drive // self.frame_every + 1

    @property
    def n_snapshots(self) -> int:
        return len(self.snapshot_steps)

    @property
    def dtype(self):
        import numpy as np
        return np.float32 if self.precision == "float32" else np.float64

    def max_ranks(self) -> int:
        return max_ranks(self.lattice)

    def to_lcr(self, t_internal: float) -> float:
        return t_internal / self.t_unit


# omega_max values this process read from the disk cache (a runaway's message then names the cache).
CACHE_HITS: set = set()


def omega_max_cached(lat: Lattice, kn, kt, kx: float, ky: float, spring: float = 0.0, mode: str = "none",
                     drive_rows=None) -> tuple[float, str]:
    """``model.stability.omega_max``, kept on disk between runs (``io.cache``)."""
    from ..io import cache
    b, t = lat.blocks
    extra = dict(spring=float(spring), mode=mode, drive_rows=list(drive_rows or [])) if spring > 0 else {}
    k = cache.key(top=[t.rows, t.cols], bottom=[b.rows, b.cols], substrate=lat.substrate,
                  kn=[float(v) for v in kn], kt=[float(v) for v in kt], kx=float(kx), ky=float(ky), **extra)
    hit = cache.lookup(k)
    if hit is not None:
        CACHE_HITS.add(hit)
        return hit
    value = _omega_max(lat, kn, kt, kx, ky, spring, mode, drive_rows)
    cache.store(k, value)
    return value


def halo_skin(skin: float, link: int, driven: bool) -> tuple[float, float]:
    """(behind, ahead) skin of the drift box (a): ``interface.halo_skin`` ahead (0: 4 links), and behind a quarter
    of it but at least one link when a drive fixes the direction of slip (every drive slides the block towards
    +x), the same both ways without one."""
    ahead = float(skin) if skin > 0 else 4.0 * link
    return (max(ahead / 4.0, float(link)) if driven else ahead), ahead


def derive(scene: dict, omega: tuple[float, str] | None = None) -> Setup:
    """Derived quantities of a resolved scene.  Raises ConfigError on an unstable dt or a drive the
    engine would take for a blow-up (``limits.check_setup``)."""
    mat = Material.from_scene(scene["material.nu"], scene["material.model"], scene["material.velocity_unit"],
                              scene["material.bottom_kn"], scene["material.bottom_kt"],
                              scene["material.kn_spring"])
    lat = Lattice(scene["lattice.top_rows"], scene["lattice.top_cols"], scene["lattice.bottom_rows"],
                  scene["lattice.bottom_cols"], scene["interface.delta0"], scene["lattice.substrate"])
    law = InterfaceLaw.from_scene(scene)
    drive = Drive.from_scene(scene)
    n_sites = lat.n_top_sites if lat.has_interface else 0
    big = law.largest(n_sites)
    if omega is None:
        omega, method = omega_max_cached(lat, [mat.kn_bottom, mat.kn_top], [mat.kt_bottom, mat.kt_top],
                                         law.shear_stiffness(big["kx"]), law.normal_stiffness(big["ky"]),
                                         **drive.stability_key())
    else:
        omega, method = omega
    damping = Damping.from_scene(scene)
    limit = damping.dt_limit(omega, [mat.kn_bottom, mat.kn_top])
    dt = scene["time.dt"] if scene["time.dt"] > 0 else scene["time.safety"] * limit
    if dt >= limit:
        what = "sqrt(beta^2 + (2/omega_max)^2) - beta (time.damping = 'bonds')" if damping.rated else "2/omega_max"
        raise ConfigError(f"time.dt = {scene['time.dt']!r}: above the stability limit {what} = {limit:.6g} a/c "
                          f"(omega_max = {omega:.6g}); accepted: 0 (auto) or 0 < dt < {limit:.6g}")
    l = lat.contact_length
    t_unit = l / mat.c_r
    n_ramp, n_settle, n_drive = drive.steps(t_unit, dt)
    frame_dt = scene["output.interface_dt"] * t_unit if scene["output.interface_dt"] > 0 else 1.0 / mat.c_r
    frame_every = max(1, int(math.floor(frame_dt / dt + 1e-9)))
    nsnap = scene["output.snapshots"] if scene["output.fields"] == "all" else 0
    snaps = () if nsnap == 0 else tuple(sorted({int(round(j * n_drive / nsnap)) for j in range(nsnap + 1)}))
    slip = scene["interface.slip_reach"]
    longest = law.longest_bond(n_sites)             # a weakening bond breaks at delta_b + D_c at the latest
    link = link_of(law.rebond_length, longest)
    skin = halo_skin(scene["interface.halo_skin"], link, drive.on)
    reach = (interface_reach(law.rebond_length, longest, slip) if slip > 0 else
             drift_reach(link, start_box(skin)))
    st = Setup(scene=scene, material=mat, lattice=lat, l=l, t_unit=t_unit, omega_max=omega, omega_method=method,
               dt_limit=limit, dt_paper=1.0 / mat.c_l, dt=dt, n_ramp=n_ramp, n_settle=n_settle,
               n_drive=n_drive, frame_every=frame_every, snapshot_steps=snaps, v0=drive.speed(mat.c_r),
               slip_reach=slip, reach=reach, skin=skin,
               precision=scene["time.precision"], law=law, drive=drive, damping=damping)
    limits.check_setup(st)
    return st
