"""Helpers of slurm/scaling.sbatch: the weak-scaling scene, the rank limit, one table row.

Responsible for the numbers of a scaling study; the batch script does the runs.

    python slurm/scaling.py weak-sets SCENE R [--set KEY=VALUE ...]   # --set options, one token a line
    python slurm/scaling.py max-ranks SCENE [--set KEY=VALUE ...]     # largest rank count the scene splits into
    python slurm/scaling.py header
    python slurm/scaling.py row STUDY LOG OUT                         # one row of the table (LOG: for errors)

Weak scaling keeps the lattice nodes per rank fixed: R ranks run the scene
with R times its columns (top and substrate), so R times the contact length
l.  Scene times are in l/c_r, so ramp, settle and drive are divided by R to
keep the number of steps, and so the run time per rank, about the same.

A row: the study, ranks, lattice nodes in all and per rank, steps, the wall
time of the time loop (the output file's timing_loop_s, read through the
output contract), and node-updates per second = nodes x steps / that time;
counts come from the output file's root attributes n_nodes, n_steps, n_ranks.
"""
from __future__ import annotations

import sys

COLUMNS = ("study", "ranks", "lattice_nodes", "nodes_per_rank", "steps", "loop_wall_s", "node_updates_per_s")


def _scene(path, sets):
    from parslip.scene.load import load
    return load(path, [s.split("=", 1)[1] if s.startswith("--set=") else s for s in sets if s != "--set"])


def weak_sets(path: str, ranks: int, sets: list[str]) -> list[str]:
    sc = _scene(path, sets)
    out = []
    for key in ("lattice.top_cols", "lattice.bottom_cols"):
        out += ["--set", f"{key}={sc[key] * ranks}"]
    for key in ("load.ramp", "load.settle", "drive.duration"):
        out += ["--set", f"{key}={sc[key] / ranks!r}"]
    return out


def max_ranks(path: str, sets: list[str]) -> int:
    from parslip.scene.derive import derive
    return derive(_scene(path, sets)).max_ranks()


def row(study: str, log: str, out: str) -> str:
    from parslip.io import contract
    try:
        a = contract.read_attrs(out)
    except OSError:
        raise SystemExit(f"scaling.py: {out}: no output file; the run did not finish (see {log})") from None
    timings = contract.read_timings(out)
    if a.get("status") != "complete" or "loop_s" not in timings:
        raise SystemExit(f"scaling.py: {out}: status {a.get('status')!r}, no loop time; the run did not finish "
                         f"(see {log})")
    nodes, steps, ranks = int(a["n_nodes"]), int(a["n_steps"]), int(a["n_ranks"])
    wall = float(timings["loop_s"])
    ups = nodes * steps / wall if wall > 0 else float("nan")
    return "\t".join(str(v) for v in (study, ranks, nodes, f"{nodes / ranks:.0f}", steps, f"{wall:.1f}", f"{ups:.4g}"))


def main(argv: list[str]) -> int:
    if not argv:
        print(__doc__, file=sys.stderr)
        return 2
    cmd, rest = argv[0], argv[1:]
    if cmd == "weak-sets":
        print("\n".join(weak_sets(rest[0], int(rest[1]), rest[2:])))
    elif cmd == "max-ranks":
        print(max_ranks(rest[0], rest[1:]))
    elif cmd == "header":
        print("\t".join(COLUMNS))
    elif cmd == "row":
        print(row(*rest[:3]))
    else:
        print(f"scaling.py: unknown command {cmd!r}; accepted: weak-sets, max-ranks, header, row", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
