"""The same bits on any x86-64 host with FMA (model.stability, docs/hpc/cluster.md).

The set-up's numbers of the shipped scenes are stored here bit for bit (float.hex), so a host that derives
another dt, wave speed or step count from the same scene fails loudly instead of drifting in the last
bits.  The libraries' CPU-dependent paths are then switched off in a subprocess (NumPy's vector code
above its baseline with NPY_DISABLE_CPU_FEATURES, OpenBLAS's kernels set to an older CPU with
OPENBLAS_CORETYPE): the set-up must not move (before omega_max was rounded, push's Lanczos value moved
from 24.45511710235529 to 24.455117102355374 under OPENBLAS_CORETYPE=Prescott).  Last, the compiled
loop built for an AVX2+FMA CPU (NUMBA_CPU_NAME=haswell) must give the default build's bits: that check rides
on the cold compile of ``tests/test_compile_once.py`` (a 3-rank job built for haswell against a 1-rank run of
the default build), which saves the suite a second compile of the loop.
"""
from __future__ import annotations

import json
import math
import subprocess
import sys

from helpers import REPO

SCENES = ("run/push.toml", "run/pull.toml", "run/shear.toml", "run/push_l1000.toml")
SPEEDS = {"c_r": "0x1.fffffffffffffp-1", "c_s": "0x1.1902da834b407p+0", "c_l": "0x1.cae3a7ebffd2ep+0",
          "kn_top": "0x1.67e079b11a654p+1", "kt_top": "0x1.12311fc3e3598p-3"}
LANCZOS = {"omega_max": "0x1.87482a0000000p+4", "dt": "0x1.2d7b9f78e8304p-4", **SPEEDS}
# (n_ramp, n_settle, n_drive, frame_every) with the floats above, computed at the commit that rounded omega_max.
STORED = {
    "run/push.toml": dict(LANCZOS, method="lanczos", steps=[679, 5434, 135862, 13]),
    "run/pull.toml": dict(LANCZOS, method="lanczos", steps=[679, 5434, 135862, 13]),
    "run/shear.toml": dict(LANCZOS, method="lanczos", steps=[679, 5434, 108690, 13]),
    "run/push_l1000.toml": dict(SPEEDS, omega_max="0x1.881d420000000p+4", dt="0x1.2cd7c85b15704p-4",
                                method="bound", steps=[6808, 54460, 1361508, 136]),
}
# random_field(240, 0.3, 5.0, 3) and random_field(50, 0.2, 1e3, 11) (model.interface): sha256 of their bytes.
RANDOM_FIELD = "9eddac9146355209"

SETUP_NUMBERS = """
import hashlib, json, sys
from parslip.model.interface import random_field
from parslip.scene.derive import derive
from parslip.scene.load import load
out = {}
for path in sys.argv[1:]:
    st = derive(load(path))
    m = st.material
    out[path] = dict(omega_max=st.omega_max.hex(), dt=st.dt.hex(), method=st.omega_method,
                     steps=[st.n_ramp, st.n_settle, st.n_drive, st.frame_every],
                     **{k: float(getattr(m, k)).hex() for k in ("c_r", "c_s", "c_l", "kn_top", "kt_top")})
fields = random_field(240, 0.3, 5.0, 3).tobytes() + random_field(50, 0.2, 1e3, 11).tobytes()
out["random_field"] = hashlib.sha256(fields).hexdigest()[:16]
print(json.dumps(out))
"""


def _setup_numbers(tmp_path, **env) -> dict:
    """The set-up numbers of SCENES and the random field's hash, derived in a fresh process with a fresh
    omega_max cache (so omega_max is computed, not read) under the extra environment ``env``."""
    import os
    run_env = dict(os.environ, PARSLIP_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(REPO), **env)
    p = subprocess.run([sys.executable, "-c", SETUP_NUMBERS, *SCENES], cwd=REPO, env=run_env,
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


def test_the_shipped_scenes_set_up_numbers_are_the_stored_bits(tmp_path):
    """omega_max, dt, the wave speeds, the stiffnesses and the step counts of push, pull, shear (Lanczos)
    and push_l1000 (the bound), bit for bit; and the random interface field's bytes."""
    got = _setup_numbers(tmp_path)
    assert got.pop("random_field") == RANDOM_FIELD
    assert got == STORED


def test_omega_max_is_rounded_up_to_24_significant_bits():
    """round_up: never below its argument, less than 2^-23 above it, 24 significant bits at most, and a
    value that already has them unchanged (so rounding twice is rounding once)."""
    import random

    from parslip.model.stability import round_up
    rng = random.Random(5)
    for x in [rng.uniform(0.1, 1e4) for _ in range(2000)] + [24.45511710235529, 2.0 ** 40, 1.5, 0.75]:
        r = round_up(x)
        assert x <= r < x * (1 + 2.0 ** -23)
        m, _ = math.frexp(r)
        assert math.ldexp(m, 24) == int(math.ldexp(m, 24))
        assert round_up(r) == r
    assert round_up(1.0 + 2.0 ** -52) == 1.0 + 2.0 ** -23


def _without_vector_paths() -> dict:
    """The environment that makes NumPy use its baseline code only and OpenBLAS its Prescott kernels (SSE3,
    every x86-64 CPU has them): what another, older CPU would run."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    off = [f for f in __cpu_dispatch__ if __cpu_features__.get(f)]
    return {"NPY_DISABLE_CPU_FEATURES": " ".join(off), "OPENBLAS_CORETYPE": "Prescott"}


def test_the_set_up_keeps_its_bits_without_the_libraries_vector_kernels(tmp_path):
    """The same numbers with NumPy's dispatched SIMD code and OpenBLAS's newer kernels switched off; the
    check that omega_max would have moved without its rounding is in the module docstring."""
    got = _setup_numbers(tmp_path, **_without_vector_paths())
    assert got.pop("random_field") == RANDOM_FIELD
    assert got == STORED
