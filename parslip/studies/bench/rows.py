"""What a row of the schedule costs beyond its nodes: the fixed cost of a vectorised row segment and the cost
of a node updated on its own, timed in the compiled loop's own kernels (``engine.loop._rows``, ``_nodes``).

    python -m parslip.studies.bench.rows            # one JSON line: segment_ns, single_ns, node_ns_hot

Every step the loop runs each block's interior rows over the same columns as one task (``kernels.rect``:
one vectorised loop per row), its other rows as a task each, and its block-edge columns (and pieces of at
most ``layout.SHORT`` columns) node by node, a column of consecutive rows one task
(``parallel.layout._tasks``).  A row segment of n nodes costs about segment_ns + n node_ns_hot: segment_ns
(the row's views, the vector loop's ends, its share of the task) is the intercept of the time per row of a
task of 16 interior rows against n over n = 8-256, node_ns_hot the slope (in cache).  single_ns is the time
per node of a column of 16 nodes updated one by one.  The travel model charges both per row segment and per
node (``scaling.step_model``; ``parallel.counts`` counts them): on a slab of many rows and few columns they
are most of a step.  On the l = 100 scene of ``bench.case`` (no MPI: one rank's state), medians of repeats.
"""
from __future__ import annotations

import json
import sys
import time

import numpy as np
from numba import njit

from ...engine import loop as L
from ...parallel.codes import FULL, MASKED


@njit(cache=True)
def _segments(reps, tasks, lv, K, prm, iface, drive, bud):
    for _ in range(reps):
        L._rows(0, tasks.shape[0], tasks, lv.bx0, lv.by0, lv.bx0, lv.by0, lv.bx1, lv.by1, K, prm, iface.exb_x,
                iface.exb_y, iface.zeros, drive, 0, 0.0, 0.0, bud, False)


@njit(cache=True)
def _singles(reps, tasks, lv, K, prm, iface, drive, bud):
    for _ in range(reps):
        L._nodes(0, tasks.shape[0], tasks, lv.bx0, lv.by0, lv.bx0, lv.by0, lv.bx1, lv.by1, K, prm, iface.exb_x,
                 iface.exb_y, drive, 0, 0.0, 0.0, bud, False)


def _ns_per_row(kernel, sim, tasks, repeats: int = 5, reps: int = 20000) -> float:
    """Time per row (ns) of one pass over ``tasks`` (medians of ``repeats``)."""
    s = sim.state
    args = (tasks, s.levels, s.K, sim.params, s.iface, s.drive, sim.budget)
    kernel(10, *args)                     # compile or load, warm the caches
    best = []
    for _ in range(repeats):
        t = time.perf_counter()
        kernel(reps, *args)
        best.append((time.perf_counter() - t) / reps * 1e9 / int(tasks["rows"].sum()))
    return float(np.median(best))


def measure() -> dict:
    """segment_ns, single_ns and node_ns_hot on this core (module docstring)."""
    from ...engine.simulation import Simulation
    from ...scene.derive import derive
    from .case import scene_at
    sim = Simulation(derive(scene_at(100, "shear", "float64")), None)
    sched = sim.sched.tasks
    bottom = sched[sched["block"] == 0]
    full = bottom[bottom["kind"] == FULL][:1].copy()
    one = bottom[bottom["kind"] == MASKED][:1].copy()
    # 16 interior rows of the substrate (each its own memory) as one task, as the schedule runs them.
    for tk in (full, one):
        assert tk["row"][0] == 2 and tk["rows"][0] >= 16
        tk["rows"] = 16
    sizes = np.array([8, 16, 32, 64, 128, 256])
    per = []
    for n in sizes:
        full["n"] = n
        per.append(_ns_per_row(_segments, sim, full))
    slope, intercept = np.polyfit(sizes.astype(float), np.array(per), 1)
    return {"segment_ns": float(intercept), "node_ns_hot": float(slope), "single_ns": _ns_per_row(_singles, sim, one),
            "segment_sizes": sizes.tolist(), "segment_ns_each": per}


def main() -> int:
    print(json.dumps(measure()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
