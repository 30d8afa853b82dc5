"""A picture of the model drawn from a scene's own geometry: ``parslip draw`` and the docs' model figure.

Responsible for one schematic figure of a scene (matplotlib, Agg): the nodes and bulk bonds of both blocks
where ``model.lattice.Lattice`` puts them, the interface bonds between facing sites (one drawn broken, its
top node beyond delta_b, and one re-formed to the next substrate site), the fixed row AB, the normal load
F_N spread over the top row SR, and the three drives (T- push on the rear face SP, T+ pull on the front
face RQ, T0 shear on SR), the scene's own drive drawn solid and the two others faint.  The broken and
re-formed bonds are drawn displaced by hand to show the interface law; every other node sits at its
reference position.  Lengths in a; the picture is to scale in x and y.

    parslip draw run/push.toml -o push_scene.png
    fig = scene_picture.draw_scene({"lattice": {"top_rows": 4, "top_cols": 12}})

Scenes with many columns are drawn whole but their labels become small: a picture reads best below about
60 columns (``--set lattice.top_cols=12 --set lattice.bottom_cols=20`` draws a scene's physics small).
"""
from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from ..model.lattice import BOTTOM, DRIVEN, TOP, Lattice
from ..model.physics import ROW_HEIGHT

# The small scene of the documentation's model page: the default physics on a 4 x 12 block and a 6 x 20
# substrate.
DOCS_SCENE = {"lattice": {"top_rows": 4, "top_cols": 12, "bottom_rows": 6, "bottom_cols": 20}}

BULK = "#7f8c99"
NODE_TOP, NODE_BOTTOM = "#1f5fa8", "#5b6670"
BOND, BROKEN, REFORMED = "#d62728", "#d62728", "#2ca02c"
DRIVE, LOAD = "#e67e00", "#6a3d9a"
MODES = {"push": "$T_-$", "pull": "$T_+$", "shear": "$T_0$"}
LABEL_BOX = dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.85)     # behind a label on bonds
ARROW = dict(arrowstyle="-|>", mutation_scale=12, lw=1.6)                          # the load and drive arrows


def _lattice(s: dict) -> Lattice:
    return Lattice(s["lattice.top_rows"], s["lattice.top_cols"], s["lattice.bottom_rows"],
                   s["lattice.bottom_cols"], s["interface.delta0"], s["lattice.substrate"])


def _bulk_segments(lat: Lattice, nodes: dict) -> dict[int, np.ndarray]:
    """Each bulk bond once (slots 0..2), as segments per block: {block: (n, 2, 2)}."""
    nbr = lat.neighbour_gids(nodes)
    pos = np.full((lat.n_nodes, 2), np.nan)
    pos[nodes["gid"]] = np.column_stack([nodes["x"], nodes["y"]])
    out = {}
    for b in (BOTTOM, TOP):
        segs = []
        for k in range(3):
            m = (nodes["block"] == b) & (nbr[:, k] >= 0)
            i, j = nodes["gid"][m], nbr[m, k]
            segs.append(np.stack([pos[i], pos[j]], axis=1))
        out[b] = np.concatenate(segs) if segs else np.zeros((0, 2, 2))
    return out


@dataclass
class _Sketch:
    """What every piece of the picture reads: the axes, the scene, its lattice and nodes, and the sizes."""
    ax: object
    s: dict                     # the resolved scene
    lat: Lattice
    nodes: dict                 # every node at its reference position
    ms: float                   # marker size, points
    lw: float                   # bulk bond width, points
    fs: int                     # font size, points

    @property
    def t(self):
        return self.lat.top

    @property
    def b(self):
        return self.lat.bottom

    @property
    def y_top(self) -> float:
        return self.t.y0 + (self.t.rows - 1) * ROW_HEIGHT

    @property
    def x_left(self) -> float:
        return self.t.col0 + self.t.offset(0)

    @property
    def x_right(self) -> float:
        return self.t.col0 + self.t.cols - 1 + self.t.offset(0)

    @property
    def top_corners(self) -> tuple[float, float]:
        """x of S (top rear) and R (top front)."""
        t = self.t
        return t.col0 + t.offset(t.rows - 1), t.col0 + t.cols - 1 + t.offset(t.rows - 1)


def _new_axes(lat: Lattice, d0: float):
    """A figure sized to the lattice (about 0.55 inch per spacing, at most 16 inches of lattice)."""
    t, b = lat.top, lat.bottom
    width = lat.ncols + 6.0
    height = (b.rows - 1) * ROW_HEIGHT + d0 + (t.rows - 1) * ROW_HEIGHT + 6.0 if lat.has_interface \
        else (t.rows - 1) * ROW_HEIGHT + 6.0
    scale = min(0.55, 16.0 / width)
    from .figures import pyplot
    return pyplot().subplots(figsize=(max(width * scale, 6.0), max(height * scale, 3.0)))


def _draw_bulk(k: _Sketch) -> None:
    """Bulk bonds and nodes of the numbered blocks."""
    from matplotlib.collections import LineCollection

    segs = _bulk_segments(k.lat, k.nodes)
    for blk in (BOTTOM, TOP):
        if len(segs[blk]):
            k.ax.add_collection(LineCollection(segs[blk], colors=BULK, linewidths=k.lw, zorder=1))
    xs, ys = k.nodes["x"], k.nodes["y"]
    top = k.nodes["block"] == TOP
    k.ax.plot(xs[top], ys[top], "o", ms=k.ms, color=NODE_TOP, zorder=3, label="block nodes")
    if (~top).any():
        k.ax.plot(xs[~top], ys[~top], "o", ms=k.ms, color=NODE_BOTTOM, zorder=3, label="substrate nodes")


def _draw_broken(k: _Sketch, xt: float, xb: float, yb: float) -> None:
    """The broken bond: its top node slid forward until the bond's length passed delta_b, so the bond is
    gone.  The node is drawn hollow where it slid to; the circle of radius delta_b about its substrate site
    is the reach."""
    from matplotlib.patches import Circle

    ax, t, fs = k.ax, k.t, k.fs
    d0, db = k.s["interface.delta0"], k.s["interface.delta_b"]
    dx = float(np.sqrt(max((1.12 * db) ** 2 - d0 ** 2, 0.0)))
    tip = (xt + dx, t.y0)
    ax.plot(*tip, "o", ms=k.ms + 1, mfc="white", mec=BROKEN, mew=1.4, zorder=5)
    ax.plot([xb, tip[0]], [yb, tip[1]], ls=(0, (2, 2)), color=BROKEN, lw=1.4, zorder=4)
    ax.add_patch(Circle((xb, yb), db, fill=False, ls=":", lw=1.0, color=BROKEN, zorder=4))
    ax.annotate("broken", tip, xytext=(tip[0] + 0.3, t.y0 + 1.5 * ROW_HEIGHT), fontsize=fs,
                color=BROKEN, bbox=LABEL_BOX, zorder=6,
                arrowprops=dict(arrowstyle="-", lw=0.7, color=BROKEN))
    ang = np.deg2rad(200.0)
    ax.annotate("", (xb + db * np.cos(ang), yb + db * np.sin(ang)), (xb, yb), zorder=6,
                arrowprops=dict(arrowstyle="->", lw=0.9, color="black", shrinkA=0, shrinkB=0))
    ax.text(xb - db - 0.15, yb - 0.45, r"$\delta_b$", fontsize=fs + 1, ha="right", va="center",
            bbox=LABEL_BOX, zorder=6)


def _draw_reformed(k: _Sketch, p_top: tuple, p_bot: tuple, yb: float) -> None:
    """The re-formed bond: a node that slid one spacing forward re-bonded to the next free substrate site
    within delta0."""
    k.ax.plot([p_top[0], p_bot[0]], [p_top[1], p_bot[1]], color=REFORMED, lw=2.0 * k.lw + 0.6, zorder=2)
    k.ax.annotate("re-formed", ((p_top[0] + p_bot[0]) / 2, (p_top[1] + p_bot[1]) / 2),
                  xytext=(p_bot[0] + 0.8, yb - 1.5 * ROW_HEIGHT), fontsize=k.fs, color=REFORMED,
                  bbox=LABEL_BOX, zorder=6, arrowprops=dict(arrowstyle="-", lw=0.6, color=REFORMED))


def _draw_interface(k: _Sketch) -> None:
    """The interface bonds between facing sites (one broken, one re-formed) and the gap delta0."""
    ax, t, b, lat = k.ax, k.t, k.b, k.lat
    d0 = k.s["interface.delta0"]
    yb = t.y0 - d0                                    # the substrate's interface row DC
    cols = t.col0 + np.arange(t.cols)
    xb_row = cols + b.offset(b.rows - 1)              # bottom sites facing the block's interface row PQ
    if lat.rigid:
        ax.plot(xb_row, np.full(len(cols), yb), "s", ms=k.ms, color=NODE_BOTTOM, zorder=3,
                label="rigid substrate sites (fixed)")
    xt = cols + t.offset(0)
    n = t.cols
    broken = n // 2 if n >= 4 else None               # one broken bond in the middle of the contact
    reformed = broken + 2 if broken is not None and broken + 2 < n - 1 else None
    for i in range(n):
        if i in (broken, reformed):
            continue
        ax.plot([xt[i], xb_row[i]], [t.y0, yb], color=BOND, lw=2.0 * k.lw + 0.4, zorder=2)
    ax.plot([], [], color=BOND, lw=2, label="interface bonds ($k_x$, $k_y$)")
    if broken is not None:
        _draw_broken(k, xt[broken], xb_row[broken], yb)
    if reformed is not None:
        _draw_reformed(k, (xt[reformed], t.y0), (xb_row[reformed + 1], yb), yb)
    # delta0: the gap at the rear edge's first bond.
    xg = xt[0] - 0.9
    ax.annotate("", (xg, t.y0), (xg, yb), arrowprops=dict(arrowstyle="<->", lw=0.8, shrinkA=0, shrinkB=0))
    ax.text(xg - 0.2, (t.y0 + yb) / 2, r"$\delta_0$", fontsize=k.fs + 1, ha="right", va="center",
            bbox=LABEL_BOX, zorder=6)
    _draw_fixed_row(k, yb, xb_row)


def _draw_fixed_row(k: _Sketch, yb: float, xb_row) -> None:
    """The fixed row AB (elastic substrate) or the fixed sites (rigid): hatching below them, and the
    substrate's corners A, B, D, C."""
    ax, b, fs, rigid = k.ax, k.b, k.fs, k.lat.rigid
    y_ab = 0.0 if not rigid else yb
    x0_ab = 0.0 if not rigid else xb_row[0]
    x1_ab = (b.cols - 1 + b.offset(0)) if not rigid else xb_row[-1]
    ax.plot([x0_ab - 0.3, x1_ab + 0.3], [y_ab - 0.25, y_ab - 0.25], color="black", lw=1.2)
    for xh in np.arange(x0_ab - 0.3, x1_ab + 0.3, 0.6):
        ax.plot([xh, xh - 0.3], [y_ab - 0.25, y_ab - 0.55], color="black", lw=0.7)
    ax.text((x0_ab + x1_ab) / 2, y_ab - 0.75, "fixed sites" if rigid else "AB fixed", fontsize=fs,
            ha="center", va="top")
    if not rigid:
        ax.text(x0_ab - 0.6, y_ab, "A", fontsize=fs, ha="right", va="center")
        ax.text(x1_ab + 0.6, y_ab, "B", fontsize=fs, ha="left", va="center")
        xd, xc = b.offset(b.rows - 1), b.cols - 1 + b.offset(b.rows - 1)
        ax.text(xd - 0.5, yb, "D", fontsize=fs, ha="right", va="center")
        ax.text(xc + 0.5, yb, "C", fontsize=fs, ha="left", va="center")


def _draw_corners_and_load(k: _Sketch) -> None:
    """The block's corners (S top rear, R top front, P bottom rear, Q bottom front) and F_N spread over
    SR, pointing down."""
    from matplotlib.patches import FancyArrowPatch

    ax, t, fs, y_top = k.ax, k.t, k.fs, k.y_top
    xs_top, xr_top = k.top_corners
    for name, (x, y, ha) in {"S": (xs_top - 0.35, y_top + 0.3, "right"), "R": (xr_top + 0.35, y_top + 0.3, "left"),
                             "P": (k.x_left - 0.35, t.y0 - 0.25, "right"),
                             "Q": (k.x_right + 0.35, t.y0 - 0.25, "left")}.items():
        ax.text(x, y, name, fontsize=fs, ha=ha, va="center", fontweight="bold")
    top_row = (k.nodes["block"] == TOP) & (k.nodes["row"] == t.rows - 1)
    for x in k.nodes["x"][top_row][:: max(1, int(top_row.sum()) // 12)]:
        ax.add_patch(FancyArrowPatch((x, y_top + 1.6), (x, y_top + 0.25), color=LOAD,
                                     **{**ARROW, "lw": 1.0, "mutation_scale": 8}))
    ax.text(xs_top + 0.5 * (xr_top - xs_top), y_top + 1.75, r"$F_N$ on SR", color=LOAD, fontsize=fs + 1,
            ha="center", va="bottom")


def _drive_span(t) -> float:
    """Length of a drive arrow, in a."""
    return max(2.0, 0.12 * t.cols)


def _draw_drives(k: _Sketch) -> None:
    """The drives: x of the driven nodes follows x_eq + v0 t.  The scene's own drive solid, the others
    faint, and its driven nodes ringed."""
    from matplotlib.patches import FancyArrowPatch

    ax, t, y_top, mode = k.ax, k.t, k.y_top, k.s["drive.mode"]
    y_mid = t.y0 + 0.5 * (t.rows - 1) * ROW_HEIGHT
    span = _drive_span(t)
    xr_top = k.top_corners[1]
    drives = {"push": ((k.x_left - 1.0 - span, y_mid), (k.x_left - 0.6, y_mid), "$T_-$ push on SP"),
              "pull": ((k.x_right + 0.6, y_mid), (k.x_right + 1.0 + span, y_mid), "$T_+$ pull on RQ"),
              "shear": ((xr_top - span - 0.5, y_top + 2.9), (xr_top + 0.5, y_top + 2.9), "$T_0$ shear on SR")}
    for m, (p0, p1, label) in drives.items():
        own = m == mode
        ax.add_patch(FancyArrowPatch(p0, p1, color=DRIVE, alpha=1.0 if own else 0.35,
                                     **{**ARROW, "lw": 2.4 if own else 1.4}))
        tx, ty = (p0[0] + p1[0]) / 2, p0[1] + (0.35 if m == "shear" else 0.45)
        ax.text(tx, ty, label + (" (this scene)" if own else ""), color=DRIVE, alpha=1.0 if own else 0.6,
                fontsize=k.fs, ha="center", va="bottom", fontweight="bold" if own else "normal")
    if mode in MODES:
        kind = k.lat.kinds(k.nodes, mode, k.s["drive.rows"] or None)
        d = kind == DRIVEN
        ax.plot(k.nodes["x"][d], k.nodes["y"][d], "o", ms=k.ms + 3, mfc="none", mec=DRIVE, mew=1.2, zorder=4,
                label="driven nodes")


def _frame(k: _Sketch) -> None:
    """Legend, limits and the title naming the lattice and the interface gaps."""
    ax, t, b, lat, fs = k.ax, k.t, k.b, k.lat, k.fs
    d0, db = k.s["interface.delta0"], k.s["interface.delta_b"]
    xs, ys = k.nodes["x"], k.nodes["y"]
    span = _drive_span(t)
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.02), ncol=3, fontsize=fs - 1, frameon=False)
    ax.autoscale_view()
    x_lo, x_hi = min(xs.min(), k.x_left - 1.5 - span), max(xs.max(), k.x_right + 1.5 + span)
    y_lo = (-1.4 if lat.has_interface else ys.min() - 1.0)
    ax.set_xlim(x_lo - 0.5, x_hi + 0.5)
    ax.set_ylim(y_lo, k.y_top + 4.0)
    below = (f"substrate {b.rows} x {b.cols}" if lat.has_interface and not lat.rigid
             else "a rigid substrate" if lat.rigid else "no substrate")
    ax.set_title(f"top block {t.rows} x {t.cols} on " + below
                 + rf"; $\delta_0$ = {d0:g} a, $\delta_b$ = {db:g} a", fontsize=fs)


def draw_scene(scene, sets=None, ax=None):
    """Draw the model of ``scene`` (a TOML path or a mapping of scene keys, as ``parslip.run`` takes,
    with ``sets`` overrides) on ``ax`` (default: a new figure sized to the lattice); return the figure.

    Raises ``ConfigError`` for a scene the loader refuses (the same one line as ``parslip run``).
    """
    from ..scene.load import load

    s = load(scene, sets)
    lat = _lattice(s)
    if ax is None:
        fig, ax = _new_axes(lat, s["interface.delta0"])
    else:
        fig = ax.figure
    ax.set_aspect("equal")
    ax.axis("off")
    ms = float(np.clip(120.0 / max(lat.ncols, 1), 1.0, 6.0))
    k = _Sketch(ax, s, lat, lat.nodes_in_columns(0, lat.ncols), ms, ms / 4.0, 10 if lat.ncols <= 60 else 7)
    _draw_bulk(k)
    if lat.has_interface:
        _draw_interface(k)
    _draw_corners_and_load(k)
    _draw_drives(k)
    _frame(k)
    fig.tight_layout()
    return fig


def scene_png(scene, sets=None, dpi: int = 130) -> bytes:
    """The picture of ``scene`` as PNG bytes (the docs build writes these into the site)."""
    from .figures import pyplot

    plt = pyplot()
    fig = draw_scene(scene, sets)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return buf.getvalue()


def write_scene_picture(scene, path, sets=None, dpi: int = 130) -> str:
    """Write the picture of ``scene`` to ``path`` (PNG, or any format matplotlib knows by suffix)."""
    import os

    from ..errors import ConfigError
    from .figures import pyplot

    plt = pyplot()
    fig = draw_scene(scene, sets)
    try:
        fig.savefig(path, dpi=dpi)
    except (OSError, ValueError) as e:
        raise ConfigError(f"-o {path}: cannot write the picture ({e}); accepted: a writable path ending in "
                          ".png, .pdf or .svg") from None
    finally:
        plt.close(fig)
    return os.fspath(path)
