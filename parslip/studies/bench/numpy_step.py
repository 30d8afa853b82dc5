"""The baseline: a straightforward vectorised NumPy step of the same model.

Whole-array operations over every node at once, the way one would write
the model in NumPy: each node's six neighbours gathered by index, the Born
forces summed with the 2x2 stiffness of each bond direction, the interface
bonds broken, claimed (nearest free substrate site within delta0, the lower
top index winning a contested site) and applied, then damped Verlet.  It
is timed by ``suite`` to show what the compiled loop gains over it.
"""
from __future__ import annotations

import time

import numpy as np

from ...engine.reference_engine import Simulation as Reference
from ...model.lattice import DIRECTIONS, DRIVEN, FIXED


class NumpyStep:
    """One vectorised Verlet step of the whole lattice (one process)."""

    def __init__(self, setup):
        ref = Reference(setup)            # its global arrays: neighbours by index, node kinds, sites
        self.st = setup
        n = ref.n_owned
        self.u = np.zeros((n, 2))
        self.up = np.zeros((n, 2))
        self.mask = ref.nb >= 0
        self.nb = np.where(self.mask, ref.nb, np.arange(n)[:, None])
        kn, kt = ref.kn[ref.block], ref.kt[ref.block]
        d = DIRECTIONS
        # K_k per node and bond: (k_n - k_t) n n^T + k_t I.
        self.kxx = ((kn - kt)[:, None] * d[None, :, 0] ** 2 + kt[:, None]) * self.mask
        self.kxy = ((kn - kt)[:, None] * d[None, :, 0] * d[None, :, 1]) * self.mask
        self.kyy = ((kn - kt)[:, None] * d[None, :, 1] ** 2 + kt[:, None]) * self.mask
        self.free = ref.kind[:n] != FIXED
        self.driven = ref.kind[:n] == DRIVEN
        self.fext = ref.fext[:n, 1].copy()
        self.top, self.bot = ref.top_node, ref.bot_node
        self.dx0 = ref.ref_x[self.top][:, None] - ref.ref_x[self.bot][None, :]
        self.partner = np.arange(len(self.top)) + setup.lattice.top.col0
        self.x0 = np.zeros(len(self.top))
        law = setup.law
        self.d0, self.db, self.kx, self.ky = law.delta0, law.delta_b, law.kx, law.ky
        self.carry, self.cf = setup.damping.carry(setup.dt), setup.damping.force_factor(setup.dt)

    def step(self):
        u = self.u
        dx = u[self.nb, 0] - u[:, None, 0]
        dy = u[self.nb, 1] - u[:, None, 1]
        f = np.stack([(self.kxx * dx + self.kxy * dy).sum(1), (self.kxy * dx + self.kyy * dy).sum(1)], axis=1)
        f[:, 1] += self.fext
        if len(self.top):
            ut, ub = u[self.top], u[self.bot]
            bonded = self.partner >= 0
            q = np.maximum(self.partner, 0)
            gx = self.dx0[np.arange(len(q)), q] + ut[:, 0] - ub[q, 0]
            gy = self.d0 + ut[:, 1] - ub[q, 1]
            broken = bonded & (gx * gx + gy * gy >= self.db ** 2)
            self.partner[broken] = -1
            free = self.partner < 0
            if free.any():
                taken = np.zeros(len(self.bot), bool)
                taken[self.partner[~free]] = True
                s = np.flatnonzero(free)
                qc = np.floor((self.st.lattice.top.col0 + s) + ut[s, 0] + 0.5).astype(int)
                cand = np.clip(qc[:, None] + np.arange(-1, 2)[None, :], 0, len(self.bot) - 1)
                cx = self.dx0[s[:, None], cand] + ut[s, 0][:, None] - ub[cand, 0]
                cy = self.d0 + ut[s, 1][:, None] - ub[cand, 1]
                d2 = np.where(taken[cand], np.inf, cx * cx + cy * cy)
                best = np.argmin(d2, axis=1)
                ok = d2[np.arange(len(s)), best] <= self.d0 ** 2
                claim = cand[np.arange(len(s)), best]
                s, claim = s[ok], claim[ok]
                first = np.unique(claim, return_index=True)[1]          # the lower top index wins
                self.partner[s[first]] = claim[first]
                self.x0[s[first]] = self.dx0[s[first], claim[first]] + ut[s[first], 0] - ub[claim[first], 0]
            bonded = self.partner >= 0
            q = self.partner[bonded]
            t = self.top[bonded]
            gx = self.dx0[np.flatnonzero(bonded), q] + u[t, 0] - u[self.bot[q], 0]
            gy = self.d0 + u[t, 1] - u[self.bot[q], 1]
            fx, fy = -self.kx * (gx - self.x0[bonded]), -self.ky * (gy - self.d0)
            np.add.at(f, (t, 0), fx)
            np.add.at(f, (t, 1), fy)
            np.add.at(f, (self.bot[q], 0), -fx)
            np.add.at(f, (self.bot[q], 1), -fy)
        new = u + (self.carry * (u - self.up) + self.cf * f)
        new[~self.free] = u[~self.free]
        self.up, self.u = u, new


def node_updates_per_s(setup, steps: int) -> float:
    """Nodes x steps / seconds of ``steps`` vectorised steps (after one warm-up step)."""
    s = NumpyStep(setup)
    s.step()
    t = time.perf_counter()
    for _ in range(steps):
        s.step()
    return len(s.u) * steps / (time.perf_counter() - t)
