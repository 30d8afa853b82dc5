"""Material constants of the Born lattice and the units of the model.

Responsible for every number that follows from the scene's material keys:
the Born stiffnesses from the wave speeds (paper Eq. 2.2), the wave speeds
back from the stiffnesses, the classical Rayleigh speed used to normalise
results, and the lattice's own surface-wave speed.

Units: lattice spacing a = 1, node mass m = 1, and velocities in units of
c_ref, which is the top block's Rayleigh speed c_r (default, the paper's
Sec. 2 normalisation) or its shear speed c_s (``material.velocity_unit =
"c_s"``).  Time is then in a/c_ref and
stiffness in m c_ref^2 / a^2.  The mass density of the triangular lattice is
rho = m / (sqrt(3)/2 a^2) = 2/sqrt(3).
"""
from __future__ import annotations

import functools

import math
from dataclasses import dataclass

import numpy as np

ROW_HEIGHT = math.sqrt(3.0) / 2.0          # y spacing of lattice rows, in a
CELL_AREA = ROW_HEIGHT                     # area per node, in a^2
DENSITY = 1.0 / CELL_AREA                  # rho, in m/a^2


def cl_over_cs(nu: float, model: str) -> float:
    """Ratio c_l/c_s for Poisson ratio ``nu``.

    plane strain: c_l/c_s = sqrt(2(1-nu)/(1-2nu));
    plane stress: c_l/c_s = sqrt(2/(1-nu)).
    """
    if model == "plane_strain":
        return math.sqrt(2.0 * (1.0 - nu) / (1.0 - 2.0 * nu))
    if model == "plane_stress":
        return math.sqrt(2.0 / (1.0 - nu))
    raise ValueError(model)


def max_nu(model: str) -> float:
    """Largest Poisson ratio with k_t >= 0, i.e. c_l^2 <= 3 c_s^2."""
    return 0.25 if model == "plane_strain" else 1.0 / 3.0


def born_stiffness(c_l: float, c_s: float, a: float = 1.0) -> tuple[float, float]:
    """Eq. 2.2: k_n = (c_l^2 - c_s^2/3)/a^2, k_t = (c_s^2 - c_l^2/3)/a^2 (m=1).  Squares as products, not
    libm's pow, which is not correctly rounded."""
    return (c_l * c_l - c_s * c_s / 3.0) / (a * a), (c_s * c_s - c_l * c_l / 3.0) / (a * a)


def born_wave_speeds(kn: float, kt: float, a: float = 1.0) -> tuple[float, float]:
    """Inverse of Eq. 2.2: c_l^2 = a^2 (9k_n + 3k_t)/8, c_s^2 = a^2 (3k_n + 9k_t)/8."""
    return math.sqrt(a * a * (9 * kn + 3 * kt) / 8), math.sqrt(a * a * (3 * kn + 9 * kt) / 8)


def _surface_det(xi: float, r: float, eta_frac: float) -> float:
    """Free-surface determinant for a plane surface wave at speed xi*c_s.

    The Born lattice's continuum limit has the bulk equations of isotropic
    elasticity but a stress with an antisymmetric part,
    sigma = lambda' tr(eps) I + 2 mu' eps + 2 eta omega, with (per rho)
    lambda' = 3/8 (k_n - k_t), mu' = 3/8 (k_n + k_t), eta = 3/4 k_t and
    mu' + eta = c_s^2.  eta_frac = eta / (rho c_s^2); eta_frac = 0 gives the
    classical Rayleigh equation.
    """
    c_s2, c_l2 = 1.0, r * r
    mu = c_s2 - eta_frac
    lam = c_l2 - 2.0 * mu
    qp = math.sqrt(1.0 - xi * xi / c_l2)
    qs = math.sqrt(1.0 - xi * xi)
    # Modes u ~ U exp(ik(x - ct) + q k y); d/dx -> i, d/dy -> q.
    # P: U = (i, qp);  S: U = (qs, -i).  Rows: traction sigma_xy, sigma_yy:
    #   M = [[i p, s], [t, i v]],  det M = -(p v + s t), real.
    # Written out rather than LAPACK's complex LU (np.linalg.det), whose last bits depend on the CPU's
    # vector kernels: + - * / and sqrt in a fixed order give the same root on every host.
    p = (mu + eta_frac) * qp + (mu - eta_frac) * qp            # sigma_xy of P, over i
    t = (lam + 2 * mu) * qp * qp - lam                          # sigma_yy of P
    s = (mu + eta_frac) * qs * qs + (mu - eta_frac)             # sigma_xy of S
    v = lam * qs - (lam + 2 * mu) * qs                          # sigma_yy of S, over i
    return -(p * v) - s * t


def _bisect(f, a: float, b: float) -> float:
    """The root of f in [a, b] (a sign change) by bisection, to the last bit of a double.

    Bisection rather than SciPy's Brent: it needs no SciPy at start-up, and
    halving until the interval stops shrinking leaves one exact answer.
    """
    fa = f(a)
    while True:
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            return m
        fm = f(m)
        if fm == 0.0:
            return m
        if (fm < 0) == (fa < 0):
            a, fa = m, fm
        else:
            b = m


@functools.lru_cache(maxsize=256)
def _surface_root(r: float, eta_frac: float) -> float:
    """The surface-wave root (about 10 ms: 400 determinants); kept per (r, eta_frac), as every scene
    load asks for the same few (a sweep loads each point's scene several times)."""
    f = lambda xi: _surface_det(xi, r, eta_frac)  # noqa: E731
    xs = np.linspace(0.5, 1.0 - 1e-9, 400)
    vals = [f(x) for x in xs]
    for i in range(len(xs) - 1):
        if vals[i] == 0.0 or np.sign(vals[i]) != np.sign(vals[i + 1]):
            return _bisect(f, xs[i], xs[i + 1])
    raise ValueError("no surface-wave root below c_s")


def rayleigh_ratio(r: float) -> float:
    """Classical Rayleigh speed c_r/c_s for c_l/c_s = r (about 0.911 at r^2 = 8/3)."""
    return _surface_root(r, 0.0)


def born_surface_ratio(kn: float, kt: float) -> float:
    """Surface-wave speed of the Born lattice's own continuum limit, in c_s.

    Its k_t term resists rigid rotation, which stiffens the free surface:
    about 0.947 c_s at nu = 0.2 in plane strain instead of 0.911.
    """
    _, c_s = born_wave_speeds(kn, kt)
    c_l, _ = born_wave_speeds(kn, kt)
    eta_frac = 0.75 * kt / (c_s * c_s)
    return _surface_root(c_l / c_s, eta_frac)


@dataclass(frozen=True)
class Material:
    """Derived constants of a scene, all in internal units (a = m = c_ref = 1)."""

    nu: float
    model: str
    velocity_unit: str
    c_s: float
    c_l: float
    c_r: float
    c_surface_born: float
    kn_top: float
    kt_top: float
    kn_bottom: float
    kt_bottom: float

    @classmethod
    def from_scene(cls, nu: float, model: str, velocity_unit: str,
                   kn_bottom: float, kt_bottom: float, kn_spring: str = "along") -> "Material":
        """``kn_spring`` 'along' (Eq. 2.1) or 'across' (the text near Fig. 1): with 'across' the k_n and
        k_t of Eq. 2.2 (and the substrate's) go to the other spring, so ``kn_*`` (the lattice's stretch
        stiffness) gets k_t's value and ``kt_*`` gets k_n's.  c_s, c_l, c_r stay those of nu: the units
        the paper reports in, which that lattice then no longer has."""
        r = cl_over_cs(nu, model)
        xi = rayleigh_ratio(r)
        c_s = 1.0 if velocity_unit == "c_s" else 1.0 / xi
        c_l = r * c_s
        kn, kt = born_stiffness(c_l, c_s)
        if kn_spring == "across":
            kn, kt, kn_bottom, kt_bottom = kt, kn, kt_bottom, kn_bottom
        elif kn_spring != "along":
            raise ValueError(kn_spring)
        try:
            c_born = born_surface_ratio(kn, kt) * c_s
        except ValueError:          # the swapped springs of 'across' have no surface wave below their c_s
            c_born = math.nan
        return cls(nu=nu, model=model, velocity_unit=velocity_unit, c_s=c_s, c_l=c_l,
                   c_r=xi * c_s, c_surface_born=c_born,
                   kn_top=kn, kt_top=kt, kn_bottom=kn_bottom, kt_bottom=kt_bottom)

    @property
    def c_l_bottom(self) -> float:
        return born_wave_speeds(self.kn_bottom, self.kt_bottom)[0]
