"""The damping: what slows the lattice's motion, built once from the scene; everything else asks it.

Two forms (``time.damping``), both with zeta in c/a (c the velocity unit, m = 1):

``"absolute"`` (the paper): every node feels -zeta u', u' its absolute
velocity, a body drag: it brakes a block translating as a whole and takes
1/e of a wave's amplitude in 2/zeta, whatever its wavelength.  The damped
Verlet scheme takes u' at the centred difference (u(t+dt) - u(t-dt))/(2 dt):

    u(t+dt) (1 + zeta dt/2) = 2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)

which the engine evaluates as an increment, u(t+dt) = u(t) + B (u(t) - u(t-dt)) + C F(t), with

    B = (1 - zeta dt/2) / (1 + zeta dt/2)      (``carry``)
    C = dt^2 / (1 + zeta dt/2)                 (``force_factor``)

A free node moving at v keeps the velocity v B^n after n steps: B^n =
exp(-zeta t) (1 + O(zeta^3 dt^2 t)).  This scheme is stable for
omega dt <= 2 whatever zeta is (``dt_limit``).

``"bonds"``: a dashpot on every bulk bond (not on the interface bonds), on the
bond's rate of deformation weighted as the bond's own stiffness: with K_j the
bond's 2x2 stiffness (``engine.kernels.stencil``) and k_n its block's normal
stiffness, the force on node i is

    F_i = sum_j K_j [(u_j - u_i) + beta (u'_j - u'_i)],   beta = zeta / k_n   (per block; a/c)

so a bond's stretch rate is damped by zeta (1 - k_t/k_n) and its transverse rate by zeta k_t/k_n (0.048
in the block at nu = 0.2; 0 in the default substrate, k_t = 0).  A rigid translation is not braked at
all; a rigid rotation only through k_t, the term by which the Born lattice itself resists rotation
elastically.  This is stiffness-proportional (Rayleigh) damping: a mode of frequency omega decays at
the rate beta omega^2 / 2 instead of zeta / 2, so long waves keep their amplitude and the highest ones
are damped most.  The scheme stays explicit: u' is the backward difference (u(t) - u(t-dt))/dt, the
velocity at the half step, and the update is Verlet without a body drag (B = 1, C = dt^2) with the bond
forces taken on the field z = u(t) + (beta/dt) (u(t) - u(t-dt)) (``rate_gain``).  For one mode,
lambda^2 + (a + a b - 2) lambda + 1 - a b = 0 with a = omega^2 dt^2, b = beta/dt: stable while
omega^2 (dt^2 + 2 beta dt) < 4, so

    dt_limit = sqrt(beta^2 + (2/omega_max)^2) - beta

with beta the largest of the blocks' (exact for one block; with two, the softer block's beta applied to
the whole lattice's omega_max, an upper bound on the damping, so a safe limit).  At the paper's zeta =
0.1 and k_n = 2.81 of the block, beta = 0.036 a/c cuts the limit of the paper's scene from 0.0818 to
0.0536 a/c (omega_max = 24.46): 1.53 times the steps.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .stability import dt_max

FORMS = ("absolute", "bonds")


@dataclass(frozen=True)
class Damping:
    """The damping of one scene (see the module docstring); zeta in c/a."""
    zeta: float
    form: str = "absolute"

    @classmethod
    def from_scene(cls, scene: dict) -> "Damping":
        """The damping of a resolved scene (``time.zeta``, ``time.damping``)."""
        return cls(zeta=float(scene["time.zeta"]), form=scene["time.damping"])

    @property
    def damped(self) -> bool:
        """The body drag acts (form "absolute", zeta > 0): the update multiplies by B (with B = 1 the loop
        skips it, same bits)."""
        return self.form == "absolute" and self.zeta > 0

    @property
    def rated(self) -> bool:
        """The bonds' dashpots act (form "bonds", zeta > 0)."""
        return self.form == "bonds" and self.zeta > 0

    @property
    def drag(self) -> float:
        """The body drag's zeta (c/a): zeta in the "absolute" form, 0 in the "bonds" form."""
        return self.zeta if self.form == "absolute" else 0.0

    def carry(self, dt: float) -> float:
        """B = (1 - zeta dt/2) / (1 + zeta dt/2): what multiplies u(t) - u(t-dt) in the update."""
        c = 0.5 * self.drag * dt
        return (1.0 - c) / (1.0 + c)

    def force_factor(self, dt: float) -> float:
        """C = dt^2 / (1 + zeta dt/2), dt in a/c: what multiplies a force in the update (m = 1)."""
        return dt * dt / (1.0 + 0.5 * self.drag * dt)

    def beta(self, kn: float) -> float:
        """The bonds' dashpot time beta = zeta / k_n (a/c) of a block of normal stiffness k_n; 0 without."""
        return self.zeta / kn if self.rated else 0.0

    def rate_gain(self, kn: float, dt: float) -> float:
        """g = beta/dt: the bond forces are taken on z = u(t) + g (u(t) - u(t-dt)); 0 without the bonds' form."""
        return self.beta(kn) / dt

    def dt_limit(self, omega_max: float, kns) -> float:
        """The largest stable dt (a/c) with the lattice's highest frequency omega_max and its blocks' k_n."""
        if not self.rated:
            return dt_max(omega_max)
        b = max(self.beta(k) for k in kns)
        d = dt_max(omega_max)
        return math.sqrt(b * b + d * d) - b

    def mode_rate(self, omega: float, kn: float) -> float:
        """Twice the rate (c/a) at which a mode of frequency omega (c/a) loses amplitude in a block of normal
        stiffness k_n: zeta for the body drag, whatever omega; beta omega^2 for the bonds' dashpots (so
        long waves are hardly damped); 0 without damping."""
        if self.rated:
            return self.beta(kn) * omega * omega
        return self.drag

    def unlike_reference(self) -> list[str]:
        """The damping options the reference engine (the paper's body drag) does not have, as "key = value"."""
        return [f"time.damping = {self.form!r}"] if self.form != "absolute" else []
