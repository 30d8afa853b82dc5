"""`parslip bench --sweep`: the throughput of a sweep of small scenes, on 1 rank and on 2.

Responsible for the number the sweep runner is held to: an 8-point sweep on
2 ranks, one point per rank, should take at most 0.55 x the time of the same
sweep on 1 rank, with a warm numba cache.  It prints numbers; it asserts
nothing (a shared machine's load would make a timed test flaky).

What is timed: the whole command, as a user runs it, from a fresh process to
its exit (Python start, imports, numba's cached kernels, MPI start-up for 2
ranks, every point, the summary): ``python -m parslip sweep`` on 1 rank and
``mpiexec -n 2 python -m parslip sweep`` on 2, each into a fresh directory.
The points are the paper's push scene (l = 100 a, 7,000 nodes) at F_N spread
over 0.6-1.3 (equal cost: the same steps and nodes), snapshots off, driven for
``duration`` l/c_r (100 by default, as in run/studies/friction_loading.toml).
Each process pays about 2 s that no rank count shares out (Python, imports,
numba's cached kernels, the summary), so the ratio reaches 0.5 only for long
points: with 8 points of T s each it is about (2 + 4 T) / (2 + 8 T).  A
one-point sweep first warms the cache.  Each repeat runs both, alternating
which goes first; medians are reported with every
repeat, the CPU time the commands used (a 2-rank run that got both cores uses
about twice its wall time), and the machine's load average before each run.

    parslip bench --sweep                 # 8 points, 3 repeats
    python -m parslip.studies.bench.sweep_throughput --points 8 --repeat 5 --json sweep_throughput.json
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

TARGET = 0.55


def _root() -> str:
    return os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _sweep_file(d: str, scene: str, n: int, duration: float) -> str:
    fns = [round(0.6 + 0.7 * i / max(n - 1, 1), 4) for i in range(n)]
    path = os.path.join(d, f"bench{n}.toml")
    with open(path, "w") as f:
        f.write(f'base = "{os.path.abspath(scene)}"\n[set]\n"drive.duration" = {duration}\n'
                f'"output.snapshots" = 0\n[grid]\n"load.FN" = {json.dumps(fns)}\n')
    return path


def _timed(cmd, cwd, env) -> dict:
    load = os.getloadavg()[0]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    p = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.monotonic() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load_before": load}


def _point_walls(outdir: str) -> list[float]:
    import csv
    with open(os.path.join(outdir, "summary.csv"), newline="") as fh:
        return [float(r["wall_s"]) for r in csv.DictReader(fh)]


def measure(points: int = 8, repeat: int = 3, scene: str | None = None, duration: float = 100.0,
            log=None) -> dict:
    """Time the sweep on 1 and 2 ranks ``repeat`` times each; returns every measurement and the medians."""
    from ...parallel.launcher import python_command
    log = log or (lambda m: print(m, file=sys.stderr, flush=True))
    scene = scene or os.path.join(_root(), "run", "push.toml")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([_root()] + [p for p in [env.get("PYTHONPATH")] if p])
    runs = {1: [], 2: []}
    with tempfile.TemporaryDirectory(prefix="parslip-sweep-bench-") as d:
        warm = _sweep_file(d, scene, 1, 1.0)
        log("warming the numba cache (a one-point sweep)")
        _timed(python_command("parslip", "sweep", warm, "-o", os.path.join(d, "warm"), "--quiet"), d, env)
        sweep = _sweep_file(d, scene, points, duration)
        for k in range(repeat):
            for ranks in ((1, 2) if k % 2 == 0 else (2, 1)):
                out = os.path.join(d, f"r{ranks}_{k}")
                cmd = python_command("parslip", "sweep", sweep, "-o", out, "--quiet",
                                     ranks=ranks if ranks > 1 else None)
                m = _timed(cmd, d, env)
                m["point_wall_s"] = _point_walls(out)
                runs[ranks].append(m)
                log(f"repeat {k + 1}/{repeat}, {ranks} rank(s): {m['wall_s']:.2f} s wall, {m['cpu_s']:.2f} s CPU, "
                    f"load {m['load_before']:.2f} before; points {min(m['point_wall_s']):.2f}-"
                    f"{max(m['point_wall_s']):.2f} s")
    med = {r: statistics.median(m["wall_s"] for m in runs[r]) for r in runs}
    ratios = [b["wall_s"] / a["wall_s"] for a, b in zip(runs[1], runs[2])]
    return {"points": points, "repeat": repeat, "scene": scene, "duration_lcr": duration, "runs": runs,
            "median_wall_s": med, "ratio_of_medians": med[2] / med[1], "ratio_per_repeat": ratios,
            "median_ratio": statistics.median(ratios), "target": TARGET, "cpus": os.cpu_count()}


def report(res: dict) -> str:
    lines = [f"sweep of {res['points']} points ({os.path.basename(res['scene'])}, drive {res['duration_lcr']:g} l/c_r, "
             f"snapshots off), {res['repeat']} repeats, warm numba cache, {res['cpus']} CPUs",
             f"{'ranks':>5} {'median wall s':>14} {'walls s':>28} {'CPU s (median)':>15} {'load before':>18}"]
    for r in (1, 2):
        ms = res["runs"][r]
        walls = " ".join("%.2f" % m["wall_s"] for m in ms)
        loads = " ".join("%.2f" % m["load_before"] for m in ms)
        cpu = statistics.median(m["cpu_s"] for m in ms)
        lines.append(f"{r:>5} {res['median_wall_s'][r]:14.2f} {walls:>28} {cpu:15.2f} {loads:>18}")
    ok = res["ratio_of_medians"] <= res["target"]
    lines.append(f"2 ranks / 1 rank: {res['ratio_of_medians']:.3f} (ratio of the medians; per repeat "
                 f"{', '.join(f'{x:.3f}' for x in res['ratio_per_repeat'])}); target <= {res['target']}: "
                 f"{'met' if ok else 'missed'}")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m parslip.studies.bench.sweep_throughput", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", type=int, default=8)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--duration", type=float, default=100.0,
                    help="drive time of each point, l/c_r (default 100: the loading study's points)")
    ap.add_argument("--scene", help="base scene (default run/push.toml)")
    ap.add_argument("--json", help="also write every measurement here")
    a = ap.parse_args(argv)
    res = measure(a.points, a.repeat, a.scene, a.duration)
    print(report(res))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
