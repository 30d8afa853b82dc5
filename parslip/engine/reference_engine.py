"""The reference implementation: the first engine's plain, serial time step.

Responsible for nothing on the run path.  It holds the whole lattice as one
array of nodes in global id order, gathers each node's neighbours by index
and sums each bond's force on its own (``kernels.per_bond``), then calls
Python per step: slow, and easy to read.  The tests compare the compiled
loop with it step by step, by global id, and use its energy and force
kernels as an independent computation.
"""
from __future__ import annotations

import numpy as np

from .kernels import per_bond as kernels
from .kernels.scheme import ramp_share
from ..errors import NonFiniteError
from ..model.interface import REFORM_ZERO
from ..model.lattice import DIRECTIONS, TOP
from ..model.physics import DENSITY
from ..scene.derive import Setup


class _SerialLayout:
    """The whole lattice on one rank: nodes in global id order and the interface sites."""

    def __init__(self, lat):
        self.rank, self.size = 0, 1
        self.nodes = nodes = lat.nodes_in_columns(0, lat.ncols)
        self.n_owned = len(nodes["gid"])
        top = np.flatnonzero(lat.is_top_site(nodes))
        self.top_node = top[np.argsort(nodes["gid"][top], kind="stable")].astype(np.int64)
        self.top_gsite = lat.top_site_of_col(nodes["col"][self.top_node]).astype(np.int64)
        self.top_owned = np.ones(len(self.top_node), bool)
        bot = np.flatnonzero(lat.is_bottom_site(nodes))
        self.bot_node = bot[np.argsort(nodes["col"][bot], kind="stable")].astype(np.int64)
        self.bot_gsite0 = 0




class Simulation:
    """The whole lattice and a plain time step (one rank only)."""

    def __init__(self, setup: Setup):
        self.setup = setup
        s, lat, mat = setup.scene, setup.lattice, setup.material
        if lat.rigid:
            raise NotImplementedError("the reference implementation has no rigid substrate")
        unlike = setup.drive.unlike_reference() + setup.damping.unlike_reference() + setup.law.unlike_reference()
        if unlike:
            raise NotImplementedError(f"the reference implementation has not {', '.join(unlike)}")
        self.layout = lay = _SerialLayout(lat)
        nodes = lay.nodes
        n_loc, n_own = len(nodes["gid"]), lay.n_owned
        self.n_owned = n_own

        # Node arrays -----------------------------------------------------
        self.u = np.zeros((n_loc, 2))
        self.u_prev = np.zeros((n_loc, 2))
        self.f = np.zeros((n_loc, 2))
        self.react = np.zeros((n_loc, 2))
        self.ref_x = nodes["x"].copy()
        self.block = nodes["block"].astype(np.int8)
        self.kind = lat.kinds(nodes, setup.drive.mode)
        self.u_drive0 = np.zeros(n_loc)
        self.fext = np.zeros((n_loc, 2))
        if lat.has_interface:
            self.fext[lat.loaded(nodes), 1] = -s["load.FN"] / lat.top.cols
        self.kn = np.array([mat.kn_bottom, mat.kn_top])
        self.kt = np.array([mat.kt_bottom, mat.kt_top])
        gids = nodes["gid"]
        nbg = lat.neighbour_gids({k: v[:n_own] for k, v in nodes.items()})
        order = np.argsort(gids)     # local order is OWNED, LEFT halo, RIGHT halo: not sorted
        pos = np.minimum(np.searchsorted(gids[order], nbg), len(gids) - 1)
        self.nb = np.where(nbg >= 0, order[pos], -1).astype(np.int64)
        if not np.array_equal(gids[self.nb[nbg >= 0]], nbg[nbg >= 0]):
            raise AssertionError("a neighbour of an owned node is missing from the halo")
        self.dirs = DIRECTIONS.copy()

        # Interface arrays ------------------------------------------------
        self.top_node = lay.top_node
        self.top_owned = lay.top_owned
        self.partner = (lay.top_gsite + lat.top.col0).astype(np.int64) if lat.has_interface \
            else np.zeros(0, np.int64)
        self.x0 = np.zeros(len(self.top_node))
        self.bot_node = lay.bot_node
        self.bot_g0 = lay.bot_gsite0
        self.taken = np.zeros(len(self.bot_node), np.int8)
        self.claim = np.zeros(len(self.top_node), np.int64)
        self.counters = np.zeros(2, np.int64)
        self.own_sites = np.flatnonzero(self.top_owned)
        self.own_bottom_sites = self.bot_node[self.bot_node < n_own]

        self.n = 0
        self._snap_index = {k: j for j, k in enumerate(setup.snapshot_steps)}
        self.first_bad = None      # (step, local index) of the first non-finite update here
        law = setup.law
        self.delta0, self.delta_b = law.delta0, law.delta_b
        self.kx, self.ky = law.kx, law.ky
        self.reform_zero = law.reform == REFORM_ZERO
        self.zeta = setup.damping.zeta

    # -------------------------------------------------------------- phases --
    def load_factor(self, n: int) -> float:
        return ramp_share(n, self.setup.n_ramp)

    def step(self):
        """Advance the state from step n to n+1 (positions u(n) -> u(n+1))."""
        st, n = self.setup, self.n
        drive_on = n >= st.n_drive_start and st.drive.on
        if n == st.n_drive_start:
            self.u_drive0[:] = self.u[:, 0]
        if len(self.top_node):
            kernels.interface_update(self.u, self.ref_x, self.top_node, self.top_owned, self.partner, self.x0,
                                     self.bot_node, self.bot_g0, self.delta0, self.delta_b, self.reform_zero,
                                     self.taken, self.claim, self.counters)
        kernels.bulk_forces(self.u, self.nb, self.block, self.kn, self.kt, self.dirs, self.n_owned, self.f)
        self.react[:] = 0.0
        if len(self.top_node):
            kernels.interface_forces(self.u, self.ref_x, self.top_node, self.top_owned, self.partner, self.x0,
                                     self.bot_node, self.bot_g0, self.delta0, self.kx, self.ky, self.f, self.react)
        shift = st.v0 * ((n + 1 - st.n_drive_start) * st.dt)
        bad = kernels.verlet_update(self.u, self.u_prev, self.f, self.react, self.fext, self.load_factor(n),
                                    self.kind, self.u_drive0, shift, drive_on, st.dt, self.zeta, self.n_owned)
        if bad >= 0 and self.first_bad is None:
            self.first_bad = (n + 1, bad)
        self.n = n + 1

    # ----------------------------------------------------------- checks -----
    def check_health(self):
        """Stop if the state went non-finite (the step and the node are in the message)."""
        if self.first_bad is not None:
            raise NonFiniteError(self.describe_bad()[1])

    def describe_bad(self):
        step, i = self.first_bad
        nd = self.layout.nodes
        st = self.setup
        blk = "top" if nd["block"][i] == TOP else "bottom"
        t = st.to_lcr((step - st.n_drive_start) * st.dt)
        return (nd["gid"][i], f"state became non-finite at step {step} (t = {t:.4g} l/c_r from drive start) "
                f"at node {nd['gid'][i]} ({blk} block, row {nd['row'][i]}, column {nd['col'][i]}, "
                f"x = {nd['x'][i]:.4g} a, y = {nd['y'][i]:.4g} a); try a smaller time.safety")

    # ------------------------------------------------------------ fields ----
    def interface_state(self):
        """Owned top sites in global site order: intact (uint8), ux/l, uy/l, partner, and the
        interface traction sxy = -f_x/(a rho c_r^2), syy = -f_y/(a rho c_r^2) of the bond's force f on the top node."""
        s = self.own_sites
        nodes = self.top_node[s]
        l = self.setup.l
        p = self.partner[s]
        bonded = p >= 0
        q = np.where(bonded, p - self.bot_g0, 0)
        ib = self.bot_node[np.clip(q, 0, max(len(self.bot_node) - 1, 0))] if len(self.bot_node) else q
        dx = (self.ref_x[nodes] - self.ref_x[ib]) + (self.u[nodes, 0] - self.u[ib, 0])
        dy = self.delta0 + (self.u[nodes, 1] - self.u[ib, 1])
        scale = 1.0 / (DENSITY * self.setup.material.c_r ** 2)
        sxy = np.where(bonded, self.kx * (dx - self.x0[s]) * scale, 0.0)
        syy = np.where(bonded, self.ky * (dy - self.delta0) * scale, 0.0)
        return (bonded.astype(np.uint8), self.u[nodes, 0] / l, self.u[nodes, 1] / l, p.astype(np.int32), sxy, syy)

    def node_fields(self):
        """Owned nodes: positions (N,3), velocities (N,3), stress (N,3) in rho c_r^2."""
        n = self.n_owned
        nd = self.layout.nodes
        pos = np.zeros((n, 3))
        pos[:, 0] = nd["x"][:n] + self.u[:n, 0]
        pos[:, 1] = nd["y"][:n] + self.u[:n, 1]
        vel = np.zeros((n, 3))
        vel[:, :2] = (self.u[:n] - self.u_prev[:n]) / self.setup.dt
        sig = np.zeros((n, 3))
        kernels.node_stress(self.u, self.nb, self.block, self.kn, self.kt, self.dirs, n,
                            0.5 / self.setup.material.c_r ** 2, sig)
        return pos, vel, sig

    def energy_per_node(self, load=None):
        out = np.zeros(self.n_owned)
        lf = self.load_factor(self.n) if load is None else load
        kernels.potential_energy(self.u, self.ref_x, self.nb, self.block, self.kn, self.kt, self.dirs,
                                 self.n_owned, self.fext, lf, self.top_node, self.top_owned, self.partner,
                                 self.x0, self.bot_node, self.bot_g0, self.delta0, self.kx, self.ky, out)
        return out

    # -------------------------------------------------------------- loop ----
    def run(self, writer=None, progress=None, until: int | None = None):
        """Advance to step ``until`` (default: the end), writing frames on the way."""
        st = self.setup
        end = st.n_steps if until is None else until
        check_every = max(1, min(st.frame_every, 200))
        while self.n < end:
            self._output(writer)
            self.step()
            if self.n % check_every == 0:
                self.check_health()
            if progress is not None:
                progress.update(self.n)
        self.check_health()
        self._output(writer)

    def _output(self, writer):
        st = self.setup
        k = self.n - st.n_drive_start
        if writer is None or k < 0:
            return
        t = st.to_lcr(k * st.dt)
        if k % st.frame_every == 0 and k // st.frame_every < st.n_frames:
            writer.interface_frame(k // st.frame_every, t, *self.interface_state())
        j = self._snap_index.get(k)
        if j is not None:
            writer.snapshot(j, t, *self.node_fields(), self.partner[self.own_sites])
