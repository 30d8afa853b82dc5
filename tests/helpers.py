"""Shared builders for the tests: scenes from dotted overrides, state access by global id."""
from __future__ import annotations

import numpy as np

from parslip.engine.reference import Simulation as ReferenceSimulation
from parslip.engine.simulation import Simulation
from parslip.model.lattice import TOP
from parslip.scene.derive import derive
from parslip.scene.load import resolve

# A free block at rest: no substrate, no load, no drive, no damping.
FREE_BLOCK = {"lattice.bottom_rows": 0, "drive.mode": "none", "load.ramp": 0.0, "load.settle": 0.0,
              "load.FN": 0.0, "time.zeta": 0.0, "output.snapshots": 0}

# The paper's set-up shrunk to seconds: bonds break and re-form within a few l/c_r.
SMALL = {"lattice.top_rows": 4, "lattice.top_cols": 24, "lattice.bottom_rows": 4, "lattice.bottom_cols": 40,
         "load.ramp": 0.5, "load.settle": 2.0, "drive.v0": 0.02, "drive.duration": 6.0,
         "output.snapshots": 3}


def small_toml(**kw) -> str:
    """SMALL (plus overrides) as scene-file text, for tests that go through the command line."""
    from parslip.scene.schema import to_toml
    over = dict(SMALL)
    over.update(kw)
    return to_toml(over)


def scene(**kw) -> dict:
    """Resolved scene from keyword overrides: scene(**{"drive.v0": 1e-2})."""
    return resolve({}, list(kw.items()))


def simulation(base: dict | None = None, **kw) -> Simulation:
    over = dict(base or {})
    over.update(kw)
    return Simulation(derive(scene(**over)))


def set_field(sim: Simulation, fn) -> None:
    """u = fn(x, y) -> (ux, uy) on every node, at rest (u(n-1) = u(n))."""
    nd = sim.state.nodes()
    ux, uy = fn(nd["x"], nd["y"])
    sim.set_u(np.stack([ux, uy], axis=1))


def row_nodes(sim: Simulation, row: int) -> np.ndarray:
    """Indices (into the arrays in global id order) of a row of the top block, sorted by x."""
    nd = sim.state.nodes()
    idx = np.flatnonzero((nd["block"] == TOP) & (nd["row"] == row))
    return idx[np.argsort(nd["x"][idx])]


def reference(sim: Simulation) -> ReferenceSimulation:
    """The first engine's plain per-node implementation, holding a copy of ``sim``'s state (one rank).

    An independent implementation of the same model: its kernels gather
    neighbours by index and sum each bond's force on its own.
    """
    ref = ReferenceSimulation(sim.setup)
    assert np.array_equal(ref.layout.nodes["gid"][:ref.n_owned], sim.state.gid)
    ref.u[:ref.n_owned] = sim.u
    ref.u_prev[:ref.n_owned] = sim.u_prev
    ref.partner[ref.own_sites] = sim.state.owned_partner()
    ref.x0[ref.own_sites] = sim.state.owned_x0()
    ref.n = sim.n
    return ref


# --- drawn interface records with known rupture fronts (front detector, paper table, accuracy) ---

DT = 0.05          # l/c_r per frame
NS = 60            # sites: dx = 1/60 l


def blank(nf):
    x = (np.arange(NS) + 0.5) / NS
    return {"t": np.arange(nf) * DT, "x": x, "intact": np.ones((nf, NS), np.uint8),
            "ux": np.zeros((nf, NS)), "uy": np.zeros((nf, NS))}


def draw(iface, k0, s0, d, fps, width, slip, crack=False, sites=None, slip_v=0.0):
    """Tip at site s0 + d*j from frame k0 + fps*j; the `width` sites behind it broken (a crack keeps all).

    A pulse adds `slip` to ux (and `slip_v` to uy) at a site from the frame it re-bonds; a crack from the
    frame it breaks.  Returns the arrival frames.
    """
    nf = len(iface["t"])
    n = sites or (NS - s0 if d > 0 else s0 + 1)
    arr = k0 + fps * np.arange(n)
    for k in range(k0, nf):
        j = min((k - k0) // fps, n - 1)
        tip = s0 + d * j
        back = j if crack else min(width - 1, j)
        lo, hi = sorted((tip, tip - d * back))
        iface["intact"][k, lo:hi + 1] = 0
        if not crack and j == n - 1 and k >= arr[-1] + fps:
            break                                   # the pulse has left through the far edge
    for j in range(n):
        s = s0 + d * j
        on = np.flatnonzero(iface["intact"][arr[j]:, s] == 1)
        k_slip = arr[j] if crack else arr[j] + on[0]
        iface["ux"][k_slip:, s] += slip
        iface["uy"][k_slip:, s] += slip_v
    return arr
