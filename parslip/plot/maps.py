"""A map of one observable over two swept keys of a sweep's summary table (``parslip map``).

Responsible for drawing a summary table (``analysis.table``) as a scatter
map: one marker per point at (x, y) = the values of two keys, coloured by an
observable (numeric: a colour scale, its value written beside the marker;
words: one colour per word), the marker's shape the rupture kind (o pulse,
s crack, D mixed, ^ none: the contact never slipped everywhere; x failed).  A key with words
for values (``drive.mode``) is an axis of categories; numbers spanning a
factor of 8 or more get a log axis (``scale="auto"``).  Rows may be picked
with ``where`` ({key: value}); two rows at one (x, y) are refused, naming the
keys that tell them apart.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError

KIND_MARKERS = {"pulse": "o", "crack": "s", "mixed": "D", "none": "^"}
FAILED_MARKER = "x"


def _is_num(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _axis(values: list, scale: str):
    """(positions, tick positions, tick labels or None, scale) for one axis."""
    if all(_is_num(v) and math.isfinite(v) for v in values):
        arr = np.asarray(values, float)
        if scale == "auto":
            scale = "log" if arr.min() > 0 and arr.max() / arr.min() >= 8 else "linear"
        ticks = sorted(set(arr.tolist()))
        return arr, ticks, [f"{v:g}" for v in ticks], scale
    cats = list(dict.fromkeys(str(v) for v in values))
    pos = np.array([cats.index(str(v)) for v in values], float)
    return pos, list(range(len(cats))), cats, "linear"


def select(tab: dict, where: dict) -> list[int]:
    """Row indices whose ``where`` keys hold the given values (numbers compared as numbers)."""
    n = len(tab["point"])
    keep = list(range(n))
    for k, v in where.items():
        if k not in tab:
            raise ConfigError(f"--where {k}={v!r}: no column {k!r}; accepted: one of {', '.join(tab)}")
        col = tab[k]
        keep = [i for i in keep if (_is_num(col[i]) and _is_num(v) and math.isclose(col[i], v, rel_tol=1e-9))
                or str(col[i]) == str(v)]
    if not keep:
        raise ConfigError(f"--where {where}: no row matches; accepted: values the table holds")
    return keep


def draw_map(tab: dict, x: str, y: str, color: str, png: str, *, where: dict | None = None, title: str = "",
             xscale: str = "auto", yscale: str = "auto", annotate: bool = True) -> str:
    """Draw ``color`` over (``x``, ``y``) from the table ``tab`` ({column: values}); write ``png``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for opt, k in (("--x", x), ("--y", y), ("--color", color)):
        if k not in tab:
            raise ConfigError(f"{opt} {k!r}: no such column; accepted: one of {', '.join(tab)}")
    rows = select(tab, where or {})
    seen = {}
    for i in rows:
        key = (str(tab[x][i]), str(tab[y][i]))
        if key in seen:
            other = [c for c in tab if c not in ("point", "status", "wall_s", "out", "scene", "commit", x, y)
                     and c in _swept(tab) and tab[c][i] != tab[c][seen[key]]]
            raise ConfigError(f"--x {x} --y {y}: points {tab['point'][seen[key]]} and {tab['point'][i]} are both at "
                              f"({key[0]}, {key[1]}); accepted: --where KEY=VALUE to keep one"
                              + (f" (they differ in {', '.join(other)})" if other else ""))
        seen[key] = i
    xs, xt, xl, xscale = _axis([tab[x][i] for i in rows], xscale)
    ys, yt, yl, yscale = _axis([tab[y][i] for i in rows], yscale)
    status = [str(tab["status"][i]) for i in rows]
    kinds = [str(tab.get("rupture_kind", [""] * len(tab["point"]))[i]) for i in rows]
    vals = [tab[color][i] for i in rows]
    numeric = all(_is_num(v) for v in vals)
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    if numeric:
        arr = np.asarray(vals, float)
        finite = arr[np.isfinite(arr)]
        norm = matplotlib.colors.Normalize(*(finite.min(), finite.max()) if len(finite) else (0, 1))
        cmap = matplotlib.colormaps["viridis"]
        colours = [cmap(norm(v)) if math.isfinite(v) else (0.7, 0.7, 0.7, 1) for v in arr]
    else:
        words = list(dict.fromkeys(str(v) for v in vals))
        palette = matplotlib.colormaps["tab10"]
        colours = [palette(words.index(str(v)) % 10) for v in vals]
    for j in range(len(rows)):
        failed = status[j] != "ok"
        m = FAILED_MARKER if failed else KIND_MARKERS.get(kinds[j], "D")
        ax.scatter(xs[j], ys[j], s=140, marker=m, c=[(0.5, 0.5, 0.5, 1)] if failed else [colours[j]],
                   edgecolors="k" if not failed else None, linewidths=0.6, zorder=3)
        if annotate:
            v = vals[j]
            text = "failed" if failed else (f"{v:.3g}" if _is_num(v) else str(v))
            ax.annotate(text, (xs[j], ys[j]), textcoords="offset points", xytext=(0, 10), ha="center", fontsize=7)
    if numeric:
        sm = matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap)
        fig.colorbar(sm, ax=ax, label=f"{color}")
    else:
        for w in words:
            ax.scatter([], [], marker="s", c=[palette(words.index(w) % 10)], label=f"{color} = {w}")
    for kind, m in KIND_MARKERS.items():
        ax.scatter([], [], marker=m, facecolors="none", edgecolors="k", label=f"rupture: {kind}")
    if any(s != "ok" for s in status):
        ax.scatter([], [], marker=FAILED_MARKER, c="0.5", label="failed")
    ax.set_xscale(xscale)
    ax.set_yscale(yscale)
    ax.set_xticks(xt)
    ax.set_xticklabels(xl)
    ax.set_yticks(yt)
    ax.set_yticklabels(yl)
    ax.minorticks_off()
    _pad(ax, xt, xscale, "x")
    _pad(ax, yt, yscale, "y")
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.25, 1.0), borderaxespad=0.0)
    ax.set_title(title or f"{color} over {x} and {y}", fontsize=9)
    fig.tight_layout()
    from .provenance import savefig_metadata
    source = {"scene": tab["scene"], "commit": tab["commit"]} if "scene" in tab and "commit" in tab else None
    fig.savefig(png, dpi=130, metadata=savefig_metadata("pdf" if png.endswith(".pdf") else "png", source))
    plt.close(fig)
    return png


def _swept(tab: dict) -> list[str]:
    """The swept keys' columns: those between point and status."""
    cols = list(tab)
    try:
        return cols[cols.index("point") + 1:cols.index("status")]
    except ValueError:
        return []


def _pad(ax, ticks, scale, which):
    lo, hi = min(ticks), max(ticks)
    if scale == "log":
        f = (hi / lo) ** 0.08 if hi > lo else 1.5
        lim = (lo / f, hi * f)
    else:
        d = 0.12 * (hi - lo) if hi > lo else 0.5
        lim = (lo - d, hi + d)
    (ax.set_xlim if which == "x" else ax.set_ylim)(*lim)
