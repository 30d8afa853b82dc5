"""The paper reproduced: the runs it needs, running or reusing them, the claims table, the figures, the readings.

Responsible for ``parslip paper``: which scenes (``ROLES``, each a set of
scene keys over the schema's defaults, which are the paper's scene), making
each run once in ``OUT/runs/<role>.vtkhdf`` (a run already there with the
same resolved scene and status ``complete`` is reused), the claims table of
``studies.paper.claims`` written as ``OUT/claims.md`` and ``OUT/claims.json``, the
figure set (``plot.figures``) under ``OUT/figures/``, and the scan of the
paper's open readings (``READINGS``): each reading and the promising
combinations scored by the share of claims that agree (``scan_readings``).

Every run starts in ``run_scene``, the one place to change when runs move
in-process (``parslip.run``).  Measuring is ``measures``' and ``claims``' job; this
module only decides what to run and writes the tables.
"""
from __future__ import annotations

import json
import logging
import math
import os
import time
from dataclasses import dataclass

from ...errors import ConfigError
from ...io.scenefile import loads as load_scene_text
from ...parallel import collective
from ...scene.load import load
from ...scene.schema import SCHEMA, to_toml
from . import claims as cl

log = logging.getLogger("parslip")

# --- the runs -------------------------------------------------------------------------------

L100 = {"lattice.top_rows": 10, "lattice.top_cols": 100, "lattice.bottom_rows": 20}
# role -> scene keys over the schema defaults (the paper's scene); run/<mode>.toml are these scenes.
ROLES: dict[str, dict] = {
    "push": {"drive.mode": "push", "drive.v0": 1e-3, "drive.duration": 100.0},
    "pull": {"drive.mode": "pull", "drive.v0": 1e-3, "drive.duration": 100.0},
    # T0 to 300 l/c_r: three fronts (Fig. 6c); the stress maps come from shear_maps.
    "shear": {"drive.mode": "shear", "drive.v0": 1e-4, "drive.duration": 300.0, "output.snapshots": 0},
    "push_v0_1e-2": {"drive.mode": "push", "drive.v0": 1e-2, "drive.duration": 15.0, "output.snapshots": 0},
    # 1000 l/c_r: three crossings at v0 = 1e-4; frames every 0.05 l/c_r (a pulse moves one site per ~7).
    "push_v0_1e-4": {"drive.mode": "push", "drive.v0": 1e-4, "drive.duration": 1000.0,
                     "output.interface_dt": 0.05, "output.snapshots": 0},
    # Sec. 4.4: the same aspect ratio at l = 300 and 500; interface frames every 0.01-0.02 l/c_r.
    "push_l300": {"drive.mode": "push", "drive.v0": 1e-3, "drive.duration": 40.0, "output.interface_dt": 0.02,
                  "output.fields": "interface"},
    "pull_l300": {"drive.mode": "pull", "drive.v0": 1e-3, "drive.duration": 40.0, "output.interface_dt": 0.02,
                  "output.fields": "interface"},
    # shear_l300 at the l = 100 scenes' cadence, 1 a/c_r: at 3 a/c_r a front at c_r crosses 3 sites a frame
    # and its fitted speed reads 0.68 c_r instead of 0.75.  shear_l500 to 100 l/c_r: the first rupture comes
    # at ~24 l/c_r and some regions take tens of l/c_r to re-bond (Sec. 4.4); frames every 5 a/c_r keep
    # its file near 200 MB.
    "shear_l300": {"drive.mode": "shear", "drive.v0": 1e-4, "drive.duration": 45.0, "output.fields": "interface"},
    "shear_l500": {"drive.mode": "shear", "drive.v0": 1e-4, "drive.duration": 100.0, "output.interface_dt": 0.01,
                   "output.fields": "interface"},
}
SCALE = {"push_l300": 3, "pull_l300": 3, "shear_l300": 3, "shear_l500": 5}
# shear_maps: the shear scene to 2 l/c_r past its first break, a snapshot every 0.5 l/c_r (Fig. 7a's maps);
# its duration follows from the shear run, so it is made after it.
MAPS = "shear_maps"
ORDER = ("push", "pull", "shear", MAPS, "push_v0_1e-2", "push_v0_1e-4", "push_l300", "pull_l300", "shear_l300",
         "shear_l500")
# --shrink: every run a few seconds (tests of the pipeline; the claims then say little).
SHRINK = {"lattice.top_rows": 4, "lattice.top_cols": 24, "lattice.bottom_rows": 4, "lattice.bottom_cols": 40,
          "load.settle": 2.0, "output.interface_dt": 0.0}
SHRINK_V0 = 0.02
SHRINK_DURATION = 6.0


def _scaled(base: dict, factor: float) -> dict:
    """The geometry of ``base`` (the role's resolved defaults) times ``factor``, same aspect ratio."""
    out = {}
    for k in ("lattice.top_rows", "lattice.top_cols", "lattice.bottom_rows", "lattice.bottom_cols"):
        v = int(round(base[k] * factor))
        out[k] = v
    if (out["lattice.bottom_cols"] - out["lattice.top_cols"]) % 2:
        out["lattice.bottom_cols"] += 1
    return out


def role_scene(role: str, sets: dict | None = None, shrink: bool = False, maps_duration: float = 0.0) -> dict:
    """The scene keys (flat, dotted) of a role: its overrides, the study's ``sets`` (a reading), scaled to
    the role's contact size; ``maps_duration`` is the shear_maps run's drive time."""
    sets = dict(sets or {})
    if role == MAPS:
        keys = dict(ROLES["shear"], **{"drive.duration": maps_duration, "output.snapshots": int(2 * maps_duration)})
    else:
        keys = dict(ROLES[role])
    if shrink:
        keys.update(SHRINK)
        keys["drive.v0"] = SHRINK_V0 * keys["drive.v0"] / (1e-4 if keys["drive.mode"] == "shear" else 1e-3)
        keys["drive.duration"] = SHRINK_DURATION if role != MAPS else maps_duration
        keys["output.snapshots"] = 0 if keys.get("output.snapshots", SCHEMA["output.snapshots"].default) == 0 else 3
    per_node = sets.get("load.FN") == "per_node"
    if per_node:
        sets.pop("load.FN")
    scene = dict(keys, **sets)
    if role in SCALE:
        geom = {k: scene.get(k, SCHEMA[k].default) for k in
                ("lattice.top_rows", "lattice.top_cols", "lattice.bottom_rows", "lattice.bottom_cols")}
        scene.update(_scaled(geom, SCALE[role] if not shrink else 1 + 0.25 * SCALE[role]))
    if per_node:
        scene["load.FN"] = float(scene.get("lattice.top_cols", SCHEMA["lattice.top_cols"].default))
    return scene


def run_scene(scene: dict, out: str, comm=None) -> int:
    """Run ``scene`` (flat dotted keys) to ``out`` on every rank of ``comm`` (None: this process, no MPI),
    in this process (``engine.runner.run_scene``, what ``parslip.run`` calls); returns the exit code the
    command line would give (0, 2 bad input, 3 failed), the same on every rank.  The scene is also written
    beside the output as ``out`` with .toml, for whoever wants to run it again by hand."""
    from ...engine.runner import run_scene as run
    from ...errors import ConfigError, RunError
    if comm is None or comm.Get_rank() == 0:
        os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
        with open(os.path.splitext(out)[0] + ".toml", "w") as fh:
            fh.write(to_toml(scene))
    if comm is not None:
        comm.Barrier()
    try:
        run(scene, out=out, overwrite=True, comm=comm, progress=False, command="parslip paper")
        return 0
    except (ConfigError, RunError) as e:
        if comm is None or comm.Get_rank() == 0:
            log.warning(f"{os.path.basename(out)}: {e}")
        return 2 if isinstance(e, ConfigError) else 3


def reusable(path: str, scene: dict) -> bool:
    """True when ``path`` is a complete run of exactly ``scene`` (its resolved keys)."""
    if not os.path.exists(path):
        return False
    try:
        from ...io.contract import read_attrs
        attrs = read_attrs(path)
        stored = load_scene_text(attrs.get("scene", ""))
        want = load(scene)
        return str(attrs.get("status")) == "complete" and all(stored.get(k) == v for k, v in want.items())
    except Exception:                                   # not a run file, an older scene: run it again
        return False


@dataclass
class Made:
    role: str
    path: str
    seconds: float          # wall time of the run; 0 when reused
    reused: bool
    code: int               # exit code (0 for a reused run)
    note: str = ""          # why a run is missing (refused scene, failed run)


def ensure(role: str, scene: dict, run_dir: str, comm=None, rerun: bool = False) -> Made:
    """Make (or reuse) the run of ``role`` with ``scene`` in ``run_dir``; a scene the schema refuses is
    reported, not run."""
    path = os.path.join(run_dir, f"{role}.vtkhdf")
    try:
        load(scene)
    except ConfigError as e:
        return Made(role, path, 0.0, False, 2, f"refused: {e}")
    # Rank 0 reads the file and every rank takes its answer (parallel.collective: a ConfigError there
    # reaches every rank instead of leaving them waiting in the broadcast).
    keep = collective.decide(comm, lambda: not rerun and reusable(path, scene))
    if keep:
        return Made(role, path, 0.0, True, 0)
    log.info(f"running {role} -> {path}")
    t0 = time.monotonic()
    code = run_scene(scene, path, comm)
    return Made(role, path, time.monotonic() - t0, False, code, "" if code == 0 else f"run failed (exit {code})")


def make_runs(run_dir: str, roles=None, sets: dict | None = None, shrink: bool = False, comm=None,
              rerun: bool = False) -> tuple[dict, list[Made]]:
    """Every role's run (``ORDER``, or ``roles``) in ``run_dir``; returns (role -> parslip.open result on
    rank 0, what was made)."""
    from ...analysis.results import open as open_run
    from ...analysis.fronts import first_break_time
    rank0 = comm is None or comm.Get_rank() == 0
    roles = [r for r in ORDER if roles is None or r in roles]
    runs, made = {}, []
    for role in roles:
        maps_duration = 0.0
        if role == MAPS:
            # Only rank 0 holds the opened runs: it measures the first break, every rank takes its value.
            tb = collective.decide(comm, lambda: first_break_time(runs["shear"]) if "shear" in runs else math.nan)
            if not math.isfinite(tb):
                made.append(Made(role, "", 0.0, False, 1, "no shear run with a break to map"))
                continue
            maps_duration = float(math.ceil(tb + 2.0))
        scene = role_scene(role, sets, shrink, maps_duration)
        mk = ensure(role, scene, run_dir, comm, rerun)
        made.append(mk)
        if rank0 and mk.code == 0 and os.path.exists(mk.path):
            runs[role] = open_run(mk.path)
    return runs, made


# --- figures and tables ---------------------------------------------------------------------

FIGURES_SCALED = ("spacetime", "front_speed")


def first_front_times(shear, maps) -> list[float]:
    """Fig. 7a's three moments of the first T0 front: its nucleation, its tip halfway, its last site; kept
    within the maps run's snapshots."""
    f = shear.fronts()[0]
    tt = f.tip["t"]
    t_max = float(maps.snapshot_times[-1]) if len(maps.snapshot_times) else float(tt[-1])
    return [min(float(t), t_max) for t in (tt[0], tt[len(tt) // 2], tt[-1])]


def write_figures(runs: dict, fig_dir: str) -> list[str]:
    """Each run's figure set under ``fig_dir/<role>/`` (the l = 300/500 runs: space-time and speed only),
    the T0 stress maps from shear_maps, the v0 sweep and push against pull."""
    from ...plot import figures
    paths = []
    for role, run in runs.items():
        if role == MAPS:
            continue
        only = FIGURES_SCALED if role in SCALE else None
        if role == "shear" or role.startswith("push_v0"):
            only = [f for f in figures.FIGURES if f != "stress_maps"]
        paths += figures.write_all(run, os.path.join(fig_dir, role), only)
    if MAPS in runs and "shear" in runs and runs["shear"].fronts():
        paths += figures.fig_stress_maps(runs[MAPS], os.path.join(fig_dir, "shear"),
                                         times=first_front_times(runs["shear"], runs[MAPS]))
    sweep = [runs[k] for k in ("push_v0_1e-2", "push", "push_v0_1e-4") if k in runs]
    if len(sweep) > 1:
        paths += figures.compare_speeds(sweep, fig_dir, scale="v0", name="v0_sweep")[0]
    if "push" in runs and "pull" in runs:
        paths += figures.compare_speeds([runs["push"], runs["pull"]], fig_dir, n=2, scale="c_r",
                                        name="push_vs_pull")[0]
    return paths


def _runs_table(made: list[Made]) -> str:
    out = ["| role | run | wall time (s) | note |", "| --- | --- | --- | --- |"]
    for mk in made:
        how = "reused" if mk.reused else f"{mk.seconds:.1f}"
        out.append(f"| {mk.role} | {os.path.basename(mk.path)} | {how} | {mk.note} |")
    return "\n".join(out) + "\n"


def _reading_text(sets: dict) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in sets.items()) if sets else "the schema defaults"


def reproduce(out_dir: str, roles=None, sets: dict | None = None, shrink: bool = False, figures: bool = True,
              comm=None, rerun: bool = False) -> dict:
    """Make or reuse every run under ``out_dir/runs``, then (rank 0) write the figures, ``claims.md`` and
    ``claims.json``.  Returns {"rows", "runs", "made", "seconds"}."""
    t0 = time.monotonic()
    rank0 = comm is None or comm.Get_rank() == 0
    if rank0:
        os.makedirs(out_dir, exist_ok=True)
    runs, made = make_runs(os.path.join(out_dir, "runs"), roles, sets, shrink, comm, rerun)
    t_runs = time.monotonic() - t0
    rows = []
    if rank0:
        rows = cl.evaluate(runs)
        if figures:
            write_figures(runs, os.path.join(out_dir, "figures"))
        seconds = time.monotonic() - t0
        title = f"The paper's claims, parslip with {_reading_text(sets or {})}"
        with open(os.path.join(out_dir, "claims.md"), "w") as fh:
            fh.write(cl.to_markdown(rows, title))
            fh.write(f"\n## Runs\n\nRuns {t_runs:.0f} s, in all {seconds:.0f} s (wall, this process).\n\n")
            fh.write(_runs_table(made))
        with open(os.path.join(out_dir, "claims.json"), "w") as fh:
            fh.write(cl.to_json(rows, reading=sets or {}, shrink=shrink, seconds=round(seconds, 1),
                                run_seconds=round(t_runs, 1),
                                runs=[{"role": m.role, "seconds": round(m.seconds, 1), "reused": m.reused,
                                       "exit": m.code, "note": m.note} for m in made]))
    return {"rows": rows, "runs": runs, "made": made, "seconds": time.monotonic() - t0}


# --- the readings -------------------------------------------------------------------------------

@dataclass(frozen=True)
class Reading:
    """One thing the paper leaves open: its scene key, the question, and the options (value, label)."""
    key: str
    question: str
    options: tuple


READINGS: tuple[Reading, ...] = (
    Reading("material.velocity_unit", "velocity unit of the stiffnesses (Sec. 2 normalises by c_r)",
            (("c_s", "c_s"), ("c_r", "c_r"))),
    Reading("material.kn_spring", "which spring is k_n", (("along", "along the bond (Eq. 2.1)"),
                                                         ("across", "across the bond (text near Fig. 1)"))),
    Reading("material.bottom_kn", "substrate k_n from \"k_n^2 = 100\"", ((100.0, "k_n = 100"),
                                                                      (10.0, "k_n = 10"))),
    Reading("drive.hold", "driven face held in", (("x", "x only"), ("xy", "x and y"))),
    Reading("interface.rebond", "a free node re-bonds to", (("nearest", "the nearest free node"),
                                                           ("facing", "the facing node"))),
    Reading("interface.rebond_within", "re-bonds within", ((0.0, "delta0 = 0.5 a"), (0.7, "delta_b = 0.7 a"))),
    Reading("load.FN", "F_N = 1 is", ((1.0, "the total"), ("per_node", "per node of SR"))),
    Reading("lattice.bottom_cols", "substrate width", ((300, "300 (the captions)"), (200, "200 (the methods)"))),
    Reading("material.model", "nu = 0.2 in", (("plane_strain", "plane strain"), ("plane_stress", "plane stress"))),
    Reading("interface.reform_x0", "rest offset of a re-formed bond", (("current", "its offset when it forms"),
                                                                      ("zero", "0"))),
)
# Other likely causes of a disagreement that are numerics, not readings: scanned beside them, never shipped.
NUMERICS: tuple[tuple[str, dict], ...] = (
    ("damping zeta halved (0.05)", {"time.zeta": 0.05}),
    ("damping zeta doubled (0.2)", {"time.zeta": 0.2}),
    ("interface frames every 0.25 a/c_r", {"output.interface_dt": 0.0025}),
    ("substrate twice as deep (40 rows)", {"lattice.bottom_rows": 40}),
)
# The scan runs these roles (about 40 s a setting on one rank); claims needing others are not measured there.
SCAN_ROLES = ("push", "pull", "shear", "push_v0_1e-2")


def default_reading() -> dict:
    return {r.key: SCHEMA[r.key].default for r in READINGS}


def _slug(sets: dict) -> str:
    if not sets:
        return "base"
    return "__".join(f"{k.split('.')[-1]}-{v}" for k, v in sets.items()).replace("/", "_")


def _score(rows: list[dict], scan_keys: set) -> tuple[int, int]:
    """(agreeing, claims the scan roles can measure)."""
    sub = [r for r in rows if r["key"] in scan_keys]
    return sum(r["verdict"] == cl.AGREES for r in sub), len(sub)


def scan_readings(out_dir: str, sets: dict | None = None, shrink: bool = False, comm=None, combos: bool = True,
                  numerics: bool = True, rerun: bool = False) -> dict:
    """Score the base reading (the schema defaults with ``sets``), each other option of every reading alone,
    the promising combinations (from the best single reading, greedily adding the reading that raises the
    score most, every remaining one tried at each step) and the numerics of ``NUMERICS``, by the claims
    the scan roles measure.
    Writes ``out_dir/readings.md`` and ``readings.json``; returns {"settings": [...], "claims": {...}}."""
    rank0 = comm is None or comm.Get_rank() == 0
    base = dict(sets or {})
    scan_keys = {c.key for c in cl.CLAIMS if set(c.needs) <= set(SCAN_ROLES)}
    results = []

    def run_setting(label: str, change: dict, kind: str):
        s = dict(base, **change)
        runs, made = make_runs(os.path.join(out_dir, "readings", _slug(change)), SCAN_ROLES, s, shrink, comm, rerun)
        notes = list(dict.fromkeys(mk.note for mk in made if mk.note))
        rows = cl.evaluate(runs) if rank0 else []
        agree, n = _score(rows, scan_keys) if rank0 else (0, 0)
        results.append({"label": label, "kind": kind, "change": change, "agree": agree, "of": n,
                        "seconds": round(sum(mk.seconds for mk in made), 1),
                        "note": "; ".join(notes), "rows": rows,
                        "alternatives": cl.alternatives(runs) if rank0 and kind == "base" else []})
        return results[-1]

    now = dict(default_reading(), **{k: v for k, v in base.items() if k in default_reading()})
    b = run_setting("base: " + ", ".join(f"{k} = {v!r}" for k, v in now.items()), {}, "base")
    singles = []
    for r in READINGS:
        for value, label in r.options:
            if value == now[r.key]:
                continue
            singles.append(run_setting(f"{r.key} = {value!r} ({label})", {r.key: value}, "reading"))
    if combos:
        # Greedy: from the best single reading, add the one other reading (any option) that raises the score
        # most, until none does; each step scores every remaining reading added to the current best.
        ok = [s_ for s_ in singles if not s_["note"]]
        best = max(ok, key=lambda s_: s_["agree"], default=None)
        while best is not None and best["agree"] > b["agree"]:
            tried = []
            for s_ in ok:
                (key, value), = s_["change"].items()
                if key in best["change"]:
                    continue
                ch = dict(best["change"], **{key: value})
                tried.append(run_setting(" + ".join(f"{k} = {v!r}" for k, v in ch.items()), ch, "combination"))
            step = max(tried, key=lambda s_: s_["agree"], default=None)
            best = step if step is not None and step["agree"] > best["agree"] and not step["note"] else None
    if numerics:
        for label, ch in NUMERICS:
            run_setting(label, ch, "numerics")
    out = {"settings": results}
    if rank0:
        _write_readings(out_dir, results, scan_keys)
    return out


def _write_readings(out_dir: str, results: list[dict], scan_keys: set) -> None:
    n_all = len(cl.CLAIMS)
    lines = ["# The paper's open readings, scored", "",
             f"Each setting runs {', '.join(SCAN_ROLES)} (the claims they measure: {len(scan_keys)} of {n_all}; "
             "the others need the v0 = 1e-4 and l = 300/500 runs of `parslip paper`).", "",
             "| setting | kind | claims agreeing (scan) | share | run time (s) | note |",
             "| --- | --- | --- | --- | --- | --- |"]
    for r in sorted(results, key=lambda r: (r["kind"] == "numerics", -r["agree"])):
        share = f"{r['agree'] / r['of']:.0%}" if r["of"] else "n/a"
        lines.append(f"| {r['label']} | {r['kind']} | {r['agree']} / {r['of']} | {share} | {r['seconds']} | "
                     f"{r['note'].replace('|', '/')} |")
    base = results[0]
    dis = [row for row in base["rows"] if row["key"] in scan_keys and row["verdict"] != cl.AGREES]
    if dis:
        lines += ["", "## Each claim the base setting misses, under every setting", ""]
        head = ["setting"] + [row["key"] for row in dis]
        lines += ["| " + " | ".join(head) + " |", "| " + " | ".join("---" for _ in head) + " |"]
        lines.append("| paper | " + " | ".join(row["paper"].replace("|", "/") for row in dis) + " |")
        lines.append("| tolerance | " + " | ".join(row["tolerance"].split(" (")[0] for row in dis) + " |")
        for r in results:
            by = {row["key"]: row for row in r["rows"]}
            cells = []
            for row in dis:
                x = by.get(row["key"])
                cells.append("-" if x is None else (f"**{x['parslip']}**" if x["verdict"] == cl.AGREES
                                                    else x["parslip"]).replace("|", "/"))
            lines.append(f"| {r['label']} | " + " | ".join(cells) + " |")
        lines += ["", "Bold: agrees."]
    alts = [a for a in base.get("alternatives", []) if a["key"] in {row["key"] for row in dis}]
    if alts:
        lines += ["", "## The same base runs, measured another way", "",
                  "| claim | measured as | parslip | verdict |", "| --- | --- | --- | --- |"]
        lines += [f"| {a['key']} | {a['how']} | {a['parslip']} | {a['verdict']} |" for a in alts]
    with open(os.path.join(out_dir, "readings.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    with open(os.path.join(out_dir, "readings.json"), "w") as fh:
        json.dump({"scan_roles": list(SCAN_ROLES), "scan_claims": sorted(scan_keys),
                   "settings": [{k: v for k, v in r.items()} for r in results]}, fh, indent=1, default=str)
