"""`parslip bench`: the benchmark suite, as a table on screen and JSON on disk.

    parslip bench                      # l = 100, 500, 1000; 1 and 2 ranks; float64 and float32
    parslip bench --quick              # l = 100 and 500, fewer seconds per case
    parslip bench --json bench.json --sizes 500 --ranks 1 2

What it measures (all on this machine, nothing asserted):

- node-updates/s of the time loop: nodes x steps / wall seconds, on the whole
  run path (``case``: interface bonds, damping, the driven face, interface
  frames written), for each size, rank count and float type;
- per step, the time of each phase (interface bonds, stencil, the halo
  exchange's post and complete) and the exchange cost;
- start-up: imports, deriving the scene (omega_max), building the state, the
  first compiled call (numba's cache loaded, or the code compiled);
- time per interface frame written;
- memory: the peak resident size per rank, and ``parslip info``'s prediction
  for the same scene (``scene.memory``), with the ratio;
- the roofline: the machine's memory bandwidth (a STREAM-like triad, one
  process and one per core) and each result's bytes moved per second as a
  fraction of it, with BYTES_PER_UPDATE bytes per node update;
- the baseline: a vectorised NumPy step of the same model (``numpy_step``),
  and each result's speed-up over it;
- time to result: the whole `parslip run run/push.toml` process, 1 and 2 ranks.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time

from ...parallel.launcher import python_command

# Bytes a node update moves to and from memory beyond the caches: u(t) read, u(t-dt) read and u(t+dt)
# written in its place, x and y each (neighbours come from cache): 6 values.
BYTES_PER_VALUE = {"float64": 8, "float32": 4}
VALUES_PER_UPDATE = 6


def _run_json(cmd: list[str], timeout: float = 900) -> dict:
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{p.stderr[-2000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def stream(ranks: int) -> float:
    """Aggregate triad bandwidth (GB/s) of ``ranks`` processes running at once."""
    procs = [subprocess.Popen([sys.executable, "-m", "parslip.studies.bench.stream"], stdout=subprocess.PIPE, text=True)
             for _ in range(ranks)]
    return sum(json.loads(p.communicate()[0].strip().splitlines()[-1])["triad_gbs"] for p in procs)


def case(l: int, ranks: int, precision: str, seconds: float, mode: str = "shear") -> dict:
    return _run_json(python_command("parslip.studies.bench.case", "--l", l, "--mode", mode, "--precision", precision,
                                    "--seconds", seconds, ranks=ranks))


def baseline(l: int, steps: int) -> float:
    """Node-updates/s of the vectorised NumPy step at contact length l (one process)."""
    code = ("import json; from parslip.studies.bench.case import scene_at; from parslip.scene.derive import derive; "
            "from parslip.studies.bench.numpy_step import node_updates_per_s; "
            f"print(json.dumps({{'ups': node_updates_per_s(derive(scene_at({l}, 'shear', 'float64')), {steps})}}))")
    return _run_json([sys.executable, "-c", code])["ups"]


def time_to_result(scene: str, ranks: int, repeats: int = 3) -> float:
    """Median wall time (s) of the whole `parslip run SCENE` process on ``ranks`` ranks (one warm-up run)."""
    import tempfile
    walls = []
    with tempfile.TemporaryDirectory() as d:
        for i in range(repeats + 1):
            cmd = python_command("parslip", "run", scene, "--out", os.path.join(d, "r.vtkhdf"), "--overwrite",
                                 "--quiet", ranks=ranks)
            t = time.perf_counter()
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
            if p.returncode != 0:
                raise RuntimeError(p.stderr[-2000:])
            if i:
                walls.append(time.perf_counter() - t)
    return sorted(walls)[len(walls) // 2]


def predicted_bytes(l: int, ranks: int, precision: str) -> int:
    from ...scene.memory import predict
    from ...scene.derive import derive
    from .case import scene_at
    return max(predict(derive(scene_at(l, "shear", precision)), ranks)["per_rank"])


def run(sizes=(100, 500, 1000), ranks=(1, 2), precisions=("float64", "float32"), seconds: float = 4.0,
        push: str | None = "run/push.toml", log=print) -> dict:
    """Every measurement of the module docstring; returns them as one dict (the JSON)."""
    res = {"machine": {"cpus": os.cpu_count(), "python": sys.version.split()[0]}, "cases": [], "baseline": {},
           "time_to_result": {}}
    log("memory bandwidth (STREAM-like triad)...")
    res["stream_gbs"] = {str(r): stream(r) for r in sorted(set(ranks))}
    for l in sizes:
        if l <= 500:
            log(f"vectorised NumPy baseline, l = {l}...")
            res["baseline"][str(l)] = baseline(l, steps=max(5, int(2e6 / (l * l * 7))))
    for l in sizes:
        for p in precisions:
            for r in ranks:
                log(f"case l = {l}, {r} rank(s), {p}...")
                c = case(l, r, p, seconds)
                bw = res["stream_gbs"][str(r)] * 1e9
                moved = c["node_updates_per_s"] * VALUES_PER_UPDATE * BYTES_PER_VALUE[p]
                c["roofline_fraction"] = moved / bw
                base = res["baseline"].get(str(l))
                c["speedup_over_numpy"] = c["node_updates_per_s"] / base if base else None
                c["predicted_peak_bytes"] = predicted_bytes(l, r, p)
                c["prediction_ratio"] = c["predicted_peak_bytes"] / max(c["peak_rss_bytes"])
                res["cases"].append(c)
    if push and os.path.exists(push):
        for r in ranks:
            log(f"time to result: parslip run {push} on {r} rank(s)...")
            res["time_to_result"][str(r)] = time_to_result(push, r)
    return res


def table(res: dict) -> str:
    """The results as a Markdown table."""
    rows = ["| l | ranks | float | nodes | µs/step | M node-updates/s | per rank | vs NumPy | roofline | exchange µs/step "
            "| frame µs | start-up s (imports/derive/first call) | peak MiB/rank | info predicted |",
            "|" + "---|" * 14]
    for c in res["cases"]:
        s = c["startup_s"]
        vs = f"{c['speedup_over_numpy']:.0f}x" if c["speedup_over_numpy"] else ""
        rows.append(
            f"| {c['l']} | {c['ranks']} | {c['precision']} | {c['nodes']:,} | {c['us_per_step']:.1f} | "
            f"{c['node_updates_per_s'] / 1e6:.0f} | {c['node_updates_per_s'] / 1e6 / c['ranks']:.0f} | {vs} | "
            f"{c['roofline_fraction']:.2f} | {c['exchange_us_per_step']:.2f} | {c['frame_write_us']:.0f} | "
            f"{s['imports']:.2f}/{s['derive']:.2f}/{s['first_call']:.2f} | {max(c['peak_rss_bytes']) / 2**20:.0f} | "
            f"{c['prediction_ratio']:.2f}x |")
    out = "\n".join(rows)
    out += "\n\nmemory bandwidth (triad): " + ", ".join(f"{r} process(es) {v:.1f} GB/s" for r, v in
                                                        res["stream_gbs"].items())
    if res["baseline"]:
        out += "\nvectorised NumPy step: " + ", ".join(f"l = {l}: {v / 1e6:.1f} M node-updates/s" for l, v in
                                                     res["baseline"].items())
    if res["time_to_result"]:
        out += "\nwhole `parslip run run/push.toml` process (median of 3, warm caches): " + ", ".join(
            f"{r} rank(s) {v:.2f} s" for r, v in res["time_to_result"].items())
    return out
