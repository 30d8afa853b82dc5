"""The damping: what slows the lattice's motion, built once from the scene; everything else asks it.

``form = "absolute"`` (the paper): every node feels -zeta m u', u' its
absolute velocity, with zeta in c/a (c the velocity unit).  The damped
Verlet scheme (m = 1) takes u' at the centred difference (u(t+dt) -
u(t-dt))/(2 dt):

    u(t+dt) (1 + zeta dt/2) = 2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)

which the engine evaluates as an increment, u(t+dt) = u(t) + B (u(t) - u(t-dt)) + C F(t), with

    B = (1 - zeta dt/2) / (1 + zeta dt/2)      (``carry``)
    C = dt^2 / (1 + zeta dt/2)                 (``force_factor``)

A free node moving at v keeps the velocity v B^n after n steps: B^n =
exp(-zeta t) (1 + O(zeta^3 dt^2 t)).  The scheme is stable for omega dt <= 2
whatever zeta is, so the damping does not enter omega_max.
"""
from __future__ import annotations

from dataclasses import dataclass

FORMS = ("absolute",)


@dataclass(frozen=True)
class Damping:
    """The damping of one scene (see the module docstring); zeta in c/a."""
    zeta: float
    form: str = "absolute"

    @classmethod
    def from_scene(cls, scene: dict) -> "Damping":
        """The damping of a resolved scene (``time.zeta``)."""
        return cls(zeta=float(scene["time.zeta"]))

    @property
    def damped(self) -> bool:
        """zeta > 0: the update multiplies by B (with zeta = 0, B = 1 and the loop skips it, same bits)."""
        return self.zeta > 0

    def carry(self, dt: float) -> float:
        """B = (1 - zeta dt/2) / (1 + zeta dt/2): what multiplies u(t) - u(t-dt) in the update."""
        c = 0.5 * self.zeta * dt
        return (1.0 - c) / (1.0 + c)

    def force_factor(self, dt: float) -> float:
        """C = dt^2 / (1 + zeta dt/2), dt in a/c: what multiplies a force in the update (m = 1)."""
        return dt * dt / (1.0 + 0.5 * self.zeta * dt)
