"""Where a precursor should stop: the static fracture-mechanics prediction of an arrest (Kammer et al.,
Tribol. Lett. 2015; Bayart et al., Nat. Phys. 2016), set beside the arrest the run measured.

A front that starts at the driven (rear) edge of the contact is taken as a mode II crack of length L from
that edge.  Its faces are unloaded from the shear traction tau_0(x) the interface held before the front
nucleated to the residual tau_r it holds after the front has passed, so the crack is driven by the stress
drop dtau(x) = tau_0(x) - tau_r.  The static stress intensity factor of an edge crack of length L in a
half-plane loaded by dtau on its faces (Tada, Paris & Irwin, The Stress Analysis of Cracks Handbook, 2000,
the edge crack in a semi-infinite plate, as Kammer et al. 2015 use it):

    K(L) = 2/sqrt(pi L) int_0^L dtau(x) F(x/L) / sqrt(1 - (x/L)^2) dx
         = 2 sqrt(L/pi) int_0^{pi/2} dtau(L sin th) F(sin th) d th,
    F(s) = 1 + (1 - s^2)(0.2945 - 0.3912 s^2 + 0.7685 s^4 - 0.9942 s^6 + 0.5094 s^8),

so a uniform drop gives K = 1.1215 dtau sqrt(pi L).  A front that nucleated inside the contact (further than
``friction.edge_sites`` from the edge it runs away from) is taken as a crack on an unbounded interface between
its trailing tip, fixed at the nucleation site, and its leading tip, L ahead: the leading tip of a Griffith
crack with arbitrary face loads (Tada et al. 2000), s measured from the trailing tip,

    K(L) = 1/sqrt(pi L/2) int_0^L dtau(s) sqrt(s/(L - s)) ds
         = 2 sqrt(2L/pi) int_0^{pi/2} dtau(L sin^2 th) sin^2 th d th,

so a uniform drop gives K = dtau sqrt(pi L/2) (half-length L/2).  Both lie in one solid on both sides of the
interface, as the identical-solid scenes are.  The energy release rate is G(L) = 1/2 H(0) K^2 with H(0) the
static mode II compliance of the block's Born continuum (signed, 1/2 H(0) K |K|: a crack pushed back, K < 0,
does not count as driven) (``cracks.mode2_compliance``: (1 - nu)/mu for an isotropic solid).  The front
stops where G falls to the fracture energy Gamma: the predicted arrest is the first L, past the first one at
which G reached Gamma, where G < Gamma again.  The plane has no height: the prediction holds for L below the
block's height H; a longer crack in a block of finite height releases more than the plane's G (the block's
bending adds to it), so there the prediction is short of a lattice that follows the continuum.

  edge_factor(s)                       F(s)
  edge_k(drop, L)                      K(L) for a drop sampled at the sites (one per spacing a; L in a)
  interior_k(drop, L)                  K(L) at the leading tip of the interior crack, drop from its trailing tip
  release_curve(drop, H0, geometry)    signed G at every L = 1..len(drop) sites ("edge" or "interior")
  predicted_length(G, gamma)           the first L where G falls back below gamma (sites); NaN or len(G)
  arrest_prediction(run, precursor)    the prediction for one of run.precursors() or edge_cracks(), with its inputs
  break_bursts(t, site, gap)           the bursts of an interface's breaks: runs of breaks no more than gap apart
  edge_cracks(run, gap, min_span)      the bursts that grew a crack from the loaded edge, as arrests to predict

Units: lengths in a unless named otherwise; tractions as stress (same units as dtau); K in stress sqrt(a);
G and Gamma in energy per a (m c_r^2 / a for the run's measures).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .cracks import DENSITY, _material, gamma_run, mode2_compliance
from .friction import edge_sites

EDGE_POLY = (0.2945, -0.3912, 0.7685, -0.9942, 0.5094)   # F(s) - 1 = (1 - s^2) sum_k c_k s^(2k)  (Tada 2000)
QUAD_POINTS = 256          # Gauss-Legendre points in theta over [0, pi/2]: the integrand is smooth there


def edge_factor(s):
    """F(s) of the edge-crack weight function (module docstring), s = x/L in [0, 1]."""
    s2 = np.asarray(s, float) ** 2
    poly = sum(c * s2 ** k for k, c in enumerate(EDGE_POLY))
    return 1.0 + (1.0 - s2) * poly


_TH, _W = np.polynomial.legendre.leggauss(QUAD_POINTS)
_TH = 0.25 * math.pi * (_TH + 1.0)           # nodes on [0, pi/2]
_W = 0.25 * math.pi * _W


def edge_k(drop, L: float) -> float:
    """K(L) = 2 sqrt(L/pi) int_0^{pi/2} dtau(L sin th) F(sin th) d th for a drop sampled at the sites:
    ``drop[i]`` holds on i <= x < i + 1 (x in a from the edge); stress sqrt(a)."""
    drop = np.asarray(drop, float)
    s = np.sin(_TH)
    idx = np.minimum((L * s).astype(int), len(drop) - 1)
    return float(2.0 * math.sqrt(L / math.pi) * np.sum(_W * drop[idx] * edge_factor(s)))


def interior_k(drop, L: float) -> float:
    """K(L) = 2 sqrt(2L/pi) int_0^{pi/2} dtau(L sin^2 th) sin^2 th d th at the leading tip of a crack on an
    unbounded interface whose trailing tip is at s = 0: ``drop[i]`` holds on i <= s < i + 1 (s in a from the
    trailing tip); stress sqrt(a).  The substitution s = L sin^2 th removes the (L - s)^-1/2 of the tip."""
    drop = np.asarray(drop, float)
    s2 = np.sin(_TH) ** 2
    idx = np.minimum((L * s2).astype(int), len(drop) - 1)
    return float(2.0 * math.sqrt(2.0 * L / math.pi) * np.sum(_W * drop[idx] * s2))


GEOMETRIES = {"edge": edge_k, "interior": interior_k}


def release_curve(drop, H0: float, geometry: str = "edge") -> np.ndarray:
    """G(L) = 1/2 H0 K(L) |K(L)| at L = 1, 2, ..., len(drop) sites (H0 the static mode II compliance), K of the
    edge crack or of the interior crack (``GEOMETRIES``): signed, so that a crack whose faces are pushed back
    (K < 0, a drop that turned negative ahead) reads G < 0 rather than the release of a crack loaded the
    other way."""
    k = GEOMETRIES[geometry]
    K = np.array([k(drop, L) for L in range(1, len(drop) + 1)])
    return 0.5 * H0 * K * np.abs(K)


def predicted_length(G, gamma: float) -> float:
    """The predicted arrest length (sites) from G at L = 1, 2, ...: the first L past the first one where
    G >= gamma at which G < gamma again; NaN when G never reaches gamma (no front), len(G) when it never
    falls back (the front crosses)."""
    G = np.asarray(G, float)
    up = np.flatnonzero(G >= gamma)
    if not len(up):
        return math.nan
    down = np.flatnonzero(G[up[0]:] < gamma)
    return float(up[0] + down[0] + 1) if len(down) else float(len(G))


def _frame(t, time: float, after: bool) -> int:
    k = int(np.searchsorted(t, time, side="right"))
    return min(k, len(t) - 1) if after else max(k - 1, 0)


def arrest_prediction(run, pre, gamma: float | None = None) -> dict:
    """The arrest fracture mechanics predicts for precursor ``pre`` (``run.precursors()``): {"L_measured",
    "L_predicted" (a), "tau_r" (rho c_r^2, the mean traction over the slipped stretch in the first frame after
    the arrest), "Gamma" (m c_r^2 / a: ``gamma`` when given, the law's fracture energy of a scene that has
    one; else the mean stored energy of its breaks, ``cracks.gamma_run``, the energy of a bond that breaks at
    its peak),
    "G_at_arrest_over_Gamma" (the static G at the measured length over Gamma), "from_edge" (whether it started
    within ``edge_sites`` of the contact's edge it runs away from), "geometry" ("edge": the edge crack from
    that edge; "interior": the crack from its nucleation site, module docstring)}.  NaN predictions where the
    front's breaks carry no Gamma."""
    iface, ns = run.interface, len(run.x)
    t = np.asarray(iface["t"], float)
    d = pre.front.direction if pre.front.direction != 0 else 1
    order = np.arange(ns) if d > 0 else np.arange(ns)[::-1]     # sites counted from the edge it leaves
    n0 = int(np.argmin(np.abs(run.x - pre.nucleation_x)))
    depth = n0 if d > 0 else ns - 1 - n0
    L_meas = pre.arrest_length * ns
    edge = depth < edge_sites(ns)
    out = {"L_measured": L_meas, "L_predicted": math.nan, "tau_r": math.nan, "Gamma": math.nan,
           "G_at_arrest_over_Gamma": math.nan, "from_edge": edge, "geometry": "edge" if edge else "interior"}
    before = np.asarray(iface["sxy"][_frame(t, pre.nucleation_time, False)], float)[order]
    after = np.asarray(iface["sxy"][_frame(t, pre.arrest_time, True)], float)[order]
    sign = 1.0 if before.sum() >= 0 else -1.0                   # the load's sense: dtau > 0 drives the front
    if not edge:                                                # the interior crack's faces: from its nucleation on
        before, after = before[depth:], after[depth:]
    n = max(int(round(L_meas)), 1)
    tau_r = float(np.mean(sign * after[:n]))
    if gamma is None:
        g = np.asarray(gamma_run(run, pre.front)["Gamma"], float)
        gamma = float(np.nanmean(g)) if np.isfinite(g).any() else math.nan
    out.update(tau_r=tau_r, Gamma=gamma)
    if not math.isfinite(gamma):
        return out
    m = _material(run)
    c_r = float(run.attrs["c_r"])
    scale = DENSITY * c_r * c_r                                 # rho c_r^2 -> internal stress
    H0 = mode2_compliance(0.0, m.kn_top, m.kt_top)
    G = release_curve((sign * before - tau_r) * scale, H0, out["geometry"]) / c_r ** 2
    out["L_predicted"] = predicted_length(G, gamma)
    out["G_at_arrest_over_Gamma"] = float(G[min(n, len(G)) - 1] / gamma)
    return out



def break_bursts(t, site, gap: float) -> list[np.ndarray]:
    """The bursts of a record of breaks (times ``t``, sorted, and their sites): the indices of each maximal run
    of breaks whose successive times are at most ``gap`` apart (same units as ``t``)."""
    t = np.asarray(t, float)
    if not len(t):
        return []
    cut = np.flatnonzero(np.diff(t) > gap) + 1
    return np.split(np.arange(len(t)), cut)


@dataclass
class EdgeCrack:
    """A burst of breaks that grew the slipped region from the loaded edge (lengths in l, times in l/c_r): its
    breaks' first and last times, the edge it grew from (``nucleation_x``, the edge site's x), its first break
    (``first_x``), its farthest break (``arrest_x``) and the crack's length from the edge to there
    (``arrest_length``), the sites its breaks span (``span``), how many breaks it holds and whether it stopped
    short of the far edge (``arrested``: its farthest break more than ``friction.edge_sites`` from it)."""
    nucleation_time: float
    arrest_time: float
    nucleation_x: float
    first_x: float
    arrest_x: float
    arrest_length: float
    span: int
    breaks: int
    arrested: bool
    direction: int

    @property
    def front(self) -> "EdgeCrack":
        """Itself, read as a front by ``arrest_prediction`` (which takes only its ``direction``)."""
        return self


def edge_cracks(run, gap: float, min_breaks: int, direction: int = 1) -> list[EdgeCrack]:
    """The precursors of an interface whose broken sites stay broken (slipping at their residual) until they
    re-form: the bursts (``break_bursts``, ``gap`` in l/c_r) of the drive's breaks (``run.events``, time >= 0)
    that hold at least ``min_breaks`` breaks, each as the crack from the loaded edge (x = 0 for ``direction``
    +1, the push; x = l for -1) to its farthest break.  The catalogue of fronts (``fronts``) cuts such a crack
    where its tip runs through sites that have not re-formed (no break there), so its pieces read as fronts
    merged into each other; a burst keeps them whole."""
    ev, ns = run.events, len(run.x)
    brk = (np.asarray(ev["kind"]) == 1) & (np.asarray(ev["time"], float) >= 0.0)
    t, site = np.asarray(ev["time"], float)[brk], np.asarray(ev["site"], int)[brk]
    order = np.argsort(t, kind="stable")
    t, site = t[order], site[order]
    depth = site if direction > 0 else ns - 1 - site              # sites from the loaded edge
    edge_x = float(run.x[0] if direction > 0 else run.x[-1])
    out = []
    for idx in break_bursts(t, site, gap):
        if len(idx) < min_breaks:
            continue
        far, tip = int(depth[idx].max()), int(site[idx][np.argmax(depth[idx])])
        out.append(EdgeCrack(nucleation_time=float(t[idx[0]]), arrest_time=float(t[idx[-1]]), nucleation_x=edge_x,
                             first_x=float(run.x[site[idx[0]]]), arrest_x=float(run.x[tip]),
                             arrest_length=(far + 1) / ns, span=int(far - depth[idx].min() + 1), breaks=len(idx),
                             arrested=far < ns - 1 - edge_sites(ns), direction=direction))
    return out
