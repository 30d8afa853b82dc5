"""A scene as text: TOML in, flat ``{"section.key": value}`` out, and back.

Responsible for the one format scenes are stored in: scene files under
``run/``, the resolved scene every output file and checkpoint keeps (root
attribute ``scene``), and sweep files.  No checks here: ``scene.load``
validates against the schema.
"""
from __future__ import annotations

import sys
from typing import Any

import tomli_w

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TOMLDecodeError = tomllib.TOMLDecodeError


def flatten(tree: dict, prefix: str = "") -> dict[str, Any]:
    """Nested tables -> dotted keys: {"drive": {"v0": 1e-3}} -> {"drive.v0": 1e-3}."""
    out = {}
    for k, v in tree.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, name + "."))
        else:
            out[name] = v
    return out


def loads(text: str) -> dict[str, Any]:
    """TOML text -> flat scene dict (raises TOMLDecodeError)."""
    return flatten(tomllib.loads(text))


def load_file(path: str) -> dict[str, Any]:
    """A TOML file -> flat dict (raises OSError, TOMLDecodeError, UnicodeDecodeError)."""
    with open(path, "rb") as f:
        return flatten(tomllib.load(f))


def to_toml(scene: dict[str, Any]) -> str:
    """A flat scene as nested TOML text (stored in every output file and checkpoint)."""
    tree: dict[str, dict] = {}
    for name, value in scene.items():
        *path, key = name.split(".")
        node = tree
        for part in path:
            node = node.setdefault(part, {})
        node[key] = value
    return tomli_w.dumps(tree)
