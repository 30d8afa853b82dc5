"""The ``draw`` subcommand: a picture of a scene's model, drawn from its own geometry.

    parslip draw run/push.toml -o push_scene.png
    parslip draw run/shear.toml --set lattice.top_cols=12 --set lattice.bottom_cols=20 -o shear_small.png

Bad input (a missing or invalid scene, an unwritable output) exits 2 with one line, as ``parslip run``.
"""
from __future__ import annotations

import os


def register(sub) -> None:
    """Add this module's subcommand to the ``parslip`` parser."""
    d = sub.add_parser("draw", help="draw a scene's model (nodes, bonds, interface, fixed row, load, drives) as a "
                       "picture", description="A schematic picture of SCENE drawn from the lattice it builds: "
                       "block and substrate nodes and bulk bonds, the interface bonds (one drawn broken, one "
                       "re-formed), the fixed row AB, F_N on SR and the drives T-, T+, T0 (the scene's own "
                       "solid).  Reads best below about 60 columns: draw a large scene's physics small with "
                       "--set lattice.top_cols=12 --set lattice.bottom_cols=20.")
    d.add_argument("scene", metavar="SCENE", help="TOML scene file, e.g. run/push.toml")
    d.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a scene key; the value is a TOML literal")
    d.add_argument("-o", "--out", metavar="PNG",
                   help="picture to write: .png, .pdf or .svg (default: SCENE's name + _scene.png in the "
                        "current directory)")
    d.add_argument("--dpi", type=int, default=130, help="resolution of a PNG (default 130)")
    d.set_defaults(func=cmd_draw)


def cmd_draw(args) -> int:
    from ..plot.scene_picture import write_scene_picture
    from ..errors import ConfigError

    if not os.path.isfile(args.scene):
        raise ConfigError(f"scene {args.scene}: no such file; accepted: a TOML scene file (e.g. run/push.toml)")
    if args.dpi <= 0:
        raise ConfigError(f"--dpi {args.dpi}: accepted: > 0")
    out = args.out or os.path.splitext(os.path.basename(args.scene))[0] + "_scene.png"
    print(write_scene_picture(args.scene, out, sets=args.set, dpi=args.dpi))
    return 0
