"""The interface law: what an adhesive bond is, built once from the scene; everything else asks it.

A bond joins a top interface site (the block's bottom row) to a bottom site
(the substrate's top row).  With x_ij, y_ij the bond's components (top minus
bottom, in a) and x0 its rest offset:

    force on the top node:  f_x = -k_x (x_ij - x0),   f_y = -k_y (y_ij - delta0)      (m c^2/a)
    breaks when             sqrt(x_ij^2 + y_ij^2) >= delta_b                          (a)
    a free site re-bonds    to a free bottom site within ``rebond_length`` (a)

The rules a scene can choose are codes, each written once as an inlined
function in ``engine.kernels.interface``:

    reform   REFORM_ZERO: a re-formed bond starts with x0 = 0 (as the initial bonds);
             REFORM_CURRENT: with x0 = x_ij (unstressed in x)
    rebond   REBOND_NEAREST: the nearest free bottom site within reach; REBOND_FACING: only the one
             facing the site (its nearest column)
    heal     bits: HEAL_SPEED, a free site takes its claim only while its x-velocity relative to the
             claimed bottom site, (u(n) - u(n-1))/dt of each, is below heal_speed (Baumberger, Caroli
             & Ronsin 2002: pulses re-stick below a slip velocity V_c); HEAL_TIME, only once the same
             bottom site has been its claim (nearest free site within reach) for heal_time: the clock
             restarts from zero whenever the claim changes or lapses (the site leaves reach, or another
             site takes the bottom site first).  0: at once (the paper)

The per-site bond state is one table of named rows (``BOND_ROWS``) that the
loop, the halo exchange and the checkpoint share: the exchange sends the
first ``N_TRAVEL`` rows of every HALO site each step, and a checkpoint
writes every row by name.  A new field of state is one more row.

Units: lengths in a, stiffnesses in m c^2/a^2.
"""
from __future__ import annotations

from collections import namedtuple
from dataclasses import dataclass

import numpy as np

REFORM_ZERO, REFORM_CURRENT = 0, 1
REBOND_NEAREST, REBOND_FACING = 0, 1
REFORM_CODES = {"zero": REFORM_ZERO, "current": REFORM_CURRENT}
REBOND_CODES = {"nearest": REBOND_NEAREST, "facing": REBOND_FACING}
HEAL_SPEED, HEAL_TIME = 1, 2

# The per-site bond state, one row each, in the state's float type (integers are exact below 2^24 even in
# float32).  Rows [0, N_TRAVEL) change as the run goes and travel with the halo exchange:
#   partner  the substrate column bonded to (-1 broken)
#   x0       the bond's rest offset (a)
#   cand     HEAL_TIME: the bottom site the free site has claimed (substrate column), while clock > 0
#   clock    HEAL_TIME: consecutive steps it has claimed ``cand`` (0: none; at most n_heal + 1)
# The others are the site's own constants (``site_values``), which every rank computes for the sites it
# stores from their global index, so they need not travel:
#   kx, ky   the bond's stiffnesses (m c^2/a^2);  delta_b  its breaking length (a)
BOND_ROWS = ("partner", "x0", "cand", "clock", "kx", "ky", "delta_b")
PARTNER, X0, CAND, CLOCK, KX, KY, DELTA_B = range(7)
N_TRAVEL = 4
SITE_CONSTANTS = ("kx", "ky", "delta_b")
# How a checkpoint stores each row: partner as int64, the others in the state's float type (None).
ROW_DTYPES = {"partner": "int64", "x0": None, "cand": "int64", "clock": "int64", "kx": None, "ky": None,
              "delta_b": None}

# What the compiled update reads of the law besides the per-site rows, lengths in the state's float type:
#   delta0 (a), rebond_length (a), reform, rebond and heal: the rules' codes; heal_du = heal_speed dt (a):
#   the largest relative x-displacement per step at which a site re-bonds; n_heal = ceil(heal_time/dt).
Rules = namedtuple("Rules", "delta0 rebond_length reform rebond heal heal_du n_heal")


@dataclass(frozen=True)
class InterfaceLaw:
    """The adhesive bonds of one scene (see the module docstring); lengths in a, stiffnesses in m c^2/a^2."""
    delta0: float                # unloaded gap; the rest length of y_ij
    delta_b: float               # breaking length
    kx: float                    # shear stiffness
    ky: float                    # normal stiffness
    reform: int                  # REFORM_* code
    rebond: int                  # REBOND_* code
    rebond_length: float         # largest length at which a free site re-bonds (delta0 unless set)
    heal_speed: float = 0.0      # c_r: re-bond only below this relative slip velocity (0: no condition)
    heal_time: float = 0.0       # l/c_r: re-bond only after claiming the same site this long (0: at once)

    @classmethod
    def from_scene(cls, scene: dict) -> "InterfaceLaw":
        """The law of a resolved scene (every ``interface.*`` key present)."""
        within = scene["interface.rebond_within"]
        return cls(delta0=float(scene["interface.delta0"]), delta_b=float(scene["interface.delta_b"]),
                   kx=float(scene["interface.kx"]), ky=float(scene["interface.ky"]),
                   reform=REFORM_CODES[scene["interface.reform_x0"]], rebond=REBOND_CODES[scene["interface.rebond"]],
                   rebond_length=float(within if within > 0 else scene["interface.delta0"]),
                   heal_speed=float(scene["interface.heal_speed"]), heal_time=float(scene["interface.heal_time"]))

    @property
    def heal(self) -> int:
        """The healing rule's bits (HEAL_SPEED, HEAL_TIME); 0 re-bonds at once."""
        return (HEAL_SPEED if self.heal_speed > 0 else 0) | (HEAL_TIME if self.heal_time > 0 else 0)

    def rules(self, dtype, setup) -> Rules:
        """The scalars the compiled update reads, lengths in the float type ``dtype``; ``setup`` gives the
        time step (a/c), the velocity unit c_r and the time unit l/c_r (``scene.derive.Setup``)."""
        import math
        f = np.dtype(dtype).type
        return Rules(delta0=f(self.delta0), rebond_length=f(self.rebond_length), reform=self.reform,
                     rebond=self.rebond, heal=self.heal, heal_du=f(self.heal_speed * setup.material.c_r * setup.dt),
                     n_heal=int(math.ceil(self.heal_time * setup.t_unit / setup.dt - 1e-9)))

    def site_values(self, n_sites: int) -> dict:
        """Each site's own constants {"kx", "ky", "delta_b"}: arrays over the global sites 0..n_sites-1 (the
        same on every rank)."""
        return {"kx": np.full(n_sites, self.kx), "ky": np.full(n_sites, self.ky),
                "delta_b": np.full(n_sites, self.delta_b)}

    @property
    def max_delta_b(self) -> float:
        """The longest a bond gets before it breaks (a): what the halo's reach must cover."""
        return self.delta_b

    @property
    def stiffness(self) -> tuple[float, float]:
        """(k_x, k_y) that enter omega_max: the stiffest bond's."""
        return self.kx, self.ky

    def closing_load(self, sites: int) -> float:
        """N k_y delta0 (m c^2/a): the total normal load that closes the mean gap of ``sites`` bonds at rest."""
        return sites * self.ky * self.delta0

    def unlike_reference(self) -> list[str]:
        """The rules of this law that the reference implementation (``engine.reference``) does not have, as
        "key = value" text; empty when it can run the law."""
        out = []
        if self.rebond != REBOND_NEAREST:
            out.append("interface.rebond = 'facing'")
        if self.rebond_length != self.delta0:
            out.append(f"interface.rebond_within = {self.rebond_length!r}")
        if self.heal:
            out.append("interface.heal_speed or interface.heal_time")
        return out
