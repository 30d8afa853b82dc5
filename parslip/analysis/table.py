"""A sweep's summary table: its columns, and the CSV and netCDF files that hold it.

Responsible for the table ``parslip sweep`` writes (``studies.sweep``) and
``parslip map`` reads: one row per point, these columns in this order:

  point                 the point's name (p000, p001, ...: its index in the sweep file's order)
  <swept keys>          one per key of the sweep file's [grid] and [zip], named by the key
                        (``drive.mode``, ``load.FN``), holding bare values
  status                "ok", "failed: REASON", or "pending" (not run yet, or interrupted)
  the observables       ``analysis.friction.observables`` (first_break_time, first_break_x, mu_s,
                        its time and place, the slip onset, the fronts by kind and fate, precursor arrest
                        lengths, mean speeds, slip per event; units in ``friction.UNITS``)
  wall_s                wall-clock seconds the point's run took (every attempt added up)
  out                   the point's output file
  scene                 the resolved scene as one line of JSON (dotted keys)
  commit                the git commit of the parslip that ran it (the output file's provenance)

Files: ``summary.csv`` (any tool; NaN and missing words are empty cells) and
``summary.nc``, netCDF4 with one dimension ``point`` and one typed variable per
column (float64 with NaN, int64, or strings; units and descriptions as
attributes), written with h5netcdf (the ``sweep`` extra).  pandas reads the
CSV (``pandas.read_csv``) and, through xarray, the netCDF
(``xarray.open_dataset(path).to_dataframe()``).
"""
from __future__ import annotations

import csv
import math
import os

from ..errors import ConfigError, OptionalPartMissing
from .friction import UNITS

OBSERVABLES = ("first_break_time", "first_break_x", "mu_s", "mu_s_time", "mu_s_after_first_break", "mu_s_place",
               "mu_s_window", "slip_onset_time", "mu_first_break", "F_s", "mu_sliding", "rupture_kind", "n_fronts",
               "n_pulse", "n_crack", "n_crossed", "n_precursors", "n_running", "n_merged", "precursor_arrest_mean",
               "precursor_arrest_max", "front_speed", "front_speed_mean", "slip_per_event")
TAIL = ("wall_s", "out", "scene", "commit")
INTEGER = {"n_fronts", "n_pulse", "n_crack", "n_crossed", "n_precursors", "n_running", "n_merged"}
WORDS = {"point", "status", "mu_s_place", "mu_s_window", "rupture_kind", "out", "scene", "commit"}
DESCRIPTIONS = {
    "point": "the point's name: p + its index in the sweep file's order",
    "status": "ok, failed: REASON, or pending",
    "first_break_time": "first time any interface bond is broken, from the drive's start",
    "first_break_x": "x of the first broken bond (the rearmost if several broke at once)",
    "mu_s": "static peak: max of -F_T/F_N up to the slip onset (over the record if none: a lower bound)",
    "mu_s_time": "time of the static peak",
    "mu_s_after_first_break": "mu_s_time - first_break_time",
    "mu_s_place": "the peak before, at (within a frame) or after the first break",
    "mu_s_window": "slip onset: the peak of a contact that slipped everywhere; record: a lower bound",
    "slip_onset_time": "first time by which every interface bond (but 2 % at each end) broke at least once",
    "mu_first_break": "mu at the first break",
    "F_s": "static friction force mu_s F_N",
    "mu_sliding": "mean mu after the slip onset",
    "rupture_kind": "kind of the first front that crossed the contact (pulse, crack); else of the fronts up to the "
                    "slip onset (mixed if they differ); none if the contact never slipped everywhere",
    "n_fronts": "rupture fronts detected", "n_pulse": "fronts that were pulses", "n_crack": "fronts that were cracks",
    "n_crossed": "fronts that crossed the contact edge to edge (by their own tip, or relayed from an edge)",
    "n_precursors": "fronts that arrested inside it",
    "n_running": "fronts still moving at the record's end",
    "n_merged": "fronts that ran into another front's broken zone",
    "precursor_arrest_mean": "mean arrest length of the precursors", "precursor_arrest_max": "largest one",
    "front_speed": "|mean speed| of the first front that crossed the contact",
    "front_speed_mean": "mean |mean speed| of all fronts",
    "slip_per_event": "mean over the fronts of the slip each carries",
    "wall_s": "wall-clock time of the point's run, every attempt added up",
    "out": "the point's output file", "scene": "the resolved scene, JSON", "commit": "git commit that ran it",
}


def columns(swept: list[str]) -> list[str]:
    """The table's columns for a sweep over ``swept`` keys."""
    return ["point", *swept, "status", *OBSERVABLES, *TAIL]


def units(name: str) -> str:
    return UNITS.get(name, "s" if name == "wall_s" else "-")


def _cell(v) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(float(v))           # numpy 2's repr of an np.float64 is "np.float64(...)"
    return str(v)


def _atomic(path: str, write) -> None:
    tmp = f"{path}.tmp{os.getpid()}"
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def write_csv(path: str, cols: list[str], rows: list[dict]) -> None:
    """The table as CSV (header = column names); written whole to a temporary file, then renamed."""
    def write(tmp):
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            for r in rows:
                w.writerow([_cell(r.get(c)) for c in cols])
    _atomic(path, write)


def markdown(rows: list[dict], cols: list[str], formats: dict | None = None) -> str:
    """The rows as a Markdown table of ``cols``: floats with ``formats[col]`` (default 3 significant
    digits), NaN as "-", anything else as its text."""
    formats = formats or {}
    out = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    for r in rows:
        cells = []
        for c in cols:
            v = r[c]
            if isinstance(v, float):
                cells.append("-" if math.isnan(v) else formats.get(c, "{:.3g}").format(v))
            else:
                cells.append(str(v))
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def _kind(values: list) -> str:
    """The netCDF type of a column: "i8", "f8" or "str"."""
    present = [v for v in values if v is not None and not (isinstance(v, float) and math.isnan(v))]
    if present and all(isinstance(v, bool) for v in present):
        return "str"
    if present and all(isinstance(v, int) and not isinstance(v, bool) for v in present) and len(present) == len(values):
        return "i8"
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return "f8"
    return "str"


def require_netcdf():
    """h5netcdf, or one line naming the extra to install (exit 2)."""
    try:
        import h5netcdf
    except ImportError:
        raise OptionalPartMissing("summary.nc: writing it needs h5netcdf, which is not installed; accepted: "
                                  "python -m pip install 'parslip[sweep]'") from None
    return h5netcdf


def write_netcdf(path: str, cols: list[str], rows: list[dict], attrs: dict | None = None) -> None:
    """The table as netCDF4: dimension ``point``, one typed variable per column (``_kind``)."""
    import h5py
    import numpy as np
    h5netcdf = require_netcdf()

    def write(tmp):
        with h5netcdf.File(tmp, "w") as f:
            f.dimensions["point"] = len(rows)
            for k, v in (attrs or {}).items():
                f.attrs[k] = v
            for c in cols:
                values = [r.get(c) for r in rows]
                kind = "str" if c in WORDS else "i8" if c in INTEGER else _kind(values)
                if kind == "str":
                    var = f.create_variable(c, ("point",), dtype=h5py.string_dtype())
                    var[:] = np.array([_cell(v) for v in values], dtype=object)
                elif kind == "i8":
                    var = f.create_variable(c, ("point",), dtype="i8", fillvalue=-1)
                    var[:] = np.array([(-1 if v is None else int(v)) for v in values], dtype=np.int64)
                else:
                    var = f.create_variable(c, ("point",), dtype="f8", fillvalue=np.nan)
                    var[:] = np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64)
                var.attrs["units"] = units(c)
                if c in DESCRIPTIONS:
                    var.attrs["long_name"] = DESCRIPTIONS[c]
    _atomic(path, write)


# --- reading --------------------------------------------------------------------------------------

def _number(text: str):
    if text == "":
        return math.nan
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    if text in ("true", "false"):
        return text == "true"
    return text


def read_rows(path: str) -> list[dict]:
    """A table this package wrote (``write_csv``: a study's CSV, a sweep's summary) as a list of rows, numbers
    typed as ``read`` types them (the columns of ``WORDS`` kept as text)."""
    with open(path, newline="") as fh:
        return [{c: (v if c in WORDS else _number(v)) for c, v in r.items()} for r in csv.DictReader(fh)]


def read(path: str) -> dict[str, list]:
    """A summary table (CSV, or netCDF through xarray) as {column: list of values}; numbers typed.

    Raises ``ConfigError`` naming the path if it is not such a table, and ``OptionalPartMissing`` naming
    the extra when a netCDF table needs xarray and it is not installed.
    """
    accepted = "a sweep's summary.csv or summary.nc (parslip sweep)"
    if not os.path.isfile(path):
        raise ConfigError(f"TABLE {path!r}: no such file; accepted: {accepted}")
    if path.endswith(".nc"):
        try:
            import xarray
        except ImportError:
            raise OptionalPartMissing(f"TABLE {path!r}: reading netCDF needs xarray and h5netcdf, not installed; "
                                      f"accepted: python -m pip install 'parslip[sweep]', or the summary.csv "
                                      f"beside it") from None
        try:
            ds = xarray.open_dataset(path, engine="h5netcdf")
        except (OSError, ValueError) as e:
            raise ConfigError(f"TABLE {path!r}: not a netCDF table ({e}); accepted: {accepted}") from None
        with ds:
            out = {}
            for name in ds.variables:
                values = ds[name].values.tolist()
                out[str(name)] = [_number(v) if isinstance(v, str) and str(name) not in WORDS else v
                                  for v in values]
        if "point" not in out:
            raise ConfigError(f"TABLE {path!r}: no column 'point'; accepted: {accepted}")
        return out
    try:
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(f"TABLE {path!r}: cannot read ({e}); accepted: {accepted}") from None
    if not rows or "point" not in rows[0] or "status" not in rows[0]:
        raise ConfigError(f"TABLE {path!r}: no header with 'point' and 'status'; accepted: {accepted}")
    head = rows[0]
    out = {c: [] for c in head}
    for r in rows[1:]:
        for c, v in zip(head, r):
            out[c].append(v if c in WORDS else _number(v))
    return out
