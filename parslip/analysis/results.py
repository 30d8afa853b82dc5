"""A run file as a read-only Python object: ``parslip.open(path)``.

Responsible for what a notebook, a script or the figure code reads from a run:
the interface record with its units, the snapshots as pyvista meshes, the
rupture fronts, the friction record (mu(t), the static peak mu_s, the
precursors), the resolved scene and the provenance.  All file access goes
through ``parslip.io.contract``; pyvista is imported only when a snapshot is
asked for.

    import parslip
    run = parslip.open("out/push.vtkhdf")
    run.interface["ux"]          # [frames, sites], in l
    run.times                    # interface frame times, l/c_r
    run.events                   # every bond break and re-formation, exact to the time step
    run.energy                   # the energy budget per frame: works, elastic, kinetic, damping, breaks
    mesh = run.snapshot_at(30.0) # pyvista UnstructuredGrid nearest t = 30 l/c_r
    [f.nucleation_time for f in run.fronts()]
    run.mu, run.mu_s, run.static_peak, run.precursors()   # friction (analysis.friction)
    run.slip_events()            # stick-slip: each drop of mu with mu before and after, and its precursors
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..errors import ConfigError
from ..io import contract

VTK_LINE = 3                    # VTK's cell type of a two-node line


class Run:
    """One run file, read lazily and cached; nothing here writes to it.

    Units: x and displacements in l (the contact length), times in l/c_r,
    speeds in c_r, interface tractions in rho c_r^2; snapshot positions in a,
    snapshot stresses in rho c_r^2 (see ``units``).
    """

    def __init__(self, path: str):
        contract.check_run_file(path)
        self.path = str(path)

    @classmethod
    def from_arrays(cls, interface: dict, scene: dict | None = None, attrs: dict | None = None) -> "Run":
        """A result object over arrays already in memory (same keys and units as ``interface``, ``events``
        included or not), without snapshots: for records drawn by hand in tests or cut from another run.
        ``scene`` holds dotted keys (``{"load.FN": 1.0}``), ``attrs`` the root attributes (``c_s``, ``c_l``,
        ``c_r`` give the block's wave speeds to a record without events)."""
        self = cls.__new__(cls)
        self.path = "<memory>"
        iface = dict(interface)
        iface.setdefault("t", iface.get("time"))
        iface.setdefault("time", iface["t"])
        # cached_property reads the instance dict first: fill it instead of the file.
        self.__dict__.update(interface=iface, scene=dict(scene or {}), attrs=dict(attrs or {}),
                             snapshot_times=np.zeros(0))
        return self

    def __repr__(self) -> str:
        s = self.scene
        return (f"<parslip run {self.path!r}: {s.get('drive.mode')} v0/c_r = {s.get('drive.v0')}, "
                f"{len(self.times)} frames x {len(self.x)} sites, {len(self.snapshot_times)} snapshots, "
                f"status {self.attrs.get('status')!r}>")

    # --- interface record ---------------------------------------------------
    @cached_property
    def interface(self) -> dict:
        """The ``/interface`` datasets as numpy arrays (``contract.read_interface``); ``t`` aliases ``time``."""
        return contract.read_interface(self.path)

    @property
    def units(self) -> dict:
        """Units of each interface array, from the output contract."""
        u = {name: spec[2] for name, spec in contract.INTERFACE_DATASETS.items()}
        u["t"] = u["time"]
        return u

    @property
    def times(self) -> np.ndarray:
        """Interface frame times, l/c_r from the start of the drive."""
        return self.interface["t"]

    @property
    def x(self) -> np.ndarray:
        """Interface site positions, in l: 0 rear edge, 1 front edge."""
        return self.interface["x"]

    @property
    def events(self) -> dict | None:
        """Every bond break and re-formation, exact to the time step (``/interface/events``): arrays ``step``
        (drive steps, negative before the drive), ``time`` (l/c_r), ``site``, ``kind`` (1 break, 2
        re-formation), ``partner`` (substrate column), sorted by step, site, kind; with ``dt`` (l/c_r per
        step), ``c_s``, ``c_l`` (c_r) and ``site_column0``.  None for a file written before events existed."""
        return self.interface.get("events")

    def replay(self) -> tuple[np.ndarray, np.ndarray]:
        """(intact, partner) [frames, sites] rebuilt from the events alone (``contract.replay_events``): equal
        to ``interface["intact"]`` and ``interface["partner"]`` for a complete record."""
        if self.events is None:
            raise ConfigError(f"RUN {self.path!r}: written before bond events existed; accepted: a run file with "
                              f"/interface/events")
        return contract.replay_events(self.events, len(self.x), self.interface["step"])

    def frame_at(self, t: float) -> int:
        """Index of the interface frame nearest time ``t`` (l/c_r)."""
        return _nearest(self.times, t, "time")

    # --- scene and provenance -----------------------------------------------
    @cached_property
    def attrs(self) -> dict:
        """Root attributes: provenance (command, git commit, version, created_utc, status), dt, c_r, l, ..."""
        return contract.read_attrs(self.path)

    @cached_property
    def scene(self) -> dict:
        """The resolved scene as dotted keys -> values (``{"drive.mode": "push", ...}``)."""
        from ..io.scenefile import loads
        text = self.attrs.get("scene")
        return loads(text) if text else {}

    @property
    def status(self) -> str:
        """"complete", "running" (still written, or killed), "checkpointed at step N", "failed: ..." """
        return str(self.attrs.get("status", "?"))

    @cached_property
    def timings(self) -> dict:
        """The run's timings in s (``io.contract.TIMINGS``): startup, compile, loop, drive, ..."""
        return contract.read_timings(self.path)

    @property
    def mode(self) -> str:
        return self.scene.get("drive.mode", "?")

    @property
    def v0(self) -> float:
        """Drive velocity, in c_r."""
        return float(self.scene.get("drive.v0", float("nan")))

    # --- snapshots ----------------------------------------------------------
    @cached_property
    def snapshot_times(self) -> np.ndarray:
        """Times of the whole-lattice snapshots, in l/c_r."""
        return contract.read_snapshot_times(self.path)

    def snapshot(self, k: int):
        """Snapshot ``k`` (negative counts from the end) as a pyvista UnstructuredGrid.

        Point fields: velocity (internal unit), sxx, syy, sxy (rho c_r^2), one point per node in global
        id order; line cells (every bond: the bulk bonds, then one per interface site, from its top node
        to the substrate node it is bonded to, the top node twice while broken) with cell fields
        ``interface`` and ``intact``; positions in a; field ``Time`` (l/c_r).  Read through the contract
        (``io.contract.read_snapshot_arrays``), so the same mesh from either snapshot layout (``io.mesh``).
        """
        n = len(self.snapshot_times)
        if not -n <= k < n:
            raise ConfigError(f"snapshot {k}: out of range; accepted: -{n} <= k < {n} "
                              f"({n} snapshots in {self.path})" if n else
                              f"snapshot {k}: {self.path} holds no snapshots; accepted: a run with output.snapshots > 0")
        from ..errors import optional
        pv = optional("pyvista", "reading a snapshot as a mesh")
        a = contract.read_snapshot_arrays(self.path, k % n)
        cells = a["cells"]
        lines = np.hstack([np.full((len(cells), 1), 2, np.int64), cells]).ravel()
        mesh = pv.UnstructuredGrid(lines, np.full(len(cells), VTK_LINE, np.uint8), np.asarray(a["points"]))
        for name in ("velocity", "sxx", "syy", "sxy"):
            mesh.point_data[name] = a[name]
        for name in ("interface", "intact"):
            mesh.cell_data[name] = a[name]
        mesh.field_data["Time"] = np.array([a["time"]])
        return mesh

    def snapshot_at(self, t: float):
        """The snapshot nearest time ``t`` (l/c_r) as a pyvista mesh."""
        return self.snapshot(_nearest(self.snapshot_times, t, "snapshot time"))

    # --- fronts -------------------------------------------------------------
    def fronts(self, **kw):
        """The rupture-front catalogue (``analysis.fronts.fronts``: options ``max_gap``, ``min_sites``,
        ``window``), cached per keyword set.  Each front carries every registered per-front field
        (``analysis.fronts.FIELDS``) as an attribute: ``run.fronts()[0].fate``."""
        from .fronts import fronts
        key = tuple(sorted(kw.items()))
        cache = self.__dict__.setdefault("_fronts", {})
        if key not in cache:
            cache[key] = fronts(self, **kw)
        return cache[key]


    @cached_property
    def energy(self) -> dict | None:
        """The energy budget per interface frame (``/energy``, m c_r^2; ``contract.ENERGY_DATASETS``):
        work_drive + work_normal + formed = elastic + kinetic + damping + broken + residual, the state's
        terms as their change since the drive started, the others as totals since then; with ``time``
        (l/c_r).  None for a file written before the budget existed."""
        return None if self.path == "<memory>" else contract.read_energy(self.path)

    # --- friction (``analysis.friction``: the definitions) -----------------------
    @property
    def friction_force(self) -> np.ndarray:
        """F_T per frame: the interface bonds' x-force on the block, m c^2/a (< 0 while it holds the block)."""
        return self._force("friction_force")

    @property
    def drive_force(self) -> np.ndarray:
        """Per frame, the x-force the drive applied to its driven nodes in the step ending there, m c^2/a."""
        return self._force("drive_force")

    @property
    def mu(self) -> np.ndarray:
        """mu(t) = -F_T / F_N per frame, the friction coefficient the interface mobilises."""
        return self._force("mu")

    def _force(self, name: str) -> np.ndarray:
        if name not in self.interface:
            raise ConfigError(f"{name}: {self.path} holds no /interface/{name} (written before parslip recorded "
                              f"forces); accepted: a run file written by this parslip")
        return self.interface[name]

    @property
    def first_break(self) -> tuple:
        """(t, x): time of the first broken bond (l/c_r; None if none broke) and the x (l) of the bonds broken then."""
        from .fronts import first_break
        return first_break(self.interface)

    @cached_property
    def static_peak(self):
        """``analysis.friction.StaticPeak``: mu_s, its time, its window and its place relative to the first break."""
        from .friction import static_peak
        self.mu                                     # a file without forces: one ConfigError line
        return static_peak(self)

    @property
    def mu_s(self) -> float:
        """The static peak of mu: max mu(t) before the contact had slipped everywhere (``static_peak``)."""
        return self.static_peak.mu_s

    @property
    def slip_onset(self) -> float | None:
        """t (l/c_r) by which every interface bond had broken at least once; None if that never happened."""
        return self.static_peak.slip_onset

    def fates(self, **kw) -> list[str]:
        """What became of each front of ``fronts(**kw)`` (``analysis.friction.fate``)."""
        return [f.fate for f in self.fronts(**kw)]

    def precursors(self, **kw) -> list:
        """The fronts that arrested inside the contact (``analysis.friction.Precursor``: arrest time, site, length)."""
        from .friction import precursors
        return precursors(self, **kw)

    def slip_events(self, min_drop: float | None = None, **kw) -> list:
        """The stick-slip record's slip events (``analysis.friction.SlipEvent``): each drop of mu(t) by at least
        ``min_drop`` (default ``friction.MIN_DROP``) of its largest value, with mu before and after, the loader's
        displacement, and the precursors since the previous event."""
        from .friction import MIN_DROP, slip_events
        return slip_events(self, MIN_DROP if min_drop is None else min_drop, **kw)

    def observables(self, **kw) -> dict:
        """The run's friction and front observables as one flat row (``analysis.friction.observables``)."""
        from .friction import observables
        return observables(self, **kw)


def _nearest(values: np.ndarray, t: float, what: str) -> int:
    if len(values) == 0:
        raise ConfigError(f"{what} {t!r}: the run holds none; accepted: a run that wrote them")
    return int(np.argmin(np.abs(np.asarray(values) - float(t))))


def open(path: str) -> Run:  # noqa: A001  (parslip.open mirrors the builtin on purpose)
    """Open a run file read-only; raises ``ConfigError`` naming the path if it is not a parslip run file."""
    return Run(path)
