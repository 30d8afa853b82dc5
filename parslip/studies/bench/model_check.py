"""The travel model's coefficients measured on this host, and the model checked against the steps it times.

`parslip bench --scaling` times ``bench.case`` at several contact lengths on 1, 2 and 3 ranks
(``scaling.measure``).  From those points and two micro-benchmarks this module takes the coefficients the
travel model charges (``scaling.Coefficients``):

    segment_ns         ``bench.rows``: what a row segment costs beyond its nodes
    single_ns          ``bench.rows``: a node updated on its own (block edges)
    node_ns            the 1-rank step time less the fixed, site, segment and single-node shares, over the
                       nodes: the median over the contact lengths measured (in cache at l = 300-500, out of
                       it at l = 1000)
    pack_ns_per_value  ``bench.pack.measure``: packing and unpacking one halo value, no MPI
    latency_us         ``bench.pack.exchange`` on 2 ranks: the exchange of a step less its packing, per
                       pair of messages (a message sent and one received)

and sets each measured point beside the model's step for the same decomposition (``scaling.step_model``
on the case's counts, no drift: a case runs seconds).  A rank count above the cores shares them: a core
then runs ceil(ranks / cores) ranks one after the other, and the prediction is multiplied by that.  The coefficients are kept for `parslip info`
(``io.cache.store_coefficients``).
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import time

import numpy as np

from .scaling import Coefficients, coefficients, step_model


def _case_setup(l: int, mode: str):
    from ...scene.derive import derive
    from .case import scene_at
    return derive(scene_at(l, mode, "float64"))


def _counts(setup, ranks: int):
    from ...parallel.counts import rank_counts
    from ...parallel.layout import slab_bounds
    lat = setup.lattice
    return rank_counts(lat, slab_bounds(lat, ranks), setup.reach, (0, 0), setup.overlap)


def _node_ns(q, rows: dict, base: Coefficients, mode: str) -> float:
    """A 1-rank point's ns per node update once the step's other shares (fixed, sites, rows) are taken out."""
    c = _counts(_case_setup(q["l"], mode), 1)
    rest = (base.fixed_us * 1e3 + base.site_ns * float(c.sites[0]) + rows["segment_ns"] * float(c.segments[0])
            + rows["single_ns"] * float(c.singles[0]))
    return (q["us_per_step"] * 1e3 - rest) / float(c.nodes[0])


def exchange_latency(l: int, mode: str = "shear", seconds: float = 1.0, timeout: float = 300.0) -> dict | None:
    """``bench.pack --exchange`` on 2 ranks at contact length ``l``, by MPI's messages (``scaling.MESSAGES``):
    rank 0's figures (us per exchange, its packing, us per message), or None if it did not finish."""
    from ...parallel.launcher import python_command
    from .scaling import MESSAGES
    cmd = python_command("parslip.studies.bench.pack", str(l), "--mode", mode, "--exchange", "--seconds", seconds,
                         *MESSAGES, ranks=2)
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    if p.returncode != 0:
        return None
    return json.loads(p.stdout.strip().splitlines()[-1])["ranks"][0]


def measured(pts, mode: str = "shear", log=print) -> Coefficients:
    """The coefficients of this host (module docstring) from the 1-rank points ``pts`` and the
    micro-benchmarks; what could not be measured keeps its value from ``scaling.coefficients``."""
    from .pack import measure as pack_measure
    from .rows import measure as rows_measure
    base = coefficients()
    one = [q for q in pts if q["ranks"] == 1 and q["us_per_step"]]
    if not one:
        return base
    big = max(one, key=lambda q: q["l"])
    st = _case_setup(big["l"], mode)
    rows = rows_measure()
    node_ns = float(np.median([_node_ns(q, rows, base, mode) for q in one]))
    pack = pack_measure(st, 2, 0, 0.5)["ns_per_value"]
    ex = exchange_latency(big["l"], mode)
    latency = base.latency_us if ex is None else max(2.0 * ex["us_per_message"], 0.0)
    src = f"parslip bench --scaling, {time.strftime('%Y-%m-%d')}, l = {', '.join(str(q['l']) for q in one)}"
    log(f"coefficients: node {node_ns:.3f} ns, row segment {rows['segment_ns']:.1f} ns, single node "
        f"{rows['single_ns']:.1f} ns, packing {pack:.2f} ns per value, latency {latency:.2f} us "
        f"({'measured' if ex else 'assumed'})")
    return Coefficients(node_ns=node_ns, site_ns=base.site_ns, segment_ns=rows["segment_ns"],
                        single_ns=rows["single_ns"], fixed_us=base.fixed_us, pack_ns_per_value=pack,
                        latency_us=latency, bandwidth_gbs=base.bandwidth_gbs, source=src)


def check(pts, coef: Coefficients, mode: str = "shear", cores: int | None = None) -> list[dict]:
    """Each timed point beside the travel model's step for its decomposition: l, ranks, measured and
    predicted us per step, their ratio (ranks above ``cores`` share them: prediction x ceil(ranks / cores))."""
    cores = cores or os.cpu_count() or 1
    rows = []
    for q in pts:
        if not q["us_per_step"]:
            continue
        st = _case_setup(q["l"], mode)
        step = float(step_model(_counts(st, q["ranks"]), coef)["step"].max())
        step *= math.ceil(q["ranks"] / cores)
        rows.append({"l": q["l"], "ranks": q["ranks"], "measured_us": q["us_per_step"], "predicted_us": step,
                     "ratio": step / q["us_per_step"]})
    return rows


def table(rows) -> str:
    """The check as a markdown table, and the largest deviation."""
    lines = ["| l | ranks | measured us/step | predicted | predicted / measured |", "| --- | --- | --- | --- | --- |"]
    lines += [f"| {r['l']} | {r['ranks']} | {r['measured_us']:.1f} | {r['predicted_us']:.1f} | {r['ratio']:.2f} |"
              for r in rows]
    if rows:
        worst = max(rows, key=lambda r: abs(np.log(r["ratio"])))
        lines.append(f"\nlargest deviation: {100 * (worst['ratio'] - 1):+.0f} % (l = {worst['l']}, "
                     f"{worst['ranks']} ranks)")
    return "\n".join(lines)
