"""Recommended fidelity settings: a quick look and publication quality.

They follow from the accuracy study (`parslip accuracy`, README "Error
against run time"), run on the push scene (32 l/c_r: its first three
nucleations) and the shear scene (76 l/c_r: its rupture), each knob against
its finest setting:

- time step: ``time.safety`` 0.9 of the stability limit moves the first break
  by <= 0.0016 l/c_r and the front speed by <= 1.2e-4 (relative) against
  0.1, at a ninth of the steps: the largest step is the right one for both.
- precision: float32 changes neither the first break nor the nucleation
  interval nor the fronts' mean speed of either scene at all (frames every
  0.25 a/c_r; slip by < 1e-5; over the whole 100 l/c_r push scene the ten
  nucleation times agree to the frame and the mean speed to 0.34 %), and
  its drive phase takes 0.83x (push) and 0.79x (shear) the CPU time of float64.
- substrate model: the rigid substrate (the k_n -> infinity limit) moves the
  first break by 1.0 % (push) and 1.2 % (shear), the slip per front by 1.8 %
  and the front speed by <= 0.7 % against the paper's k_n = 100, for a drive
  phase 10.8x (push) and 10.1x (shear) cheaper.  Elastic substrates converge to
  it as k_n grows, so the rigid one is the right model of "comparatively
  rigid" but not the paper's number: publication keeps k_n = 100.
- interface cadence: 1 a/c_r (the default, auto) measures front speeds to
  <= 1e-3 and first breaks to one frame (0.01 l/c_r); coarser frames save
  nothing worth having (the drive's cost hardly changes).
- substrate size: the paper's 300 x 20 is within 1.1 % (first break) of
  500 x 40, and 200 x 20 (the methods text) is indistinguishable from it;
  it is a geometry, not a preset key.

Each preset is a set of scene keys with the value to use; ``differences``
turns a scene into ``--set`` items that apply one (`parslip info` prints them for both).
"""
from __future__ import annotations

# Minutes become seconds: rigid substrate and float32, errors of 1-2 % in the first break and the slip.
QUICK_LOOK = {"lattice.substrate": "rigid", "time.precision": "float32", "time.safety": 0.9,
              "output.interface_dt": 0.0}
# The paper's model at the largest stable step: errors from the numerics below 0.2 % (time step, precision).
PUBLICATION = {"lattice.substrate": "elastic", "material.bottom_kn": 100.0, "time.precision": "float64",
               "time.safety": 0.9, "output.interface_dt": 0.0}


def differences(scene: dict, preset: dict) -> list[str]:
    """``--set KEY=VALUE`` items that would turn ``scene`` into ``preset`` (empty if it already is)."""
    out = []
    for key, value in preset.items():
        if scene.get(key) != value:
            out.append(f"{key}={value if not isinstance(value, str) else repr(value)[1:-1]}")
    return out
