"""Scaling model of the time per step: what each rank computes and exchanges, a fit to measured runs, predictions.

    python -m parslip.studies.bench.scaling layout run/push_l500.toml --ranks 64      # per-rank table of the decomposition
    python -m parslip.studies.bench.scaling measure --sizes 100 300 500 1000 --ranks 1 2 3 --json points.json
    python -m parslip.studies.bench.scaling fit points.json --exclude-ranks 3 --predict 2000:64
    parslip bench --scaling                                                    # measure, fit and predict in one

The model.  Every step each rank updates its OWNED nodes and interface
sites, then waits for the halo values its peers send, so a step lasts as
long as its busiest rank's share:

    t_step = max over ranks r of ( a N_r + s S_r + b H_r + m M_r ) + c        (microseconds)

    N_r  nodes rank r owns (lattice nodes; the drive's and the fixed row's included),
    S_r  interface sites (top interface nodes) rank r owns: each costs a bond update and the
         re-bonding search on top of its node update,
    H_r  halo values rank r sends plus receives per step: 2 (x and y) per HALO node copy and
         one per travelling bond row (4: partner, x0, healing candidate and clock) per HALO interface site, as ``parallel.exchange`` packs them,
    M_r  messages rank r sends plus receives per step: 2 per peer (one each way),
    c    the fixed cost of a step (loop overhead, flag checks, the exchange's calls).

a and s are in us per node and per site (1/a is the per-core throughput in
node updates per us), b in us per value, m in us per message.  The features
are exact counts from ``parallel.layout`` (``rank_features``), not
estimates.  The fit (``fit``) is weighted least squares on relative
residuals, (t_model - t_measured) / t_measured, since the measured times
span two orders of magnitude; it takes the max over ranks of each feature
separately (for balanced slabs the busiest rank in nodes is also the one
with the most halo, up to the two end slabs' single neighbour).  Which
terms enter is the caller's: on one shared-memory machine M is 0 or 2 for
every 1- or 2-rank point and cannot be told apart from c, so the fit on
this machine leaves m out and a cluster prediction adds it from an assumed
network latency (``predict``).

Measured points come from ``parslip.studies.bench.case`` under mpiexec (one JSON
line per case: ``us_per_step``, per-phase times, owned nodes per rank).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from ...model.lattice import BOTTOM, TOP

TERMS = {"N": "a", "S": "s", "H": "b", "M": "m", "1": "c"}
UNITS = {"a": "us/node", "s": "us/site", "b": "us/value", "m": "us/message", "c": "us"}


# ---------------------------------------------------------------------------------------------- features --
@dataclass
class RankShare:
    """What one rank computes and exchanges in one step (counts; columns in a)."""
    rank: int
    cols: tuple                 # global columns [c0, c1) it owns
    nodes: int                  # N: owned nodes
    sites: int                  # S: owned interface sites of the sliding block
    values_sent: int
    values_received: int
    peers: list                 # ranks it exchanges with, ascending
    halo_top: tuple             # (left, right) HALO columns of the block's interface row
    halo_bottom: tuple          # (left, right) HALO columns of the substrate's interface row
    halo_bulk: int              # HALO columns of a bulk row (widest side)
    peer_values: dict = field(default_factory=dict)   # peer -> values received from it per step

    @property
    def values(self) -> int:
        """H: halo values sent plus received per step."""
        return self.values_sent + self.values_received

    @property
    def messages(self) -> int:
        """M: messages sent plus received per step (one each way per peer)."""
        return 2 * len(self.peers)

    @property
    def hops(self) -> int:
        """How many slabs away its farthest peer is (1: neighbours only)."""
        return max((abs(p - self.rank) for p in self.peers), default=0)


def _seg_values(segments) -> int:
    """Values a list of row segments carries: x and y of each node."""
    return sum(2 * (sg.hi - sg.lo) for sg in segments)


def _site_values(sites) -> int:
    """Values a list of interface-site ranges carries: the travelling rows of the bond table of each site
    (``model.interface.BONDS.travel``: partner, x0, the healing candidate and clock)."""
    from ...model.interface import BONDS
    return sum(len(BONDS.travel) * (hi - lo) for lo, hi in sites)


def _halo_sides(blk, r: int) -> tuple[int, int]:
    (olo, ohi), (slo, shi) = blk.owned[r], blk.stored[r]
    if ohi <= olo:
        return 0, 0
    return int(olo - slo), int(shi - ohi)


def rank_share(lattice, layout) -> RankShare:
    """The counts of ``RankShare`` for one rank's layout (``parallel.layout.build_layout``)."""
    c0, c1 = layout.col_range
    bl, tl = layout.blocks
    sites = 0
    halo_top = halo_bottom = (0, 0)
    if lattice.has_interface:
        lo, hi = tl.owned[0]
        sites = int(max(hi - lo, 0))
        halo_top = _halo_sides(tl, 0)
        if not lattice.rigid:
            halo_bottom = _halo_sides(bl, bl.rows - 1)
    bulk = 0
    for b, blk in ((BOTTOM, bl), (TOP, tl)):
        for r in range(blk.rows):
            if lattice.has_interface and ((b == TOP and r == 0) or (b == BOTTOM and r == blk.rows - 1)):
                continue
            bulk = max(bulk, *_halo_sides(blk, r))
    sent = sum(_seg_values(p.send) + _site_values(p.send_sites) for p in layout.peers)
    recv = {p.rank: _seg_values(p.recv) + _site_values(p.recv_sites) for p in layout.peers}
    nodes = sum(int(blk.rows) * max(int(blk.owned[0][1] - blk.owned[0][0]), 0)
                for b, blk in ((BOTTOM, bl), (TOP, tl)) if blk.rows and lattice.numbered[b])
    return RankShare(rank=layout.rank, cols=(c0, c1), nodes=nodes,
                     sites=sites, values_sent=sent, values_received=sum(recv.values()),
                     peers=sorted(recv), halo_top=halo_top, halo_bottom=halo_bottom, halo_bulk=bulk,
                     peer_values=recv)


def rank_shares(setup, ranks: int) -> list[RankShare]:
    """Every rank's share of a run of ``setup`` on ``ranks`` ranks (no MPI: the layouts are pure)."""
    from ...parallel.layout import build_layout
    lat = setup.lattice
    return [rank_share(lat, build_layout(lat, r, ranks, setup.reach, setup.scene["drive.mode"],
                                           overlap=setup.overlap))
            for r in range(ranks)]


def features(shares: list[RankShare]) -> dict:
    """The model's features of one run: the max over ranks of N, S, H and M, and 1."""
    return {"N": max(s.nodes for s in shares), "S": max(s.sites for s in shares),
            "H": max(s.values for s in shares), "M": max(s.messages for s in shares), "1": 1}


# -------------------------------------------------------------------------------------------------- fit --
@dataclass
class Fit:
    """A fitted model: coefficients by name (``TERMS``), their standard errors, the points it was fitted to."""
    terms: tuple
    coef: dict
    stderr: dict
    points: list                # dicts with "features", "us_per_step" and anything else the caller kept
    rms_rel: float              # root mean square of the relative residuals

    def predict(self, feats: dict, extra: dict | None = None) -> float:
        """t_step (us) for features ``feats``; ``extra`` adds coefficients the fit lacks (e.g. m)."""
        coef = dict(self.coef)
        coef.update(extra or {})
        return sum(coef[TERMS[t]] * feats[t] for t in TERMS if TERMS[t] in coef)

    def residuals(self) -> np.ndarray:
        """(t_model - t_measured) / t_measured of each fitted point."""
        return np.array([self.predict(p["features"]) / p["us_per_step"] - 1 for p in self.points])


def fit(points: list[dict], terms=("N", "H", "1")) -> Fit:
    """Least squares of ``t_step = sum_k coef_k x_k`` on relative residuals.

    Minimises sum_i ((sum_k coef_k x_ik - t_i) / t_i)^2, i.e. ordinary least
    squares of the design rows x_ik / t_i against 1.  Standard errors from
    the covariance s^2 (X^T X)^-1 of that problem, with s^2 the residual sum
    of squares over (points - terms); zero when the points are as many as
    the terms.  Raises ValueError when the points cannot determine the terms.
    """
    terms = tuple(terms)
    X = np.array([[float(p["features"][t]) for t in terms] for p in points])
    y = np.array([float(p["us_per_step"]) for p in points])
    Xw = X / y[:, None]
    if len(points) < len(terms) or np.linalg.matrix_rank(Xw) < len(terms):
        raise ValueError(f"{len(points)} points cannot determine the terms {terms}: the design has rank "
                         f"{np.linalg.matrix_rank(Xw)}")
    ones = np.ones(len(points))
    coef, *_ = np.linalg.lstsq(Xw, ones, rcond=None)
    res = Xw @ coef - ones
    dof = len(points) - len(terms)
    s2 = float(res @ res) / dof if dof > 0 else 0.0
    cov = s2 * np.linalg.inv(Xw.T @ Xw)
    names = [TERMS[t] for t in terms]
    return Fit(terms=terms, coef=dict(zip(names, coef.tolist())),
               stderr=dict(zip(names, np.sqrt(np.maximum(np.diag(cov), 0)).tolist())),
               points=list(points), rms_rel=float(np.sqrt(np.mean(res ** 2))))


# ------------------------------------------------------------------------------------------ prediction --
@dataclass
class Cluster:
    """What a prediction assumes of the cluster: how its cores and its network compare with this machine.

    throughput_ratio  per-core node-update rate there / here (1: the same core and memory bandwidth per core)
    latency_us        time a message costs on the network (MPI small-message latency and software overhead)
    bandwidth_gbs     network bandwidth per rank, GB/s (the halo's bytes cost 8 / bandwidth ns per value)
    overlap           True: the messages travel while the interior computes (as ``engine.loop`` does), so
                      only what exceeds the interior's compute time adds to the step
    """
    throughput_ratio: float = 1.0
    latency_us: float = 2.0
    bandwidth_gbs: float = 10.0
    overlap: bool = False


def predict(f: Fit, shares: list[RankShare], cluster: Cluster, value_bytes: int = 8) -> dict:
    """t_step (us) of a run with these shares on a cluster, from a fit on this machine.

    compute  = (a N + s S) / throughput_ratio + c            of the busiest rank,
    network  = M latency + H value_bytes / bandwidth          per step of the busiest rank,
    exposed  = network, or with overlap max(0, network - interior compute) where the interior
               is the compute of the nodes no peer needs (the late tasks: about N minus the
               halo-facing columns; taken as compute x (1 - H / (2 N)), a lower bound on it),
    t_step   = compute + b_pack H + exposed,  with b_pack the fitted shared-memory cost per value
               (packing and unpacking stay on the cores; on this machine it also holds the
               shared-memory copy, so it counts that twice: an upper bound).
    """
    feats = features(shares)
    a, s, c = f.coef.get("a", 0.0), f.coef.get("s", 0.0), f.coef.get("c", 0.0)
    b = f.coef.get("b", 0.0)
    worst = max(shares, key=lambda r: a * r.nodes + s * r.sites)
    compute = (a * worst.nodes + s * worst.sites) / cluster.throughput_ratio + c
    H, M = feats["H"], feats["M"]
    network = M * cluster.latency_us + H * value_bytes / (cluster.bandwidth_gbs * 1e3)
    interior = compute * max(0.0, 1 - H / (2 * max(worst.nodes, 1)))
    exposed = max(0.0, network - interior) if cluster.overlap else network
    t = compute + b * H + exposed
    return {"features": feats, "compute_us": compute, "pack_us": b * H, "network_us": network,
            "exposed_network_us": exposed, "us_per_step": t}


@dataclass
class Coefficients:
    """What the travel model (``travel_model``) charges per step, and the network it assumes.

    node_ns            ns per node update of one core (1 / the per-core throughput `parslip bench` measures)
    site_ns            ns per interface site the bond update runs over, beyond its node update
    segment_ns         ns a row costs beyond its nodes (its views, the loop's ends; consecutive rows: one task)
    single_ns          ns per node the loop updates on its own (block edges, short pieces)
    fixed_us           us per step that does not scale (loop overhead, flag checks, the exchange's calls)
    pack_ns_per_value  ns to pack or unpack one halo value (``studies.bench.pack``, measured directly)
    latency_us         us per message (MPI's small-message latency on the network; measured by MPI's messages
                       between 2 ranks, ``run.exchange = "messages"``: ranks on one node that share memory
                       pay less, ``parallel.shm``)
    bandwidth_gbs      GB/s per rank on the network
    overlap            the messages travel while the interior computes (``run.overlap``: the scene's, set by
                       ``travel_model``; the code before overlapped)
    source             where the coefficients come from
    """
    node_ns: float = 1.68
    site_ns: float = 20.0
    segment_ns: float = 30.0        # 29.8 measured at eb55656 (rows merged into one task)
    single_ns: float = 20.0
    fixed_us: float = 1.0
    pack_ns_per_value: float = 2.5
    latency_us: float = 2.0
    bandwidth_gbs: float = 10.0
    overlap: bool = False
    source: str = "defaults"


def coefficients(precision: str = "float64") -> Coefficients:
    """The coefficients `parslip bench` measured on this host (``io.cache``'s coefficients file), else the
    defaults: the per-core throughput of ``scene.budget.THROUGHPUT``, a site at ``layout.SITE_COST`` node
    updates, and the packing, row and fixed costs measured on the project's 2-core x86-64 host.  Whether the
    exchange overlaps is the scene's (``run.overlap``), never the host's: a stored value is ignored."""
    from ...io.cache import load_coefficients
    from ...parallel.layout import SITE_COST
    from ...scene.budget import THROUGHPUT
    node_ns = 1e9 / THROUGHPUT[precision]
    base = Coefficients(node_ns=node_ns, site_ns=SITE_COST * node_ns)
    stored = load_coefficients()
    if not stored:
        return base
    known = {k: v for k, v in stored.items() if k in Coefficients.__dataclass_fields__ and k != "overlap"}
    return Coefficients(**{**base.__dict__, **known})


def travel_shifts(setup, samples: int = 5) -> list[int]:
    """The block's shifts (columns) the travel model looks at: from none to the drive's whole travel, when the
    halos follow the slip; none when the scene fixes a slip reach (its slabs never move)."""
    if setup.reach.drift is None or not setup.lattice.has_interface:
        return [0]
    travel = setup.drive.travel(setup.material.c_r, setup.t_unit)
    return sorted({int(round(travel * k / max(samples - 1, 1))) for k in range(samples)})


def step_model(counts, coef: Coefficients) -> dict:
    """Each rank's predicted time per step (us) from its counts (``parallel.counts.Counts``):

        compute  = node_ns N + site_ns (S + F)           F: the HALO sites its bond update also runs over
                   + segment_ns R + single_ns O          R row segments, O nodes updated on their own
        pack     = pack_ns_per_value H                   H: halo values sent plus received
        network  = (M / 2) latency + 8 H / bandwidth      M: messages sent plus received
        exposed  = max(0, network - interior) with overlap, else network, where the interior is the
                   compute of the nodes no peer needs, at least compute (1 - H / (2 N))
        step     = compute + pack + exposed + fixed_us

    The busiest rank sets the step, as every rank waits for its peers' halos."""
    foreign = counts.halo_top.sum(axis=1)
    compute = (coef.node_ns * counts.nodes + coef.site_ns * (counts.sites + foreign) + coef.segment_ns * counts.segments
               + coef.single_ns * counts.singles) / 1e3
    values = counts.values
    pack = coef.pack_ns_per_value * values / 1e3
    network = counts.messages / 2 * coef.latency_us + 8 * values / (coef.bandwidth_gbs * 1e3)
    interior = compute * np.clip(1 - values / (2 * np.maximum(counts.nodes, 1)), 0, 1)
    exposed = np.maximum(network - interior, 0) if coef.overlap else network
    step = compute + pack + exposed + coef.fixed_us
    return {"step": step, "compute": compute + coef.fixed_us, "foreign": foreign}


def travel_model(setup, ranks: int, coef: Coefficients, gather: bool = True, samples: int = 5) -> dict:
    """The busiest rank's figures per step, each the maximum over the scene's whole travel (``travel_shifts``:
    the slabs cut for the block at each shift, its halos those of a drift box with the scene's skin), and
    rank 0's memory over the median rank's; every count in closed form (``parallel.counts``), so it takes
    seconds at thousands of ranks.  Keys as `parslip info --json` prints them.  Whether the exchange overlaps
    is the scene's (``run.overlap``)."""
    from dataclasses import replace
    from ...parallel.counts import rank_counts
    from ...parallel.layout import Drift, drift_reach, slab_bounds
    from ...scene.memory import per_rank_bytes
    lat = setup.lattice
    coef = replace(coef, overlap=setup.overlap)
    out = {"ranks": ranks, "shifts": travel_shifts(setup, samples), "peers_max": 0, "messages_per_step": 0,
           "halo_values_per_step": 0, "foreign_sites_max": 0, "step_us_predicted": 0.0, "step_us_compute": 0.0,
           "efficiency_predicted": 1.0, "rank0_memory_ratio": 0.0, "memory_mib_rank0": 0.0,
           "memory_mib_median": 0.0}
    for shift in out["shifts"]:
        reach = setup.reach
        if reach.drift is not None:
            d = reach.drift
            reach = drift_reach(reach.link, Drift(shift, d.top, d.bottom, d.skin))
        bounds = slab_bounds(lat, ranks, shift)
        c = rank_counts(lat, bounds, reach, (0, shift), coef.overlap)
        m = step_model(c, coef)
        mem = per_rank_bytes(setup, ranks, gather, counts=c, bounds=bounds)
        med = float(np.median(mem))
        step, compute = float(m["step"].max()), float(m["compute"].max())
        out["peers_max"] = max(out["peers_max"], int(c.peers.max()))
        out["messages_per_step"] = max(out["messages_per_step"], int(c.messages.max()))
        out["halo_values_per_step"] = max(out["halo_values_per_step"], int(c.values.max()))
        out["foreign_sites_max"] = max(out["foreign_sites_max"], int(m["foreign"].max()))
        out["rank0_memory_ratio"] = max(out["rank0_memory_ratio"], float(mem[0]) / med)
        out["memory_mib_rank0"] = max(out["memory_mib_rank0"], float(mem[0]) / 2 ** 20)
        out["memory_mib_median"] = max(out["memory_mib_median"], med / 2 ** 20)
        if step >= out["step_us_predicted"]:
            out["step_us_predicted"], out["step_us_compute"] = step, compute
        out["efficiency_predicted"] = min(out["efficiency_predicted"], compute / step)
    out.update({"pack_ns_per_value": coef.pack_ns_per_value, "latency_us": coef.latency_us,
                "bandwidth_gbs": coef.bandwidth_gbs, "overlap": coef.overlap, "node_ns": coef.node_ns,
                "site_ns": coef.site_ns, "segment_ns": coef.segment_ns, "single_ns": coef.single_ns,
                "fixed_us": coef.fixed_us, "coefficients": coef.source})
    return out


# The design before the halos followed the slip, for the tables' "before" columns: halos fixed for the drive's
# whole travel (plus 2 a), and the exchange packing a segment per row (2.6 ns per value, studies.bench.pack at
# 754492d on this host; the fitted 26 ns of earlier pages held MPI's shared-memory copy as well).
BEFORE_PACK_NS = 2.6


def _before(setup):
    """``setup`` as the code before the halos followed the slip laid it out: halos for the whole travel."""
    from dataclasses import replace

    from ...parallel.layout import interface_reach
    travel = setup.drive.travel(setup.material.c_r, setup.t_unit) + 2.0
    big = setup.law.largest(setup.lattice.n_top_sites if setup.lattice.has_interface else 0)
    return replace(setup, reach=interface_reach(setup.law.rebond_length, big["delta_b"], travel),
                   scene={**setup.scene, "run.overlap": True})


def scaling_rows(setup, ranks_list, coef: Coefficients, gather: bool = False) -> list[dict]:
    """Strong scaling of one scene: each rank count's travel model now and as the code before laid it out
    (fixed halos for the whole travel, segment-per-row packing), with the step on one rank for the speed-up."""
    from dataclasses import replace as dc_replace
    one = travel_model(setup, 1, coef, gather)["step_us_predicted"]
    old = dc_replace(coef, pack_ns_per_value=BEFORE_PACK_NS)
    rows = []
    for p in ranks_list:
        if p > setup.lattice.ncols:
            continue
        now = travel_model(setup, p, coef, gather)
        before = travel_model(_before(setup), p, old, gather)
        rows.append({"ranks": p, "nodes": setup.lattice.n_nodes, "now": now, "before": before,
                     "speedup": one / now["step_us_predicted"],
                     "parallel_efficiency": one / (p * now["step_us_predicted"])})
    return rows


def rows_markdown(rows) -> str:
    """The strong-scaling rows as a table."""
    out = ["| ranks | peers (before) | halo values/step (before) | us/step predicted (before) | compute us/step | "
           "efficiency (before) | speed-up | T1/(P TP) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        n, b = r["now"], r["before"]
        out.append(f"| {r['ranks']} | {n['peers_max']} ({b['peers_max']}) | {n['halo_values_per_step']:,} "
                   f"({b['halo_values_per_step']:,}) | {n['step_us_predicted']:,.1f} ({b['step_us_predicted']:,.1f}) | "
                   f"{n['step_us_compute']:,.1f} | {n['efficiency_predicted']:.2f} ({b['efficiency_predicted']:.2f}) | "
                   f"{r['speedup']:,.0f} | {r['parallel_efficiency']:.2f} |")
    return "\n".join(out)


def steps_to(setup, t_lcr: float) -> int:
    """Steps of a run of ``setup`` up to drive time ``t_lcr`` (l/c_r), its ramp and settle included."""
    return setup.n_ramp + setup.n_settle + int(math.ceil(t_lcr * setup.t_unit / setup.dt))


# ----------------------------------------------------------------------------------------- measurement --
def _cpu_busy() -> float | None:
    """CPU seconds every process on the machine has used since boot (/proc/stat: user, nice, system,
    irq, softirq, steal); None where there is no /proc/stat."""
    try:
        with open("/proc/stat") as f:
            v = [int(x) for x in f.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    return (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / os.sysconf("SC_CLK_TCK")


def _children_cpu() -> float:
    """CPU seconds of this process's finished descendants (the MPI ranks of the cases run so far)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def machine_busy(probe: float = 1.0) -> float | None:
    """Share of the machine's cores busy over ``probe`` seconds (0: idle, 1: every core), None off Linux."""
    b0 = _cpu_busy()
    if b0 is None:
        return None
    time.sleep(probe)
    return (_cpu_busy() - b0) / (probe * (os.cpu_count() or 1))


def wait_quiet(limit: float = 0.1, timeout: float = 300.0, log=print) -> float | None:
    """Wait until at most ``limit`` of the cores are busy (others' work), or ``timeout`` s; returns the last share."""
    t0 = time.monotonic()
    busy = machine_busy()
    told = False
    while busy is not None and busy > limit and time.monotonic() - t0 < timeout:
        if not told:
            log(f"  machine {100 * busy:.0f} % busy; waiting for it to fall below {100 * limit:.0f} %")
            told = True
        time.sleep(2.0)
        busy = machine_busy()
    return busy


# The route the model charges each message by (``Coefficients.latency_us``: MPI's messages, what a peer on another
# node pays): its latency and the runs it is checked against take it, not a node's shared memory (``run.exchange``).
MESSAGES = ("--set", 'run.exchange="messages"')


def run_case(l: int, ranks: int, seconds: float, mode: str, timeout: float) -> dict | None:
    """``python -m parslip.studies.bench.case`` under mpiexec in a session of its own, its halos by MPI's messages
    (``MESSAGES``); None if it ran past ``timeout`` s.

    A case that runs too long (ranks spinning on an oversubscribed machine) is ended as a whole
    process group, so no rank is left behind spinning.
    """
    from ...parallel.launcher import python_command
    cmd = python_command("parslip.studies.bench.case", "--l", l, "--mode", mode, "--precision", "float64",
                         "--seconds", seconds, *MESSAGES, ranks=ranks)
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        return None
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{err[-2000:]}")
    return json.loads(out.strip().splitlines()[-1])


def timed_case(l: int, ranks: int, seconds: float, mode: str, timeout: float = 300.0) -> dict:
    """One ``bench.case`` run, with the share of the cores others used meanwhile (``others_cpu``, 0..1).

    others = (CPU the whole machine used - CPU of the case's processes) / (wall x cores), from
    /proc/stat and the rusage of this process's children; None off Linux.  A case past ``timeout``
    gives ``{"us_per_step": None, "timed_out": timeout}``.
    """
    b0, c0, t0 = _cpu_busy(), _children_cpu(), time.monotonic()
    res = run_case(l, ranks, seconds, mode, timeout)
    b1, c1, wall = _cpu_busy(), _children_cpu(), time.monotonic() - t0
    if res is None:
        res = {"us_per_step": None, "timed_out": timeout}
    res["others_cpu"] = None if b0 is None else max(0.0, ((b1 - b0) - (c1 - c0)) / (wall * (os.cpu_count() or 1)))
    return res


def measure(sizes, ranks, seconds: float = 3.0, repeats: int = 2, mode: str = "shear", quiet: float | None = 0.1,
            tries: int = 4, timeout: float = 300.0, path: str | None = None, log=print) -> list[dict]:
    """Run ``parslip.studies.bench.case`` for every size and rank count; each point keeps its fastest clean repeat.

    The fastest, not the mean: on a shared machine other processes only ever slow a run down.  With
    ``quiet`` (a share of the cores), each repeat waits until others use at most that much, and a
    repeat during which others used more than ``quiet`` is done again (up to ``tries`` times), so the
    points are of a machine to themselves as far as it can be had; every point records the others'
    share of its best repeat (``others_cpu``) and whether it stayed under ``quiet`` (``clean``).
    Each point: l, ranks, us_per_step (and every repeat's), the case's JSON, and the model's features.
    With ``path``, the points are written there after each one, and points already there are kept
    (a measurement stopped half-way continues).  A case past ``timeout`` s counts as a repeat with no
    time; a point whose repeats all timed out has ``us_per_step`` None.
    """
    from ...scene.derive import derive
    from .case import scene_at
    out = []
    if path and os.path.exists(path):
        with open(path) as f:
            out = json.load(f)
        if not isinstance(out, list) or not all(isinstance(p, dict) and "ranks" in p for p in out):
            raise ValueError(f"{path}: not a file of scaling points (a list of measured points); "
                             f"accepted: a new path, or one an earlier measurement wrote")
    done = {(p["l"], p["ranks"]) for p in out}
    for l in sizes:
        st = derive(scene_at(l, mode, "float64"))
        for r in ranks:
            if (l, r) in done:
                continue
            feats = features(rank_shares(st, r))
            runs = []
            for _ in range(repeats):
                for _ in range(tries if quiet is not None else 1):
                    if quiet is not None:
                        wait_quiet(quiet, log=log)
                    c = timed_case(l, r, seconds, mode, timeout)
                    c["clean"] = quiet is None or c["others_cpu"] is None or c["others_cpu"] <= quiet
                    runs.append(c)
                    if c["clean"] or c["us_per_step"] is None:
                        # A case ended at its timeout is not tried again: its ranks, killed before their
                        # launcher waited for them, count as others' CPU, so "busy" says nothing there.
                        break
            timed = [c for c in runs if c["us_per_step"] is not None]
            clean = [c for c in timed if c["clean"]] or timed
            best = min(clean, key=lambda c: c["us_per_step"]) if clean else runs[-1]
            each = ", ".join(("timed out" if c["us_per_step"] is None else f"{c['us_per_step']:.1f}")
                             + ("" if c["clean"] else " (busy)") for c in runs)
            log(f"l = {l}, {r} rank(s): best {best['us_per_step']} us/step (repeats {each})")
            out.append({"l": l, "ranks": r, "us_per_step": best["us_per_step"], "clean": best["clean"],
                        "others_cpu": best["others_cpu"],
                        "repeats_us_per_step": [c["us_per_step"] for c in runs], "features": feats, "case": best})
            if path:
                with open(path, "w") as f:
                    json.dump(out, f, indent=1)
    return out


# ---------------------------------------------------------------------------------------------- tables --
def layout_table(shares: list[RankShare]) -> str:
    """One line per rank: columns, nodes, sites, peers, farthest hop, halo widths, halo values per step."""
    rows = ["rank  columns      nodes  sites  peers                     hops  halo top  halo bottom  bulk  "
            "values/step (sent+recv)"]
    for s in shares:
        peers = ",".join(str(p) for p in s.peers)
        rows.append(f"{s.rank:4d}  [{s.cols[0]:4d},{s.cols[1]:4d})  {s.nodes:6d}  {s.sites:5d}  {peers:24s}  "
                    f"{s.hops:4d}  {s.halo_top[0]:3d}+{s.halo_top[1]:<3d}   {s.halo_bottom[0]:3d}+"
                    f"{s.halo_bottom[1]:<3d}      {s.halo_bulk:4d}  {s.values_sent}+{s.values_received}")
    return "\n".join(rows)


def fit_table(f: Fit) -> str:
    """Coefficients with standard errors, then every point: measured, model, relative residual."""
    lines = [f"t_step = {' + '.join(f'{TERMS[t]} {t}' if t != '1' else 'c' for t in f.terms)}   (us; "
             f"rms relative residual {100 * f.rms_rel:.1f} %)"]
    for name in f.coef:
        lines.append(f"  {name} = {f.coef[name]:.5g} +- {f.stderr[name]:.2g} {UNITS[name]}")
    lines.append("| l | ranks | N (max/rank) | S | H | measured us/step | model us/step | residual |")
    lines.append("|---|---|---|---|---|---|---|---|")
    for p in f.points:
        m = f.predict(p["features"])
        ft = p["features"]
        lines.append(f"| {p['l']} | {p['ranks']} | {ft['N']:,} | {ft['S']} | {ft['H']} | {p['us_per_step']:.1f} | "
                     f"{m:.1f} | {100 * (m / p['us_per_step'] - 1):+.1f} % |")
    return "\n".join(lines)


def _points_table(f: Fit, points: list[dict]) -> str:
    lines = ["| l | ranks | N (max/rank) | H | measured us/step | model us/step | measured / model |", "|---|---|---|---|---|---|---|"]
    for p in points:
        m = f.predict(p["features"])
        lines.append(f"| {p['l']} | {p['ranks']} | {p['features']['N']:,} | {p['features']['H']} | "
                     f"{p['us_per_step']:.1f} | {m:.1f} | {p['us_per_step'] / m:.2f} |")
    return "\n".join(lines)


def _scene_setup(spec: str, mode: str):
    """'2000' (the paper's geometry scaled to l = 2000, ``bench.case.scene_at``) or a scene file."""
    from ...scene.derive import derive
    if spec.isdigit():
        from .case import scene_at
        return derive(scene_at(int(spec), mode, "float64"))
    from ...scene.load import load
    return derive(load(spec, []))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m parslip.studies.bench.scaling", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    lay = sub.add_parser("layout", help="per-rank table of a scene's decomposition")
    lay.add_argument("scene", help="scene file, or a contact length l for the paper's geometry scaled")
    lay.add_argument("--ranks", type=int, required=True)
    lay.add_argument("--mode", default="shear", help="drive mode when SCENE is a contact length")
    me = sub.add_parser("measure", help="run parslip.studies.bench.case at several sizes and rank counts")
    me.add_argument("--sizes", type=int, nargs="+", default=[100, 200, 300, 500, 700, 1000])
    me.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 3])
    me.add_argument("--seconds", type=float, default=3.0)
    me.add_argument("--repeats", type=int, default=2)
    me.add_argument("--json", default="scaling.json",
                    help="where the points go, one by one; points already there are kept (default scaling.json)")
    me.add_argument("--timeout", type=float, default=300.0, help="seconds after which a case is ended (default 300)")
    me.add_argument("--quiet", type=float, default=0.1,
                    help="wait for others to use at most this share of the cores, and redo a repeat during which "
                         "they used more (default 0.1; 0 or less: measure whatever the load)")
    ta = sub.add_parser("tables", help="strong and weak scaling of the travel model, now and before, as markdown")
    ta.add_argument("scene", help="scene file (the contact lengths are set by --l)")
    ta.add_argument("--l", type=int, nargs="+", default=[10_000, 100_000])
    ta.add_argument("--ranks", type=int, nargs="+", default=[1, 4, 16, 64, 256, 1024, 4096])
    ta.add_argument("--weak", default="10000:256", metavar="L:RANKS",
                    help="weak scaling at the per-rank share of l = L on RANKS ranks (default 10000:256)")
    fi = sub.add_parser("fit", help="fit the model to measured points and predict")
    fi.add_argument("json")
    fi.add_argument("--terms", default="N,H,1", help="comma-separated features of the model (N, S, H, M, 1)")
    fi.add_argument("--exclude-ranks", type=int, nargs="*", default=[3],
                    help="rank counts kept out of the fit (default 3: oversubscribes this 2-core machine)")
    fi.add_argument("--predict", nargs="*", default=["2000:64"], metavar="L:RANKS")
    fi.add_argument("--mode", default="shear")
    fi.add_argument("--latency-us", type=float, default=2.0)
    fi.add_argument("--bandwidth-gbs", type=float, default=10.0)
    fi.add_argument("--throughput-ratio", type=float, default=1.0)
    a = p.parse_args(argv)
    if a.cmd == "layout":
        shares = rank_shares(_scene_setup(a.scene, a.mode), a.ranks)
        print(layout_table(shares))
        f = features(shares)
        print(f"busiest rank: N = {f['N']}, S = {f['S']}, H = {f['H']} values/step, M = {f['M']} messages/step; "
              f"farthest peer {max(s.hops for s in shares)} slabs away")
        return 0
    if a.cmd == "tables":
        weak_l, weak_p = (int(v) for v in a.weak.split(":"))
        return _tables(a.scene, a.l, a.ranks, (weak_l, weak_p))
    if a.cmd == "measure":
        measure(a.sizes, a.ranks, a.seconds, a.repeats, quiet=a.quiet if a.quiet > 0 else None, timeout=a.timeout,
                path=a.json, log=lambda m: print(m, file=sys.stderr, flush=True))
        print(f"wrote {a.json}")
        return 0
    with open(a.json) as fh:
        pts = json.load(fh)
    return report(pts, tuple(a.terms.split(",")), a.exclude_ranks, a.predict, a.mode,
                  Cluster(a.throughput_ratio, a.latency_us, a.bandwidth_gbs))


def _tables(scene: str, lengths, ranks, weak, out=print) -> int:
    """Strong scaling at each contact length l (the scene's aspect ratio kept: substrate 3 l wide), and weak
    scaling at the per-rank share of ``weak`` = (l, ranks): l grows with the rank count."""
    from ...scene.derive import derive
    from ...scene.load import load
    coef = coefficients()
    out(f"coefficients: {coef}")
    for l in lengths:
        st = derive(load(scene, [f"lattice.top_cols={l}", f"lattice.bottom_cols={3 * l}"]))
        out(f"\n### Strong scaling, l = {l:,} ({st.lattice.n_nodes:,} nodes), {scene}\n")
        out(rows_markdown(scaling_rows(st, ranks, coef)))
    base_l, base_p = weak
    out(f"\n### Weak scaling: l = {base_l:,} x P / {base_p:,} (the same nodes per rank), {scene}\n")
    rows = []
    for p in ranks:
        l = max(int(round(base_l * p / base_p)), 100)
        st = derive(load(scene, [f"lattice.top_cols={l}", f"lattice.bottom_cols={3 * l}"]))
        r = scaling_rows(st, [p], coef)
        if r:
            r[0]["ranks"] = f"{p} (l = {l:,})"
            rows += r
    out(rows_markdown(rows))
    return 0


def report(pts, terms, exclude, targets, mode, cluster: Cluster, out=print) -> int:
    """Fit, the held-out points against the model, and the predictions, as text."""
    timed = [q for q in pts if q["us_per_step"] is not None]
    used = [q for q in timed if q["ranks"] not in exclude]
    held = [q for q in timed if q["ranks"] in exclude]
    f = fit(used, terms)
    out(fit_table(f))
    if held:
        out("\nheld out of the fit:")
        out(_points_table(f, held))
    for spec in targets:
        l, r = spec.split(":")
        st = _scene_setup(l, mode)
        shares = rank_shares(st, int(r))
        pr = predict(f, shares, cluster)
        steps = steps_to(st, 100.0)
        out(f"\nl = {l} on {r} ranks ({mode}; {st.lattice.n_nodes:,} nodes): N = {pr['features']['N']:,}, "
            f"H = {pr['features']['H']}, M = {pr['features']['M']} per step on the busiest rank")
        out(f"  compute {pr['compute_us']:.1f} us + packing {pr['pack_us']:.1f} us + network "
            f"{pr['network_us']:.1f} us ({pr['exposed_network_us']:.1f} exposed) = {pr['us_per_step']:.1f} us/step")
        out(f"  to 100 l/c_r: {steps:,} steps (ramp and settle included) = {steps * pr['us_per_step'] / 1e6:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
