"""`parslip sweep SWEEP.toml -o OUTDIR`: many scenes as one job, resumable, with a summary table.

Responsible for a sweep from its file to its table: reading and checking the
sweep file, the points it spells, dealing them to groups of ranks, running
each point (``engine.runner.run_scene``, the run as a library call) into its
own output file, recording how each ended, and writing the summary table
(``analysis.table``).

The sweep file (paths relative to the working directory, as everywhere):

    base = "run/push.toml"          # the scene every point starts from
    ranks_per_point = 1             # optional; ranks that run one point together (default 1)
    [set]                           # optional: fixed overrides, every point
    "drive.duration" = 8
    [grid]                          # optional: the cartesian product of these lists (first key slowest)
    "drive.mode" = ["push", "pull"]
    "load.FN" = [0.5, 1.0]
    [zip]                           # optional: equal-length lists taken together, times the grid
    "interface.kx" = [0.05, 0.1]
    "interface.ky" = [0.15, 0.3]

Keys are scene keys (`parslip keys`), quoted or as TOML tables.  Points are
numbered in the grid's order (its first key slowest), each grid point taking
every [zip] row in turn; point i is named p000..., its output
OUTDIR/points/<name>.vtkhdf and its record OUTDIR/points/<name>.json.

How it runs.  The job's ranks (COMM_WORLD, or one process) split into groups
of ``ranks_per_point`` ranks (``comm.Split``); each group runs its points one
after the other on its own communicator.  With ``--shard I/N`` (a Slurm job
array: one task per shard) the points are first dealt to N shards, by their
estimated cost only, so every task computes the same split whatever is on
disk; each task then deals its shard's pending points to its groups.  Both
deals are longest-first to the least-loaded (ties to the lower index):
deterministic.

Resuming: a point whose record says "ok" or "failed: ..." is skipped (the
latter re-run with ``retry_failed``).  A point whose record says "running"
was cut short; its output file says how:
  complete          the run finished but the job ended before the record did: recorded now;
  failed: ...       the job was aborted under it (the watchdog marks the file failed): the point is
                    marked failed with that reason and not run again;
  otherwise         it continues from its checkpoint (``restart="auto"``; a fresh start when there is
                    none).  A point left "running" MAX_UNEXPLAINED times (a process killed with no
                    word, again and again) is marked failed instead.
A point stopped cleanly (SIGTERM, SIGUSR1, --stop-after: its run wrote a
checkpoint) says "stopped: ..." and continues without counting.  Points
checkpoint every ``DEFAULT_CHECKPOINT_WALL`` s of wall clock unless the
sweep sets checkpoint.every or checkpoint.wall; a finished point's checkpoint
is removed.

A point that fails (bad value: ``ConfigError``; non-finite state, write error:
``RunError``; any other exception on a one-rank group) is recorded
"failed: REASON" and the others go on.  Bad sweep files (unknown key,
wrong shape, a [set] or base that does not load) are one ``ConfigError``
line naming the key, the value and what is accepted (exit 2).
"""
from __future__ import annotations

import itertools
import json
import math
import os
import signal
import sys
import time
import traceback
from dataclasses import dataclass, field

from ..errors import ConfigError, RunError
from ..parallel import collective

SECTIONS = ("base", "ranks_per_point", "set", "grid", "zip")
DEFAULT_CHECKPOINT_WALL = 300.0      # s between a point's checkpoints unless the sweep sets a cadence
MAX_UNEXPLAINED = 3                  # times a point may be found "running" on resume before it is failed
WAIT_POLL_S = 0.05                   # a group that has finished polls the others (no busy MPI barrier)
MANIFEST = "sweep.json"


@dataclass
class Point:
    index: int
    name: str
    swept: dict                       # the swept keys' values of this point
    sets: dict                        # every override: [set] and the swept values

    def label(self) -> str:
        return ", ".join(f"{k}={_short(v)}" for k, v in self.swept.items()) or "(base)"


@dataclass
class Sweep:
    path: str
    base: str
    ranks_per_point: int
    fixed: dict
    grid: dict
    zip: dict
    points: list = field(default_factory=list)

    @property
    def swept(self) -> list[str]:
        return list(self.grid) + list(self.zip)


def _short(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


# --------------------------------------------------------------------------------- the sweep file --

def load_sweep(path: str) -> Sweep:
    """Read and check a sweep file; ``ConfigError`` (one line: key, value, accepted) on anything wrong."""
    from ..io import scenefile
    from ..scene.load import load
    from ..scene.schema import SCHEMA

    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ConfigError(f"SWEEP {path!r}: no such file; accepted: a sweep file (TOML with base, [set], [grid], "
                          f"[zip])")
    try:
        with open(path, "rb") as fh:
            raw = scenefile.tomllib.load(fh)
    except (scenefile.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ConfigError(f"SWEEP {path!r}: malformed TOML ({e}); accepted: a sweep file") from None
    for k in raw:
        if k not in SECTIONS:
            raise ConfigError(f"{path}: {k} = {raw[k]!r}: unknown key; accepted: {', '.join(SECTIONS)}")
    base = raw.get("base")
    if not isinstance(base, str) or not base:
        raise ConfigError(f"{path}: base = {base!r}: accepted: the path of a scene file, relative to the working "
                          f"directory (base = \"run/push.toml\")")
    if not os.path.isfile(base):
        raise ConfigError(f"{path}: base = {base!r}: no such file (paths are relative to the working directory "
                          f"{os.getcwd()}); accepted: a scene file")
    rpp = raw.get("ranks_per_point", 1)
    if isinstance(rpp, bool) or not isinstance(rpp, int) or rpp < 1:
        raise ConfigError(f"{path}: ranks_per_point = {rpp!r}: accepted: an integer >= 1")
    tables = {}
    for sec in ("set", "grid", "zip"):
        t = raw.get(sec, {})
        if not isinstance(t, dict):
            raise ConfigError(f"{path}: {sec} = {t!r}: accepted: a table [{sec}] of scene keys")
        tables[sec] = scenefile.flatten(t)
    seen = {}
    for sec, t in tables.items():
        for key, value in t.items():
            if key not in SCHEMA:
                near = [k for k in SCHEMA if k.lower() == key.lower() or k.split(".")[-1] == key.split(".")[-1]]
                hint = f" (did you mean {near[0]}?)" if near else ""
                raise ConfigError(f"{path}: [{sec}] {key} = {value!r}: unknown scene key{hint}; accepted: a key "
                                  f"of `parslip keys`")
            if key in seen:
                raise ConfigError(f"{path}: [{sec}] {key}: also in [{seen[key]}]; accepted: each key in one of "
                                  f"[set], [grid], [zip]")
            seen[key] = sec
            if sec != "set" and (not isinstance(value, list) or not value):
                raise ConfigError(f"{path}: [{sec}] {key} = {value!r}: accepted: a non-empty list of values")
            if sec == "set" and isinstance(value, (list, dict)):
                raise ConfigError(f"{path}: [set] {key} = {value!r}: accepted: one value (lists go in [grid] "
                                  f"or [zip])")
    lens = {k: len(v) for k, v in tables["zip"].items()}
    if len(set(lens.values())) > 1:
        raise ConfigError(f"{path}: [zip] lists of lengths {lens}: accepted: lists of one length, taken together")
    try:
        load(base, tables["set"])
    except ConfigError as e:
        raise ConfigError(f"{path}: base {base!r} with [set]: {e}") from None
    sw = Sweep(path, base, rpp, tables["set"], tables["grid"], tables["zip"])
    sw.points = points(sw)
    return sw


def points(sw: Sweep) -> list[Point]:
    """Every point of the sweep, in order: the grid's product (first key slowest), each with every zip row."""
    gk, zk = list(sw.grid), list(sw.zip)
    combos = list(itertools.product(*sw.grid.values())) if gk else [()]
    rows = list(zip(*sw.zip.values())) if zk else [()]
    n = len(combos) * len(rows)
    width = max(3, len(str(n - 1)))
    out = []
    for i, (g, z) in enumerate(itertools.product(combos, rows)):
        swept = dict(zip(gk, g))
        swept.update(zip(zk, z))
        out.append(Point(i, f"p{i:0{width}d}", swept, {**sw.fixed, **swept}))
    return out


def point_sets(sw: Sweep, p: Point) -> dict:
    """The overrides a point runs with: its own, and a wall-clock checkpoint cadence unless one is set."""
    sets = dict(p.sets)
    if not any(k in sets for k in ("checkpoint.every", "checkpoint.wall")):
        from ..scene.load import load
        base = load(sw.base)
        if not any(base[k] for k in ("checkpoint.every", "checkpoint.wall")):
            sets["checkpoint.wall"] = DEFAULT_CHECKPOINT_WALL
    return sets


# ------------------------------------------------------------------------------------ the dealing --

def cost(sw: Sweep, p: Point) -> float:
    """A point's estimated cost, node-updates up to a constant: nodes x simulated time x steps per l/c_r
    (top_cols / safety); 0 for a point whose scene does not load (it fails at once)."""
    from ..model.lattice import Lattice
    from ..scene.load import load
    try:
        s = load(sw.base, p.sets)
    except ConfigError:
        return 0.0
    lat = Lattice(s["lattice.top_rows"], s["lattice.top_cols"], s["lattice.bottom_rows"], s["lattice.bottom_cols"],
                  s["interface.delta0"], s["lattice.substrate"])
    t = s["load.ramp"] + s["load.settle"] + s["drive.duration"]
    return float(lat.n_nodes) * t * s["lattice.top_cols"] / s["time.safety"]


def deal(costs: list[float], n: int) -> list[list[int]]:
    """Items (by position in ``costs``) to ``n`` bins, longest first to the least-loaded bin (ties: lower
    index, lower bin); each bin's items in increasing order.  Deterministic."""
    bins: list[list[int]] = [[] for _ in range(n)]
    load = [0.0] * n
    for i in sorted(range(len(costs)), key=lambda i: (-costs[i], i)):
        b = min(range(n), key=lambda j: (load[j], j))
        bins[b].append(i)
        load[b] += costs[i]
    return [sorted(b) for b in bins]


# ---------------------------------------------------------------------------------------- records --

def _points_dir(outdir: str) -> str:
    return os.path.join(outdir, "points")


def out_path(outdir: str, p: Point) -> str:
    return os.path.join(_points_dir(outdir), f"{p.name}.vtkhdf")


def _record_path(outdir: str, p: Point) -> str:
    return os.path.join(_points_dir(outdir), f"{p.name}.json")


def read_record(outdir: str, p: Point) -> dict | None:
    try:
        with open(_record_path(outdir, p)) as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return None


def write_record(outdir: str, p: Point, rec: dict) -> None:
    """Written whole to a temporary file and renamed: a killed process never leaves half a record."""
    path = _record_path(outdir, p)
    rec = dict(rec, name=p.name, index=p.index, swept=p.swept, updated_utc=time.strftime("%Y-%m-%dT%H:%M:%SZ",
                                                                                          time.gmtime()))
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w") as fh:
        json.dump(rec, fh, default=str)
    os.replace(tmp, path)


def _file_status(out: str) -> str | None:
    """The output file's status attribute, None when there is no readable file."""
    import h5py

    from ..io.contract import read_status
    try:
        with h5py.File(out, "r") as f:
            return read_status(f)
    except (OSError, KeyError):
        return None


def _manifest(sw: Sweep) -> dict:
    return {"sweep": os.path.abspath(sw.path), "base": sw.base, "ranks_per_point": sw.ranks_per_point,
            "set": sw.fixed, "grid": sw.grid, "zip": sw.zip,
            "points": [{"name": p.name, "swept": p.swept} for p in sw.points]}


def prepare(sw: Sweep, outdir: str) -> None:
    """OUTDIR and its manifest: made on first use; on a later call it must hold the same points."""
    try:
        os.makedirs(_points_dir(outdir), exist_ok=True)
    except OSError as e:
        raise ConfigError(f"-o {outdir!r}: cannot create ({e.strerror}); accepted: a writable directory") from None
    path = os.path.join(outdir, MANIFEST)
    want = _manifest(sw)
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w") as fh:
        json.dump(want, fh, indent=1, default=str)
    try:
        os.link(tmp, path)           # atomic: exactly one task of a job array creates it
    except FileExistsError:
        pass
    finally:
        os.remove(tmp)
    with open(path) as fh:
        have = json.load(fh)
    want = json.loads(json.dumps(want, default=str))
    differ = [k for k in ("base", "set", "points") if want[k] != have.get(k)]
    if differ:
        raise ConfigError(f"-o {outdir!r}: holds another sweep ({have.get('sweep')}: its {', '.join(differ)} "
                          f"differ from this file's); accepted: the same sweep file to resume it, or a new -o")


def triage(sw: Sweep, outdir: str, names: set | None = None, retry_failed: bool = False) -> tuple[list, list]:
    """Rank 0 before a run: settle the records of points a killed job left "running" (see the module's
    docstring) and return (pending points, lines to log) among ``names`` (all when None)."""
    todo, notes = [], []
    for p in sw.points:
        if names is not None and p.name not in names:
            continue
        rec = read_record(outdir, p)
        status = (rec or {}).get("status", "pending")
        if status == "ok" or (status.startswith("failed") and not retry_failed):
            continue
        if status == "running":
            out = out_path(outdir, p)
            fs = _file_status(out)
            unexplained = int(rec.get("unexplained", 0)) + 1
            if fs == "complete":
                notes.append(f"{p.name}: its run had completed; recording it")
            elif fs is not None and fs.startswith("failed"):
                reason = fs[len("failed:"):].strip()
                write_record(outdir, p, dict(rec, status=f"failed: {reason} (the job ended under it)"))
                notes.append(f"{p.name}: failed: {reason} (the job ended under it); not run again")
                continue
            elif unexplained >= MAX_UNEXPLAINED:
                write_record(outdir, p, dict(rec, status=f"failed: interrupted {unexplained} times without a word "
                                                         f"(killed?); not run again", unexplained=unexplained))
                notes.append(f"{p.name}: failed: interrupted {unexplained} times without finishing")
                continue
            else:
                from ..io.checkpoint import path_for
                notes.append(f"{p.name}: was cut short (attempt {unexplained}); continuing "
                             + ("from its checkpoint" if os.path.exists(path_for(out)) else "from the start"))
            write_record(outdir, p, dict(rec, status="pending", unexplained=unexplained))
        todo.append(p)
    return todo, notes


# ---------------------------------------------------------------------------------------- running --

class _Stop:
    """SIGTERM or SIGUSR1 between points (or while a group waits for the others): finish nothing new."""

    def __init__(self):
        self.flag = False
        self._previous = {}
        for sig in (signal.SIGTERM, signal.SIGUSR1):
            try:
                self._previous[sig] = signal.signal(sig, self._on)
            except ValueError:            # not the main thread
                pass

    def _on(self, signum, frame):
        self.flag = True

    def restore(self):
        for sig, h in self._previous.items():
            signal.signal(sig, h)


def _error_line(e: BaseException) -> str:
    """An exception's text on one line (its whitespace collapsed), or its class name when it has none."""
    return " ".join(str(e).split()) or e.__class__.__name__


def run_point(sw: Sweep, p: Point, outdir: str, comm=None, stop_after: float | None = None) -> dict:
    """Run one point on ``comm`` (None: this process) and return its record (every rank alike for the
    status; rank 0's holds the observables).  Its status: "ok", "failed: ...", or "stopped: ..." when
    the run stopped with a checkpoint (a signal, or ``stop_after``) or was interrupted (Ctrl-C)."""
    from ..engine.runner import run_scene
    rank = comm.Get_rank() if comm is not None else 0
    out = out_path(outdir, p)
    rec = dict(read_record(outdir, p) or {}) if rank == 0 else {}
    rec.update(out=os.path.relpath(out, outdir))
    t0 = time.monotonic()
    try:
        sets = point_sets(sw, p)
        oc = run_scene(sw.base, out=out, sets=sets, restart="auto", comm=comm, progress=False,
                       stop_after=stop_after, command=f"parslip sweep {sw.path} ({p.name})")
    except (ConfigError, RunError) as e:
        rec.update(status=f"failed: {_error_line(e)}")
        oc = None
    except Exception as e:            # noqa: BLE001 - on one rank: a bug in one point must not end the sweep
        if comm is not None and comm.Get_size() > 1:
            raise                     # run_scene has already taken the job down
        traceback.print_exc()
        rec.update(status=f"failed: internal error {e.__class__.__name__}: {_error_line(e)}")
        oc = None
    rec["wall_s"] = float(rec.get("wall_s", 0.0)) + (time.monotonic() - t0)
    if oc is not None:
        rec["status"] = "ok" if oc.complete else f"stopped: {oc.status}"
        rec["interrupted"] = oc.interrupted
    if rank == 0:
        _finish_record(rec, out)
    return rec


def _finish_record(rec: dict, out: str) -> None:
    """Observables, resolved scene and commit from the point's output file (rank 0)."""
    from ..analysis.results import Run
    from ..version import git_commit
    rec.setdefault("commit", git_commit())
    if not os.path.exists(out):
        return
    try:
        run = Run(out)
        rec["scene"] = run.scene
        rec["commit"] = run.attrs.get("git_commit", rec["commit"])
        if rec["status"] == "ok":
            rec["observables"] = run.observables()
            from ..io.checkpoint import path_for, remove
            remove(path_for(out))     # the end-of-run checkpoint of a finished point (and its parts): only disk now
    except (ConfigError, OSError, KeyError, ValueError) as e:
        if rec["status"] == "ok":
            rec["status"] = f"failed: its output cannot be read ({_error_line(e)})"


def _wait_all(comm) -> None:
    """Wait for every rank of ``comm`` without spinning a core: a non-blocking barrier, polled."""
    if comm is None or comm.Get_size() == 1:
        return
    req = comm.Ibarrier()
    while not req.Test():
        time.sleep(WAIT_POLL_S)


@dataclass
class SweepResult:
    outdir: str
    ran: int = 0                      # points run by this job
    ok: int = 0
    failed: int = 0
    stopped: int = 0                  # points stopped with a checkpoint (continue: run the sweep again)
    interrupted: bool = False         # Ctrl-C
    summary: list = field(default_factory=list)     # paths of the summary files written (rank 0)
    rows: list = field(default_factory=list)


def run_sweep(path: str, outdir: str, comm=None, *, shard: tuple[int, int] = (0, 1), stop_after: float | None = None,
              retry_failed: bool = False, reanalyse: bool = False, echo=None) -> SweepResult:
    """Run the points of sweep file ``path`` still to run into ``outdir`` on every rank of ``comm`` (None:
    this process alone, no MPI); then (world rank 0) write the summary.  ``shard`` = (I, N): only the
    points dealt to shard I of N (a job array task).  ``stop_after``: wall seconds after which no point
    starts and the running ones stop with a checkpoint.  ``reanalyse``: compute the finished points'
    observables again from their files (after a change to ``analysis``).  ``echo(line)`` reports progress
    (rank 0 of each group); every rank must call this alike.

    The steps: rank 0 plans (reads the sweep, deals the points still to run to the groups of
    ranks_per_point ranks) and every rank learns the plan; each group runs its points (``_run_group``);
    the groups' counts are added up; rank 0 writes the summary."""
    rank = comm.Get_rank() if comm is not None else 0
    size = comm.Get_size() if comm is not None else 1
    echo = echo or (lambda line: print(line, file=sys.stderr, flush=True))
    deadline = time.monotonic() + stop_after if stop_after is not None else None
    si, sn = shard
    if not (isinstance(si, int) and isinstance(sn, int) and sn >= 1 and 0 <= si < sn):
        raise ConfigError(f"--shard {si}/{sn}: accepted: I/N with 0 <= I < N")
    sw, dealt, notes, n_mine = collective.decide(comm, lambda: _plan(path, outdir, size, shard, retry_failed))
    rpp = sw.ranks_per_point
    groups = size // rpp
    g = rank // rpp
    sub = comm.Split(g, rank) if comm is not None and size > 1 else None
    if rank == 0:
        for line in notes:
            echo(f"sweep: {line}")
        todo = sum(len(b) for b in dealt)
        echo(f"sweep {path}: {len(sw.points)} points"
             + (f", {n_mine} in shard {si}/{sn}" if sn > 1 else "")
             + f", {todo} to run on {size} rank(s) in {groups} group(s) of {rpp} -> {outdir}")
    res = SweepResult(outdir)
    lead = _run_group(sw, [sw.points[i] for i in dealt[g]], outdir, sub, g, deadline, res, echo)
    _wait_all(comm)
    _add_up(comm, res, lead)
    if rank == 0:
        if reanalyse:
            _reanalyse(sw, outdir, shard)
        res.rows = summary_rows(sw, outdir)
        res.summary = write_summary(sw, outdir, res.rows)
    return res


def _plan(path: str, outdir: str, size: int, shard: tuple[int, int], retry_failed: bool):
    """Rank 0: the sweep, the indices of the points each group runs, notes on the points skipped, and
    how many points this shard holds."""
    from ..analysis.table import require_netcdf
    require_netcdf()
    sw = load_sweep(path)
    if size % sw.ranks_per_point:
        raise ConfigError(f"{path}: ranks_per_point = {sw.ranks_per_point}: the job has {size} rank(s); "
                          f"accepted: a rank count that is a multiple of ranks_per_point")
    prepare(sw, outdir)
    mine = _shard_points(sw, shard)
    todo, notes = triage(sw, outdir, mine, retry_failed)
    groups = size // sw.ranks_per_point
    dealt = deal([cost(sw, p) for p in todo], groups)
    return sw, [[todo[i].index for i in b] for b in dealt], notes, len(mine)


def _shard_points(sw, shard: tuple[int, int]) -> set:
    """Names of the points dealt to shard I of N (longest first to the least loaded)."""
    si, sn = shard
    return {sw.points[i].name for i in deal([cost(sw, p) for p in sw.points], sn)[si]}


def _run_group(sw, points, outdir: str, sub, g: int, deadline, res: SweepResult, echo) -> bool:
    """Run this group's ``points`` one after the other, until they are done, a stop was asked for, or the
    deadline passed (the group's ranks agree on stopping).  Counts into ``res``; True on the group's lead."""
    lead = (sub.Get_rank() if sub is not None else 0) == 0
    group = sub if sub is not None and sub.Get_size() > 1 else None
    stop = _Stop()
    try:
        for p in points:
            left = None if deadline is None else deadline - time.monotonic()
            halt = stop.flag or (left is not None and left <= 0)
            if group is not None:
                halt = any(group.allgather(halt))
            if halt:
                break
            if lead:
                write_record(outdir, p, dict(read_record(outdir, p) or {}, status="running"))
            rec = run_point(sw, p, outdir, group, left)
            res.ran += 1
            status = rec["status"]
            if lead:
                write_record(outdir, p, rec)
                echo(f"sweep group {g}: {p.name} [{p.label()}] {_describe(rec)}")
            if status == "ok":
                res.ok += 1
            elif status.startswith("failed"):
                res.failed += 1
            else:
                res.stopped += 1
                res.interrupted = bool(rec.get("interrupted"))
                break
    finally:
        stop.restore()
    return lead


def _add_up(comm, res: SweepResult, lead: bool) -> None:
    """Each group's counts once (from its lead rank), added up on every rank."""
    if comm is None or comm.Get_size() == 1:
        return
    mine = [res.ran, res.ok, res.failed, res.stopped, int(res.interrupted)] if lead else [0] * 5
    counts = [sum(c) for c in zip(*comm.allgather(mine))]
    res.ran, res.ok, res.failed, res.stopped, res.interrupted = counts[:4] + [bool(counts[4])]


def _reanalyse(sw, outdir: str, shard: tuple[int, int]) -> None:
    """Rank 0: the observables of this shard's finished points computed again from their files."""
    mine = _shard_points(sw, shard)
    for p in sw.points:
        rec = read_record(outdir, p)
        if p.name in mine and rec and rec.get("status") == "ok":
            _finish_record(rec, out_path(outdir, p))
            write_record(outdir, p, rec)


def _describe(rec: dict) -> str:
    st = rec["status"]
    wall = f" in {rec.get('wall_s', 0.0):.1f} s"
    if st != "ok":
        return st + wall
    o = rec.get("observables") or {}
    mu = o.get("mu_s", math.nan)
    mu_txt = f"mu_s = {mu:.4g}" + ("" if o.get("mu_s_window") == "slip onset" else " (bound)")
    return (f"ok{wall}: {mu_txt}, first break t = {o.get('first_break_time', math.nan):.3g}, "
            f"{o.get('n_fronts', 0)} fronts ({o.get('rupture_kind', '?')}), {o.get('n_precursors', 0)} precursors")


# ---------------------------------------------------------------------------------------- summary --

def summary_rows(sw: Sweep, outdir: str) -> list[dict]:
    """One row per point from the records on disk (every shard's), in point order."""
    from ..analysis.table import OBSERVABLES
    rows = []
    for p in sw.points:
        rec = read_record(outdir, p) or {}
        status = rec.get("status", "pending")
        if status in ("running", "pending") or status.startswith("stopped"):
            status = "pending"
        row = {"point": p.name, **p.swept, "status": status}
        obs = rec.get("observables") or {}
        for k in OBSERVABLES:
            row[k] = obs.get(k)
        scene = rec.get("scene")
        row.update(wall_s=rec.get("wall_s"), out=os.path.join("points", f"{p.name}.vtkhdf"),
                   scene=json.dumps(scene, sort_keys=True) if scene else "", commit=rec.get("commit", ""))
        rows.append(row)
    return rows


def write_summary(sw: Sweep, outdir: str, rows: list[dict]) -> list[str]:
    """OUTDIR/summary.csv and OUTDIR/summary.nc, under a lock: the tasks of a job array each write them
    when they end, and the last one holds every point."""
    import fcntl

    from ..analysis import table
    cols = table.columns(sw.swept)
    csv_path, nc_path = os.path.join(outdir, "summary.csv"), os.path.join(outdir, "summary.nc")
    with open(os.path.join(outdir, ".summary.lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        rows = summary_rows(sw, outdir)          # read again under the lock: other tasks may have finished
        table.write_csv(csv_path, cols, rows)
        table.write_netcdf(nc_path, cols, rows, attrs={"sweep": os.path.abspath(sw.path), "base": sw.base,
                                                       "swept": json.dumps(sw.swept),
                                                       "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ",
                                                                                    time.gmtime())})
    return [csv_path, nc_path]
