"""Off-screen pictures of a run's snapshots: one frame as PNG, the series as MP4 or GIF.

Responsible for how a snapshot looks: bonds drawn as lines coloured by a
node field, intact interface bonds on top in pure red, the colour scale
centred on zero and symmetric for signed fields, the camera framed on the
contact (the interface bonds' extent plus 10 % on each side, the top block
and some substrate in height), a caption with the field, its unit and the
time.  It reads runs only through ``parslip.open`` (``Run.snapshot_times``,
``Run.snapshot(k)``), and renders with pyvista off screen (EGL; no display).

    import parslip
    from parslip.plot.render import render_frame, render_movie
    run = parslip.open("out/push.vtkhdf")
    render_frame(run, "sxy", 50.0, "sxy_t50.png")      # time in l/c_r, nearest snapshot
    render_movie(run, "sxy", "sxy.mp4")                # every snapshot, one scale for all
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError

# Off-screen EGL rendering needs no X display; it must be chosen before VTK makes a window.
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

WINDOW = (1600, 480)            # pixels; multiples of 16, so MP4 encoders need not resize
INTACT_RGB = (255, 0, 0)        # pure red: outside every colour map used here (coolwarm's red is 180, 4, 38)
MOVIE_SUFFIXES = (".mp4", ".gif")
# Colour limits take this percentile of |value|, so a single node at a crack tip does not wash out the field.
CLIM_PERCENTILE = 99.0


@dataclass(frozen=True)
class Field:
    """A node field as drawn: ``array`` in the snapshot, ``component`` (None: the scalar itself,
    -1: the vector's magnitude), whether its scale is symmetric about zero, its unit."""
    array: str
    component: int | None
    symmetric: bool
    unit: str
    cmap: str


def fields(velocity_unit: str = "c_s") -> dict[str, Field]:
    """The drawable fields: stresses in rho c_r^2, velocities in the run's internal velocity unit."""
    stress = "rho c_r^2"
    return {"sxx": Field("sxx", None, True, stress, "coolwarm"),
            "syy": Field("syy", None, True, stress, "coolwarm"),
            "sxy": Field("sxy", None, True, stress, "coolwarm"),
            "vx": Field("velocity", 0, True, velocity_unit, "coolwarm"),
            "vy": Field("velocity", 1, True, velocity_unit, "coolwarm"),
            "speed": Field("velocity", -1, False, velocity_unit, "viridis")}


FIELD_NAMES = tuple(fields())


def field_spec(run, name: str) -> Field:
    """The ``Field`` called ``name``; ConfigError naming the accepted ones otherwise."""
    # A file written before material.velocity_unit existed ran in c_s, the only unit there was then.
    unit = str(run.scene.get("material.velocity_unit", "c_s")) if hasattr(run, "scene") else "c_s"
    table = fields(unit)
    if name not in table:
        raise ConfigError(f"--field {name!r}: unknown; accepted: {', '.join(table)}")
    return table[name]


def field_values(mesh, f: Field) -> np.ndarray:
    """Node values of field ``f`` on a snapshot mesh (a 1-D array, one value per point)."""
    a = np.asarray(mesh.point_data[f.array])
    if f.component is None:
        return a
    return np.linalg.norm(a, axis=1) if f.component < 0 else a[:, f.component]


def colour_limits(values, f: Field) -> tuple[float, float]:
    """(lo, hi): +-P99 of |value| for a signed field, so zero sits mid-scale; [0, P99] otherwise.

    A field that is zero everywhere gets +-1 (or [0, 1]) so the scale stays valid.
    """
    v = np.abs(np.asarray(values, dtype=float))
    lim = float(np.percentile(v, CLIM_PERCENTILE)) if v.size else 0.0
    if not np.isfinite(lim) or lim <= 0:
        lim = float(v.max()) if v.size and np.isfinite(v.max()) and v.max() > 0 else 1.0
    return (-lim, lim) if f.symmetric else (0.0, lim)


def snapshot_index(run, time: float | None) -> int:
    """Index of the snapshot nearest ``time`` (l/c_r); the last one for None.

    Accepted: the snapshots' time span widened by half the mean spacing at
    each end, so a rounded time (e.g. 4.0 for 4.0028) still names its snapshot.
    """
    t = np.asarray(run.snapshot_times, dtype=float)
    if t.size == 0:
        raise ConfigError(f"RUN {run.path!r}: holds no snapshots; accepted: a run with output.snapshots > 0")
    if time is None:
        return t.size - 1
    half = 0.5 * (t[-1] - t[0]) / (t.size - 1) if t.size > 1 else 0.0
    if not (np.isfinite(time) and t[0] - half - 1e-12 <= time <= t[-1] + half + 1e-12):
        raise ConfigError(f"--time {time:g}: outside the snapshots ({t.size} from {t[0]:g} to {t[-1]:g} l/c_r); "
                          "accepted: a time in that span (the nearest snapshot is drawn)")
    return int(np.argmin(np.abs(t - time)))


@dataclass
class Frame:
    """What a rendered frame shows: snapshot index, its time (l/c_r), the colour limits, and
    the view: ``focal`` (x, y in a) at the window's centre, ``half_height`` (a) from there to
    the top edge (parallel projection, so the map from the plane to pixels is affine)."""
    step: int
    time: float
    clim: tuple[float, float]
    path: str
    window: tuple[int, int]
    focal: tuple[float, float]
    half_height: float

    def pixel(self, xy) -> tuple[float, float]:
        """(column, row from the top) of the world point ``xy`` (a) in the picture."""
        w, h = self.window
        per_a = 0.5 * h / self.half_height             # pixels per lattice spacing, both axes
        return (0.5 * w + (xy[0] - self.focal[0]) * per_a, 0.5 * h - (xy[1] - self.focal[1]) * per_a)


def _contact_view(mesh, window=WINDOW) -> tuple[tuple[float, float, float], float]:
    """Focal point and parallel scale (half the visible height, in a) framing the contact.

    x: the interface bonds' extent +- 10 % of the contact length; y: from a
    quarter of that length below the interface to just above the top block.
    The wider requirement wins for the window's aspect ratio.
    """
    iface = mesh.extract_cells(np.asarray(mesh.cell_data["interface"]) == 1)
    pts = np.asarray(mesh.points)
    if iface.n_cells:
        b = iface.bounds
        x0, x1, y_if = b[0], b[1], 0.5 * (b[2] + b[3])
    else:                               # no interface (a free block): the whole lattice
        x0, x1 = pts[:, 0].min(), pts[:, 0].max()
        y_if = pts[:, 1].min()
    w = max(x1 - x0, 1.0)
    inside = (pts[:, 0] >= x0 - 0.1 * w) & (pts[:, 0] <= x1 + 0.1 * w)
    y_top = pts[inside, 1].max() + 0.05 * w
    y_bot = y_if - 0.25 * w
    aspect = window[0] / window[1]
    half_h = max(0.5 * (y_top - y_bot), 0.5 * 1.2 * w / aspect)
    return (0.5 * (x0 + x1), 0.5 * (y_top + y_bot), 0.0), half_h


class _Scene:
    """One off-screen plotter; ``draw`` puts a snapshot in it with fixed camera and colour limits."""

    def __init__(self, window=WINDOW):
        from ..errors import optional
        pv = optional("pyvista", "drawing a snapshot")
        self.pv = pv
        self.pl = pv.Plotter(off_screen=True, window_size=list(window))
        self.pl.set_background("white")
        self.pl.enable_parallel_projection()
        self.window = tuple(window)

    def frame_on(self, mesh):
        """Point the camera at the contact; return (focal point, half height) for ``Frame``."""
        focal, half_h = _contact_view(mesh, self.window)
        cam = self.pl.camera
        cam.focal_point = focal
        cam.position = (focal[0], focal[1], focal[2] + 10 * half_h)
        cam.up = (0.0, 1.0, 0.0)
        cam.parallel_scale = half_h
        return focal[:2], half_h

    def draw(self, mesh, name: str, f: Field, clim, time: float):
        pl = self.pl
        pl.clear_actors()
        scal = field_values(mesh, f)
        m = mesh.copy(deep=False)
        m.point_data["_shown"] = scal
        pl.add_mesh(m, scalars="_shown", cmap=f.cmap, clim=clim, line_width=2, lighting=False,
                    scalar_bar_args={"title": f"{name} [{f.unit}]", "color": "black", "vertical": True,
                                     "position_x": 0.92, "position_y": 0.1, "height": 0.8, "width": 0.04})
        intact = mesh.extract_cells((np.asarray(mesh.cell_data["interface"]) == 1) &
                                    (np.asarray(mesh.cell_data["intact"]) == 1))
        if intact.n_cells:
            pl.add_mesh(intact, color=INTACT_RGB, line_width=4, lighting=False)
        pl.add_text(f"{name}   t = {time:.3f} l/c_r   red: intact interface bonds", position="upper_left",
                    font_size=12, color="black", name="caption")

    def close(self):
        self.pl.close()


def render_frame(run, field: str, time: float | None, png: str, *, clim=None, window=WINDOW) -> Frame:
    """Render the snapshot nearest ``time`` (l/c_r; None: the last) of ``run`` to ``png``.

    ``run`` is a ``parslip.open`` result; ``field`` one of ``FIELD_NAMES``
    (sxx, syy, sxy in rho c_r^2; vx, vy, speed in the internal velocity unit);
    ``clim`` fixes the colour limits (default: +-P99 of |value| for signed
    fields, [0, P99] for speed).  Raises ``ConfigError`` for an unknown field,
    a time outside the snapshots, or a run without snapshots.
    """
    f = field_spec(run, field)
    k = snapshot_index(run, time)
    mesh = run.snapshot(k)
    clim = tuple(clim) if clim is not None else colour_limits(field_values(mesh, f), f)
    t = float(run.snapshot_times[k])
    sc = _Scene(window)
    try:
        focal, half_h = sc.frame_on(mesh)
        sc.draw(mesh, field, f, clim, t)
        sc.pl.screenshot(png)
        from .provenance import stamp_png
        stamp_png(png, run)
        return Frame(k, t, clim, png, tuple(window), focal, half_h)
    finally:
        sc.close()


def render_movie(run, field: str, path: str, *, fps: float = 4.0, clim=None, window=WINDOW) -> int:
    """Render every snapshot of ``run`` as one frame of ``path`` (.mp4 or .gif); return the frame count.

    One colour scale for the whole series (from all snapshots, as in
    ``colour_limits``) and one camera (framed on the first snapshot), so
    frames compare.  ``fps``: frames per second of the movie.
    """
    f = field_spec(run, field)
    ext = os.path.splitext(path)[1].lower()
    if ext not in MOVIE_SUFFIXES:
        raise ConfigError(f"--movie {path!r}: unknown format {ext or '(none)'}; accepted: {', '.join(MOVIE_SUFFIXES)}")
    if not fps > 0:
        raise ConfigError(f"--fps {fps:g}: accepted: > 0 frames per second")
    n = len(run.snapshot_times)
    snapshot_index(run, None)                       # ConfigError when there are none
    from ..errors import optional
    optional("pyvista", f"writing the movie {path}")
    optional("imageio", f"writing the movie {path}")
    if ext == ".mp4":
        optional("imageio_ffmpeg", f"writing the movie {path}")
    meshes = [run.snapshot(k) for k in range(n)]
    if clim is None:
        clim = colour_limits(np.concatenate([field_values(m, f) for m in meshes]), f)
    sc = _Scene(window)
    try:
        if ext == ".gif":
            sc.pl.open_gif(path, fps=fps)
        else:
            sc.pl.open_movie(path, framerate=fps, quality=7)
        sc.frame_on(meshes[0])
        for k, m in enumerate(meshes):
            sc.draw(m, field, f, clim, float(run.snapshot_times[k]))
            sc.pl.write_frame()
    finally:
        sc.close()
    return n
