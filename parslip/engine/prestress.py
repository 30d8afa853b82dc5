"""A held prestress: when the interface's mean shear traction is read, and the step the loader stops.

Responsible for ``drive.prestress`` (``model.drive.Prestress``) on the Python side of a run: the mean
over the sites of the stretch of the shear traction they carry is read between calls of the compiled
loop, at steps every rank computes from what every rank holds, and the first reading at or above
tau_0 stops the loader (``loop.Params.n_hold``) and dates the nucleation (``model.interface.Rules``).

The reading is a collective sum that does not depend on the rank count: each rank rounds each of its
OWNED sites' shear force to a multiple of QUANTUM and sums the integers (``kernels.interface.shear_sum``);
the ranks' integers add exactly.  So every rank reads the same mean, and 1 and 3 ranks stop at the same
step with the same bits.  The readings come every ``Prestress.EVERY`` drive steps, and sooner as the mean
nears tau_0: the next is the step at which the line through the last two readings reaches tau_0 (at least
one step, at most EVERY on).  The loader then overshoots tau_0 by at most what one step of the drive adds
while the load rises steadily.
"""
from __future__ import annotations

import logging
import math

import numpy as np

from ..model.interface import NEVER
from ..model.physics import DENSITY
from ..parallel.layout import PAD
from .kernels import interface as ik

# The rounding of each site's shear force in the sum (m c^2/a): 2^-40, far below any traction a run holds,
# and 2^23 sites of forces up to 2^20 stay within an int64.
QUANTUM = 2.0 ** -40


class Hold:
    """The held prestress of one run on one rank (``setup.drive.prestress``; nothing to do without one)."""

    def __init__(self, setup, comm=None):
        self.setup, self.comm = setup, comm
        self.held = setup.drive.prestress
        self.step = None                # the step from which the loader holds still, once decided
        self.tau = math.nan             # the mean shear traction read then (rho c_r^2)
        self.last = None                # (step, mean) of the previous reading
        self.next = setup.n_drive_start if self.held is not None else None
        n = setup.lattice.n_top_sites
        self.sites = self.held.sites(n) if self.held is not None else (0, 0)

    def pending(self) -> bool:
        """A prestress is asked for and not yet reached."""
        return self.held is not None and self.step is None

    def next_read(self, n: int) -> int | None:
        """The step of the next reading after step n, or None."""
        return self.next if self.pending() and self.next is not None and self.next > n else None

    def mean(self, sim) -> float:
        """The mean over the stretch's sites of the shear traction they carry at u(n), bonds and contact friction
        (rho c_r^2); collective."""
        s, st = sim.state, self.setup
        bx, by, tx, ty = s.level(sim.n)
        bxp, byp, txp, typ = s.level(sim.n - 1)
        br = s.iface.geom.brow
        lo, hi = self.sites
        mine = int(ik.shear_sum(sim.n, tx[PAD], ty[PAD], bx[br], by[br], txp[PAD], typ[PAD], bxp[br], byp[br], s.iface,
                                lo, hi, QUANTUM))
        total = mine if self.comm is None else self.comm.allreduce(mine)
        return total * QUANTUM / (hi - lo) / (DENSITY * st.material.c_r ** 2)

    def read(self, sim) -> bool:
        """At a reading's step: read the mean and decide; True when the loader stops here (collective)."""
        n = sim.n
        if not self.pending() or n != self.next:
            return False
        tau = self.mean(sim)
        if tau >= self.held.tau0:
            self.step, self.tau = n, tau
            self.apply(sim)
            self._announce()
            return True
        every = self.held.EVERY
        ahead = every
        if self.last is not None and tau > self.last[1]:
            rate = (tau - self.last[1]) / (n - self.last[0])
            ahead = max(1, min(every, int(math.floor((self.held.tau0 - tau) / rate))))
        self.last = (n, tau)
        self.next = n + ahead
        return False

    def apply(self, sim) -> None:
        """Give the loop the decided step: the loader holds from it, the nucleation starts after the settling."""
        st = self.setup
        hold = NEVER if self.step is None else self.step
        sim.params = sim.params._replace(n_hold=hold)
        law = st.law
        if law.nucleation is not None and self.held is not None:
            start = NEVER
            if self.step is not None:
                steps = st.t_unit / st.dt
                start = self.step + int(round(self.held.settle * steps)) + int(round(law.nucleation.start * steps))
            s = sim.state
            s.iface = s.iface._replace(rules=s.iface.rules._replace(nuc_start=start))

    def _announce(self) -> None:
        st, law = self.setup, self.setup.law
        steps = st.t_unit / st.dt
        when = (self.step - st.n_drive_start) / steps
        text = (f"prestress held: the mean shear traction over x = {list(self.held.x)} l reached {self.tau:.6g} "
                f"rho c_r^2 (drive.prestress.tau0 = {self.held.tau0:g}) at t = {when:.4g} l/c_r; the loader "
                f"holds from there")
        if law.nucleation is not None:
            text += (f"; the nucleation starts at t = {when + self.held.settle + law.nucleation.start:.4g} l/c_r, "
                     f"after {self.held.settle:g} l/c_r of settling")
        logging.getLogger("parslip").info(text)

    # ------------------------------------------------------------ checkpoint --
    def attrs(self) -> dict:
        """What a checkpoint keeps, so that a continued run reads and stops at the same steps."""
        last = self.last if self.last is not None else (-1, math.nan)
        return {"prestress_step": -1 if self.step is None else self.step, "prestress_tau": self.tau,
                "prestress_next": -1 if self.next is None else self.next,
                "prestress_last": np.array(last, np.float64)}

    def restore(self, sim, attrs: dict) -> None:
        """Continue from a checkpoint's ``attrs`` (one written before prestresses existed holds none)."""
        if self.held is None or "prestress_step" not in attrs:
            return
        step, nxt = int(attrs["prestress_step"]), int(attrs["prestress_next"])
        self.step = None if step < 0 else step
        self.tau = float(attrs["prestress_tau"])
        self.next = None if nxt < 0 else nxt
        last = attrs["prestress_last"]
        self.last = None if last[0] < 0 else (int(last[0]), float(last[1]))
        self.apply(sim)

    def output_attrs(self) -> dict:
        """The run file's record of the hold (root attributes): the drive time it began (l/c_r, NaN: never) and
        the mean shear traction read then (rho c_r^2)."""
        if self.held is None:
            return {}
        st = self.setup
        t = math.nan if self.step is None else st.to_lcr((self.step - st.n_drive_start) * st.dt)
        return {"prestress_time": t, "prestress_tau": self.tau}
