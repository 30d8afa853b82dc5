"""Recommended fidelity settings: a quick look and publication quality.

They follow from the accuracy study (`parslip accuracy`, README "Error
against run time"): each is a set of scene keys with the value to use.
`parslip info` names the quick-look setting when a scene differs from it.
"""
from __future__ import annotations

# Provisional until the accuracy study's numbers are in the README.
QUICK_LOOK = {"lattice.substrate": "rigid", "time.precision": "float32"}
PUBLICATION = {"lattice.substrate": "elastic", "time.precision": "float64", "time.safety": 0.9}


def differences(scene: dict, preset: dict) -> list[str]:
    """``--set KEY=VALUE`` items that would turn ``scene`` into ``preset`` (empty if it already is)."""
    out = []
    for key, value in preset.items():
        if scene.get(key) != value:
            out.append(f"{key}={value if not isinstance(value, str) else repr(value)[1:-1]}")
    return out
