"""Reading a scene: TOML file, then ``--set key=value`` overrides, then checks.

``resolve`` turns the file plus overrides into a flat, validated dict; any
bad value raises ``ConfigError`` with one line naming the key, the value and
what is accepted.  The CLI turns that into exit code 2.
"""
from __future__ import annotations

from typing import Any

from ..errors import ConfigError
from ..io import scenefile
from ..model.interface import check_nucleation, check_patches
from ..model.physics import max_nu
from . import limits
from .schema import SCHEMA


def load(scene, sets=None) -> dict[str, Any]:
    """The one scene loader: a scene, then overrides, then every check; a flat, validated dict.

    ``scene`` is a TOML file path or a mapping (flat ``{"drive.v0": 1e-3}`` or nested
    ``{"drive": {"v0": 1e-3}}``); ``sets`` is a mapping ``{key: value}`` or a list of ``"KEY=VALUE"``
    strings (values as TOML literals, as ``--set`` takes them).  Raises ``ConfigError`` naming the key,
    the value and what is accepted.
    """
    import os
    if isinstance(scene, (str, os.PathLike)):
        raw = load_scene_file(os.fspath(scene))
    elif isinstance(scene, dict):
        raw = scenefile.flatten(scene)
    else:
        raise ConfigError(f"scene {scene!r}: accepted: a TOML file path or a mapping of scene keys")
    return resolve(raw, overrides(sets))


def overrides(sets) -> list[tuple[str, Any]]:
    """``{key: value}`` or ``["KEY=VALUE", ...]`` (or None) as a list of (key, value)."""
    if not sets:
        return []
    if isinstance(sets, dict):
        return [(str(k), v) for k, v in sets.items()]
    if isinstance(sets, str):
        sets = [sets]
    return [parse_set(s) for s in sets]


def _typed(name: str, value: Any) -> Any:
    key = SCHEMA[name]
    if key.kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, key.kind) or (key.kind is int and isinstance(value, bool)):
        kind = {float: "a number", int: "an integer", str: "a string", bool: "true or false",
                list: "an array"}[key.kind]
        raise ConfigError(f"{name} = {value!r}: expected {kind}"
                          f"{'' if key.units == '-' else f' in {key.units}'}; accepted: {key.accepted}")
    return value


def parse_set(item: str) -> tuple[str, Any]:
    """Parse one ``--set key=value``; the value is a TOML literal."""
    if "=" not in item:
        raise ConfigError(f"--set {item!r}: expected key=value, e.g. drive.v0=1e-3")
    name, text = (s.strip() for s in item.split("=", 1))
    try:
        value = scenefile.loads(f"v = {text}")["v"]
    except scenefile.TOMLDecodeError:
        # Python spellings TOML refuses (.01, 5.), then a bare word as a string: drive.mode=pull
        try:
            value = float(text)
        except ValueError:
            value = text
    return name, value


def load_scene_file(path: str) -> dict[str, Any]:
    try:
        return scenefile.load_file(path)
    except FileNotFoundError:
        raise ConfigError(f"scene {path!r}: no such file; accepted: a TOML scene such as run/push.toml") from None
    except IsADirectoryError:
        raise ConfigError(f"scene {path!r}: is a directory; accepted: a TOML scene file") from None
    except scenefile.TOMLDecodeError as e:
        raise ConfigError(f"scene {path!r}: malformed TOML ({e}); accepted: a TOML scene file") from None
    except UnicodeDecodeError:
        raise ConfigError(f"scene {path!r}: not UTF-8 text; accepted: a TOML scene file") from None


def load_scene_text(text: str) -> dict[str, Any]:
    """A scene stored as TOML text (output files and checkpoints keep the resolved scene), flattened."""
    return scenefile.loads(text)


def resolve(raw: dict[str, Any], overrides: list[tuple[str, Any]] = ()) -> dict[str, Any]:
    """Defaults, then the scene, then overrides; every value checked."""
    flat = dict(raw)
    for name, value in overrides:
        flat[name] = value
    scene = {}
    for name, value in flat.items():
        if name not in SCHEMA:
            near = [k for k in SCHEMA if k.split(".")[-1] == name.split(".")[-1]]
            hint = f" (did you mean {near[0]}?)" if near else ""
            raise ConfigError(f"{name} = {value!r}: unknown key{hint}; accepted keys: "
                              + ", ".join(SCHEMA))
        scene[name] = _typed(name, value)
    for name, key in SCHEMA.items():
        scene.setdefault(name, key.default)
        if not key.check(scene[name]):
            unit = "" if key.units == "-" else f" (in {key.units})"
            raise ConfigError(f"{name} = {scene[name]!r}: out of range{unit}; accepted: {key.accepted}")
    _cross_checks(scene)
    return scene


def _check_rows(s: dict[str, Any]) -> None:
    rows = s["drive.rows"]
    if not rows:
        return
    n = s["lattice.top_rows"]
    accepted = f"accepted: [] (every row) or [first, last] with 0 <= first <= last < lattice.top_rows = {n}"
    if s["drive.mode"] not in ("push", "pull"):
        raise ConfigError(f"drive.rows = {rows!r}: only a push or a pull acts on chosen rows (drive.mode = "
                          f"{s['drive.mode']!r} drives the whole top row SR); {accepted}, with drive.mode push or pull")
    if not (len(rows) == 2 and all(isinstance(v, int) and not isinstance(v, bool) for v in rows)
            and 0 <= rows[0] <= rows[1] < n):
        raise ConfigError(f"drive.rows = {rows!r}: out of range; {accepted}")


def _check_friction(s: dict[str, Any]) -> None:
    mu = s["interface.contact_friction"]
    if mu > 0 and not s["interface.contact"] > 0:
        raise ConfigError(f"interface.contact_friction = {mu!r}: friction needs the contact's normal force, and "
                          f"interface.contact = {s['interface.contact']!r}; accepted: 0, or any mu >= 0 with "
                          f"interface.contact > 0")


def _cross_checks(s: dict[str, Any]) -> None:
    if s["interface.delta_b"] <= s["interface.delta0"]:
        raise ConfigError(f"interface.delta_b = {s['interface.delta_b']!r}: must exceed interface.delta0 = "
                          f"{s['interface.delta0']!r}; accepted: delta_b > delta0 (in a)")
    check_patches(s["interface.patch"], s["interface.delta0"])
    check_nucleation(s)
    _check_rows(s)
    _check_friction(s)
    nu_hi = max_nu(s["material.model"])
    if s["material.nu"] > nu_hi:
        raise ConfigError(f"material.nu = {s['material.nu']!r}: gives k_t < 0 in {s['material.model']}; "
                          f"accepted: -1 < nu <= {nu_hi:.4g}")
    if s["lattice.bottom_rows"] and s["lattice.bottom_cols"] < s["lattice.top_cols"] or (
            s["lattice.bottom_rows"] and (s["lattice.bottom_cols"] - s["lattice.top_cols"]) % 2):
        raise ConfigError(f"lattice.bottom_cols = {s['lattice.bottom_cols']!r}: the top block (top_cols = "
                          f"{s['lattice.top_cols']}) must centre on it; accepted: >= top_cols with the same parity")
    limits.check_scene(s)
