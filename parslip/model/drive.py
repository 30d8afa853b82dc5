"""The drive: how a scene loads the block, built once from the scene; everything else asks it.

The normal load F_N is ramped up linearly over ``ramp``, held while the
lattice settles with damping over ``settle``, then the drive acts for
``duration`` (all in l/c_r).  The drive moves the block's driven face (the
rear face for a push, T-; the front face for a pull, T+; the top row for a
shear, T0; ``mode = "none"``: no drive) at v0 (c_r) along x:

    prescribed (spring = 0)   u_x(driven node, t) = u_x(node, t_0) + v0 (t - t_0)     t_0 the drive's start
    spring (spring = k_s)     f_x = k_s (u_x(node, t_0) + v0 (t - t_0) - u_x(node, t))   (m c^2/a)

``hold = "xy"`` also holds a prescribed node's y where it was at t_0;
``rows`` restricts a push or a pull to the face's rows [first, last] of the
block (``[]``: every row).  The compiled loop reads the drive as one code
(``code``): DRIVE_X or DRIVE_XY, with DRIVE_SPRING or'ed in; 0 is no drive.

A held prestress (``prestress``, ``Prestress``) stops the loader once the
interface's mean shear traction has reached tau_0 and holds it there: the
driven face (or the springs' loader) keeps its x from that step on, and the
lattice settles under the held load.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

# The loop's drive word: the face's x prescribed (DRIVE_X) or x and y (DRIVE_XY); DRIVE_SPRING or'ed in: tied
# to the loader by springs instead.
DRIVE_X, DRIVE_XY = 1, 2
DRIVE_SPRING = 8


@dataclass(frozen=True)
class Prestress:
    """Load the interface to a mean shear traction ``tau0`` (rho c_r^2, the unit of /interface/sxy), then hold:
    the mean over the sites of ``x`` = [from, to) (l) of the shear traction they carry, summed exactly (so the
    same on any rank count), is read every ``EVERY`` drive steps, sooner as it nears tau0 (the step to the
    crossing extrapolated from the last two readings, at least 1); the drive stops at the first reading at
    or above tau0, every rank at the same step, and the lattice then settles for ``settle`` (l/c_r) before a
    nucleation starts."""
    tau0: float
    settle: float
    x: tuple = (0.0, 1.0)

    # Drive steps between readings of the mean while it is far from tau0 (the loop's agreement cadence).
    EVERY = 256

    def sites(self, n_sites: int) -> tuple[int, int]:
        """The global sites [lo, hi) whose mean is read (``model.interface.zone_sites``)."""
        from .interface import zone_sites
        return zone_sites(self.x, n_sites)


@dataclass(frozen=True)
class Drive:
    """The loading of one scene (see the module docstring); times in l/c_r, v0 in c_r, spring in m c^2/a^2."""
    mode: str                    # "push", "pull", "shear" or "none"
    hold: str                    # "x" or "xy"
    v0: float                    # c_r
    duration: float              # l/c_r
    spring: float = 0.0          # m c^2/a^2; 0: prescribed motion
    rows: tuple = ()             # (first, last) rows of a push or pull; (): every row of the face
    ramp: float = 0.0            # l/c_r over which F_N rises linearly
    settle: float = 0.0          # l/c_r of damped settling at full F_N before the drive
    prestress: Prestress | None = None   # stop the drive at a mean interface shear traction and hold it

    @classmethod
    def from_scene(cls, scene: dict) -> "Drive":
        """The drive of a resolved scene (every ``drive.*`` and ``load.ramp``, ``load.settle`` key present)."""
        tau0 = float(scene["drive.prestress.tau0"])
        held = Prestress(tau0=tau0, settle=float(scene["drive.prestress.settle"]),
                         x=tuple(float(v) for v in scene["drive.prestress.x"])) if tau0 > 0 else None
        return cls(mode=scene["drive.mode"], hold=scene["drive.hold"], v0=float(scene["drive.v0"]),
                   duration=float(scene["drive.duration"]), spring=float(scene["drive.spring"]),
                   rows=tuple(int(r) for r in scene["drive.rows"]), ramp=float(scene["load.ramp"]),
                   settle=float(scene["load.settle"]), prestress=held)

    @property
    def on(self) -> bool:
        """A drive acts (``mode`` is not "none")."""
        return self.mode != "none"

    @property
    def code(self) -> int:
        """The loop's drive word: 0 without a drive, else DRIVE_X or DRIVE_XY, with DRIVE_SPRING or'ed in."""
        if not self.on:
            return 0
        return (DRIVE_XY if self.hold == "xy" else DRIVE_X) | (DRIVE_SPRING if self.spring > 0 else 0)

    def steps(self, t_unit: float, dt: float) -> tuple[int, int, int]:
        """(n_ramp, n_settle, n_drive): the steps of each phase at time step dt (a/c), t_unit = l/c_r in a/c;
        the drive takes at least one step."""
        return (int(round(self.ramp * t_unit / dt)), int(round(self.settle * t_unit / dt)),
                max(1, int(math.ceil(self.duration * t_unit / dt))))

    def speed(self, c_r: float) -> float:
        """v0 in internal units (a c/a): v0 c_r."""
        return self.v0 * c_r

    def travel(self, c_r: float, t_unit: float) -> float:
        """How far the loader moves over the drive, v0 c_r duration t_unit (a); 0 without a drive."""
        return self.speed(c_r) * self.duration * t_unit if self.on else 0.0

    def stability_key(self) -> dict:
        """What of the drive enters omega_max (``model.stability.omega_max``): the loader springs, on the
        face ``mode`` and ``rows`` select."""
        return dict(spring=self.spring, mode=self.mode, drive_rows=list(self.rows))

    def unlike_reference(self) -> list[str]:
        """The drive options the reference engine (the paper's prescribed x) does not have, as "key = value"."""
        out = []
        if self.hold != "x":
            out.append(f"drive.hold = {self.hold!r}")
        if self.spring:
            out.append(f"drive.spring = {self.spring!r}")
        if self.rows:
            out.append(f"drive.rows = {list(self.rows)!r}")
        return out
