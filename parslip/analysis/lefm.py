"""The theory a mode II rupture between two identical solids is compared with: dynamic fracture mechanics of a
shear crack, sub-Rayleigh and supershear, with a cohesive (slip-weakening) zone.  Pure functions of numbers:
no run, no file.  docs/studies/weakening.md states the theory and tabulates its values.

  Solid(k, eta)                        the solid: k = c_s/c_l, eta the Born continuum's couple-stress share
  Solid.isotropic(nu, model), Solid.born(kn, kt), Solid.of(material)
  compliance(v, solid)                 H(v) in G = 1/2 H K_II^2 of a steady sub-Rayleigh tip (1/(rho c_s^2))
  velocity_factor(v, solid)            A_II(v) = H(v)/H(0) (Freund 1990, Eq. 5.3.11 for eta = 0)
  expanding_k(v, solid)                k_II(v) = K_II / (dtau sqrt(pi a)) of a crack expanding at constant v
  expanding_g(v, solid)                g_II(v) = A_II(v) k_II(v)^2 (Freund 1990, Eq. 7.4.5)
  supershear_exponent(v, solid)        gamma(v): the supershear tip's stress falls as x^-gamma
  broberg(v, solid)                    the factors G1, G2 of Kammer et al.'s Eq. 1 (Broberg 1994, 1999)
  energy_ratio(v, d_over_a, solid)     Broberg's velocity function G/G_0 at any speed, with a cohesive zone
  kammer_length(v, r, solid)           the half-length L/l_0 at which a supershear front runs at v (Eq. 1)
  kammer_speed(L, r, solid)            its inverse on the stable branch
  minimal_supershear_length(r, solid)  l_m/l_0 (Kammer et al. 2018, Fig. 3B); NaN where none exists
  minimal_length_limit(solid)          the r above which none exists
  expanding_length(v, r, solid)        L/l_0 of a sub-Rayleigh crack expanding at v (the Griffith analogue)
  zone_contraction(v, solid)           X_c(v)/X_c0 = 1/A_II(v) of a steady sub-Rayleigh cohesive zone
  static_zone(gamma, drop, M, law)     X_c0, the static cohesive zone (Palmer & Rice 1973; linear slip weakening)
  lefm_zone(v, solid, tau_p, tau_r, d_c)  X_c_lefm(v) = X_c0 H(0)/H(v) of the linear slip-weakening law
  supershear_zone(v, solid)            the cohesive zone behind a supershear tip, X_c rho c_s^2 dtau_c^2 / Gamma
  andrews_f(S), andrews_lc(...), andrews_lc_gamma(...)   Andrews' transition length (Xia et al. 2004's fit)

Units: speeds in c_s of the solid; stresses in rho c_s^2 (so H, M, tractions are numbers); lengths in any one
unit.  r (``tau0_over_taup``) = (tau_0 - tau_r)/(tau_p - tau_r), the prestress above the residual over the peak
above it; l_0 = rho c_s^2 Gamma / (tau_p - tau_r)^2 (Kammer et al.'s mu Gamma / tau_p^2, stresses counted from
the residual); L is the half-length of a bilateral crack, from its centre (the hypocentre) to a tip.

The solid.  The Born lattice's long-wave limit is isotropic in the bulk but its stress has an antisymmetric part,
sigma = lambda' tr(eps) I + 2 mu' eps + 2 eta_m omega, mu' + eta_m = rho c_s^2 (``model.physics``), which changes the
tractions on a crack's faces: ``eta`` = eta_m / (rho c_s^2) = 3 k_t / (4 c_s^2) (0.0833 for the default nu = 0.2 in
plane strain), mu1 = 1 - eta.  Every formula here carries it: eta = 0 is the classical isotropic solid of the
literature, and the published curves are quoted there; ``Solid.born`` is the lattice's own continuum, whose
surface-wave speed (0.947 c_s at nu = 0.2) and static modulus (within 2 % of a static lattice crack,
``cracks.mode2_compliance``) differ from the classical ones.  With it the steady relations read
  R(s) = (1 - 2 mu1 s^2)^2 + 4 mu1^2 s^2 eta_l eta_s,  eta_l = sqrt(k^2 - s^2), eta_s = sqrt(1 - s^2) (slowness s),
  H(v) = alpha_s v^2 / (4 mu1^2 alpha_l alpha_s - (2 mu1 - v^2)^2)                 (below c_R),
  tan(pi gamma) = 4 mu1^2 alpha_l beta_s / (v^2 - 2 mu1)^2                            (above c_s),
alpha = sqrt(1 - v^2/c^2), beta_s = sqrt(v^2/c_s^2 - 1); the surface wave is the zero of R, and gamma = 1/2 at
v = sqrt(2 mu1) c_s (sqrt 2 c_s classically, Burridge 1973; Freund 1979).

Supershear with a linear cohesive zone (derived here along Broberg's route; checked against his curves below).
*Inner problem:* a tip steady at c_s < v < c_l with a cohesive zone of length d behind it whose traction falls
linearly in distance from tau_p to tau_r (Broberg's linear zone).  On the interface
tau = C [cos(pi gamma) delta' - sin(pi gamma) H[delta']] (H the Hilbert transform, delta the slip,
C = 2 mu1^2 alpha_l rho c_s^2 / (v^2 sin(pi gamma))); the solution
bounded at the tip has the far field tau - tau_r = K* x^-gamma with K* = sin(pi gamma) (tau_p - tau_r) d^gamma /
(pi gamma (1 + gamma)), and its zone takes Gamma = (tau_p - tau_r)^2 d G1 / (rho c_s^2) per unit advance,
  G1 = v^2 sin^2(pi gamma) w_d / (2 pi mu1^2 alpha_l),   w_d = 1 / (3 gamma (1 - gamma) (2 - gamma)),
w_d being the double integral of Broberg's Eq. 6.3.70 for the linear zone in closed form (a telescoping series).
*Outer problem:* the singular bilateral crack expanding at v from a point under the stress drop tau_0 - tau_r
(Broberg 1994).  Its fields are homogeneous in (x, y, t); by Smirnov-Sobolev, on the interface
d/dt du_x/dx = Re W(t/x)/x and d/dt sigma_xy = rho c_s^2 Re V(t/x)/x with V = R(zeta) W(zeta)/(zeta eta_s(zeta)),
and the mixed conditions (u_x = 0 ahead, sigma_xy = const on the crack) are a homogeneous Hilbert problem for W
whose jump is exp(2 pi i gamma(1/s)) between the tip and the S-wave front and -1 behind it.  Its solution,
  W = i C zeta e^E(zeta) (1 - zeta^2)^(1/2) / ((zeta^2 - p^2)(zeta^2 - s_R^2)),
  E(zeta) = int_p^1 2u gamma(1/u) / (u^2 - zeta^2) du
(p = 1/v the tip's slowness, s_R the surface wave's), vanishes at the S front and has a pole at s_R, where V
stays regular; the other canonical choice, (1 - zeta^2)^(-1/2) and no pole, leaves a step in the crack faces'
traction at the S-wave front and fails the boundary condition.
C follows from the faces' traction (V integrated along the imaginary zeta axis), K* = kappa (tau_0 - tau_r) L^gamma
from W at the tip.  *Matching* the two K*: d = L (G2 r)^(1/gamma), G2 = pi gamma (1 + gamma) kappa / sin(pi gamma), so

  Gamma rho c_s^2 / ((tau_p - tau_r)^2 L) = G1 G2^(1/gamma) r^(1/gamma)            (Kammer et al. 2018, Eq. 1)

Against a public implementation of Broberg's equations (read, not copied): the master curves G1 G2^(1/gamma) that
Kammer and Albertini's ``solidmechanics`` tabulates (``lefm/supershear-mastercurves/k0577.csv``, ``k0667.csv``, made
by the MATLAB ``Crack_SupershearEqMotion3.m``; columns v/c_l, gamma, G) at c_s/c_l = 0.577 and 0.667: this
module's G agrees within 0.11 % on 14 speeds from 1.01 to 1.72 c_s at 0.577 and within 0.22 % on 7 speeds at
0.667 (the largest gap at 0.99 c_l, where their trapezoidal rule on 1000 points is coarsest), gamma to their
5 digits; and 1/G1 is their supershear zone 1.723 (nu = 0.33, v = 0.8 c_l).  ``tests/test_lefm.py`` holds a
few of those values.  They tabulate no 0.612, the lattice's ratio, so the comparison is at theirs.

Sources: L. B. Freund, Dynamic Fracture Mechanics (1990), Eqs. 5.3.10-11, 6.3.65-68 (as ``solidmechanics`` cites
them), 7.4.5; Freund, J. Geophys. Res. 84 (1979) 2199; K. B. Broberg, Geophys. J. Int. 119 (1994) 706 and Cracks
and Fracture (1999), ch. 6 (Eqs. 6.3.69-70, 6.9.111, 6.9.118, as the MATLAB implementation cites them); D. S. Kammer,
I. Svetlizky, G. Cohen, J. Fineberg, Sci. Adv. 4 (2018) eaat5622, Eq. 1 and Fig. 3; A. C. Palmer, J. R. Rice,
Proc. R. Soc. A 332 (1973) 527; J. R. Rice, in Physics of the Earth's Interior (1980); I. Svetlizky, J. Fineberg,
Nature 509 (2014) 205; D. J. Andrews, J. Geophys. Res. 81 (1976) 5679 and 90 (1985) 1073; K. Xia, A. J. Rosakis,
H. Kanamori, J. R. Rice, Science 303 (2004) 1859.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..model.physics import born_wave_speeds, cl_over_cs

# Gauss-Legendre nodes and weights on (0, 1); every integrand below is made smooth by its substitution.
QUAD_POINTS = 160
_T, _WT = np.polynomial.legendre.leggauss(QUAD_POINTS)
_T, _WT = 0.5 * (_T + 1.0), 0.5 * _WT


@dataclass(frozen=True)
class Solid:
    """k = c_s/c_l and eta = the couple-stress share of rho c_s^2 (0: classical; module docstring)."""

    k: float
    eta: float = 0.0

    def __post_init__(self):
        mu1 = 1.0 - self.eta
        if not (0.0 < self.k < 1.0 and 0.0 < mu1 <= 1.0 and mu1 * (1.0 + self.k ** 2) < 2.0):
            raise ValueError(f"Solid(k={self.k}, eta={self.eta}): accepted 0 < k < 1, 0 <= eta < 1, "
                             "(1 - eta)(1 + k^2) < 2")

    @classmethod
    def isotropic(cls, nu: float, model: str = "plane_strain") -> "Solid":
        """The classical solid of Poisson ratio nu (``model.physics.cl_over_cs``)."""
        return cls(1.0 / cl_over_cs(nu, model))

    @classmethod
    def born(cls, kn: float, kt: float) -> "Solid":
        """The Born lattice's continuum of bond stiffnesses k_n, k_t (eta = 3 k_t / (4 c_s^2), as
        ``model.physics.born_surface_ratio`` takes it)."""
        c_l, c_s = born_wave_speeds(kn, kt)
        return cls(float(c_s / c_l), float(0.75 * kt / (c_s * c_s)))

    @classmethod
    def of(cls, material, born: bool = True) -> "Solid":
        """The block of a ``model.physics.Material``: its Born continuum, or (``born=False``) the classical solid
        of the same c_s/c_l."""
        return cls.born(material.kn_top, material.kt_top) if born else cls(material.c_s / material.c_l)

    @property
    def mu1(self) -> float:
        return 1.0 - self.eta

    @property
    def c_l(self) -> float:
        return 1.0 / self.k

    @property
    def c_R(self) -> float:
        """The surface-wave speed (c_s): the zero of R, the root in (0, 1) of the cubic
        -x^3 + 8 mu1 x^2 + (16 mu1^4 k^2 - 24 mu1^2) x + 32 mu1^3 - 16 mu1^4 (1 + k^2) = 0, x = v^2 (Rayleigh's for
        mu1 = 1)."""
        return _surface_speed(self.k, self.mu1)

    @property
    def H0(self) -> float:
        """The static mode II compliance H(0) = 1 / (2 mu1 (2 - mu1 (1 + k^2))): (1 - nu) for eta = 0."""
        return 1.0 / (2.0 * self.mu1 * (2.0 - self.mu1 * (1.0 + self.k ** 2)))

    @property
    def modulus(self) -> float:
        """M = 1/H(0), G = K^2/(2M) of a static crack: mu/(1 - nu) for eta = 0 (rho c_s^2)."""
        return 1.0 / self.H0


@functools.lru_cache(maxsize=64)
def _surface_speed(k: float, mu1: float) -> float:
    roots = np.roots([-1.0, 8.0 * mu1, 16.0 * mu1 ** 4 * k * k - 24.0 * mu1 ** 2,
                      32.0 * mu1 ** 3 - 16.0 * mu1 ** 4 * (1.0 + k * k)])
    x = sorted(r.real for r in roots if abs(r.imag) < 1e-12 and 0.0 < r.real < 1.0)
    # squaring brought in spurious roots: keep the one where R itself vanishes
    for xi in x:
        v = math.sqrt(xi)
        a_l, a_s = math.sqrt(1.0 - k * k * xi), math.sqrt(1.0 - xi)
        if abs(4 * mu1 ** 2 * a_l * a_s - (2 * mu1 - xi) ** 2) < 1e-9:
            return v
    raise ValueError(f"no surface wave for k = {k}, mu1 = {mu1}")


def _speeds(v):
    return np.atleast_1d(np.asarray(v, float)), np.ndim(v) == 0


def _out(a, scalar: bool):
    return float(a[0]) if scalar else a


# --- sub-Rayleigh -----------------------------------------------------------------------------------------
def compliance(v, solid: Solid):
    """H(v) in G = 1/2 H K_II^2 of a mode II tip steady at 0 <= v < c_R (1/(rho c_s^2); module docstring):
    alpha_s v^2 / (4 mu1^2 alpha_l alpha_s - (2 mu1 - v^2)^2), written without the cancellation at small v (the
    denominator over v^2 is a polynomial); Freund's v^2 alpha_s / (mu c_s^2 D) for eta = 0.  Diverges at c_R."""
    vv, scalar = _speeds(v)
    if np.any((vv < 0) | (vv >= solid.c_R)):
        raise ValueError(f"v = {v}: accepted 0 <= v < c_R = {solid.c_R:.6g} c_s")
    m, k, x = solid.mu1, solid.k, vv * vv
    a_l, a_s = np.sqrt(1.0 - k * k * x), np.sqrt(1.0 - x)
    num = 32 * m ** 3 - 16 * m ** 4 * (1 + k * k) + (16 * m ** 4 * k * k - 24 * m * m) * x + 8 * m * x * x - x ** 3
    return _out(a_s * (4 * m * m * a_l * a_s + (2 * m - x) ** 2) / num, scalar)


def velocity_factor(v, solid: Solid):
    """A_II(v) = H(v)/H(0): 1 at rest, infinite at c_R (Freund 1990, Eq. 5.3.11, for eta = 0)."""
    return compliance(v, solid) / solid.H0


def _rayleigh_imag(y, solid: Solid):
    """R(i y) = (1 + 2 mu1 y^2)^2 - 4 mu1^2 y^2 sqrt((k^2 + y^2)(1 + y^2)) > 0, as (A^4 - B^2)/(A^2 + B) so that
    the y^8 and y^6 terms cancel exactly rather than in floating point."""
    m, k, y2 = solid.mu1, solid.k, np.asarray(y, float) ** 2
    A = 1 + 2 * m * y2
    B = 4 * m * m * y2 * np.sqrt((k * k + y2) * (1 + y2))
    poly = 1 + 8 * m * y2 + (24 * m * m - 16 * m ** 4 * k * k) * y2 ** 2 + \
        (32 * m ** 3 - 16 * m ** 4 * (1 + k * k)) * y2 ** 3
    return poly / (A * A + B)


def expanding_k(v, solid: Solid):
    """k_II(v) = K_II / ((tau_0 - tau_r) sqrt(pi L)) at the tips of a mode II crack expanding symmetrically at
    constant 0 <= v < c_R from zero length (Broberg's problem; Freund 1990, Eqs. 6.3.65-68 for eta = 0):

        k_II = |R(p)| / (p^2 sqrt(p^2 - 1) I),   I = int_0^inf R(iy) / (sqrt(1 + y^2) (p^2 + y^2)^(3/2)) dy,

    p = 1/v, R the module docstring's; 1 at v = 0, 0 at c_R.  (Derived here as the supershear case is, with
    W = i C zeta (p^2 - zeta^2)^(-3/2).)"""
    vv, scalar = _speeds(v)
    out = np.ones_like(vv)
    m, k = solid.mu1, solid.k
    th = 0.5 * math.pi * _T
    for i, vi in enumerate(vv):
        if vi <= 0.0:
            continue
        if vi >= solid.c_R:
            raise ValueError(f"v = {vi}: accepted 0 <= v < c_R = {solid.c_R:.6g} c_s")
        p = 1.0 / vi
        y = p * np.tan(th)                                   # y = p tan(theta): the integrand ~ 1/y^2 far out
        f = _rayleigh_imag(y, solid) / (np.sqrt(1 + y * y) * (p * p + y * y) ** 1.5) * p / np.cos(th) ** 2
        integral = 0.5 * math.pi * np.sum(_WT * f)
        R_p = abs((1 - 2 * m * p * p) ** 2 - 4 * m * m * p * p * math.sqrt(p * p - k * k) * math.sqrt(p * p - 1))
        out[i] = R_p / (p * p * math.sqrt(p * p - 1) * integral)
    return _out(out, scalar)


def expanding_g(v, solid: Solid):
    """g_II(v) = A_II(v) k_II(v)^2: G of the expanding crack over the static G_0 = pi (tau_0 - tau_r)^2 L H(0)/2 of
    a crack as long (Freund 1990, Eq. 7.4.5); 1 at rest, 0 at c_R."""
    return velocity_factor(v, solid) * np.asarray(expanding_k(v, solid)) ** 2


def expanding_length(v, r, solid: Solid):
    """L/l_0 = 2 / (pi H(v) k_II(v)^2 r^2) at which a sub-Rayleigh crack expanding at v releases Gamma: the
    sub-Rayleigh branch beside Kammer et al.'s Eq. 1 (module docstring's units).  At v = 0 it is Griffith's
    half-length 2 M Gamma / (pi (tau_0 - tau_r)^2), which ``andrews_lc_gamma`` gives."""
    return 2.0 / (math.pi * np.asarray(compliance(v, solid)) * np.asarray(expanding_k(v, solid)) ** 2 * r * r)


# --- supershear ---------------------------------------------------------------------------------------------
def supershear_exponent(v, solid: Solid):
    """gamma(v) = (1/pi) atan2(4 mu1^2 alpha_l beta_s, (v^2 - 2 mu1)^2) for c_s <= v <= c_l: the stress ahead of
    a supershear mode II tip falls as x^-gamma (Freund 1979; Broberg 1999, Eq. 6.9.111).  0 at c_s and c_l, 1/2
    at v = sqrt(2 mu1) (sqrt 2 c_s classically), the one supershear speed of a square-root singularity."""
    vv = np.asarray(v, float)
    m, k = solid.mu1, solid.k
    a_l = np.sqrt(np.clip(1.0 - (k * vv) ** 2, 0.0, None))
    b_s = np.sqrt(np.clip(vv * vv - 1.0, 0.0, None))
    return np.arctan2(4 * m * m * a_l * b_s, (vv * vv - 2 * m) ** 2) / math.pi


def _inner(v: float, g: float, solid: Solid) -> float:
    """G1(v) = v^2 sin^2(pi g) w_d / (2 pi mu1^2 alpha_l), w_d = 1/(3 g (1 - g)(2 - g)): the steady supershear tip's
    linear cohesive zone of length d takes Gamma = (tau_p - tau_r)^2 d G1 (module docstring).  The traction law
    there is tau = C [cos(pi g) delta' - sin(pi g) H[delta']], 1/C = v^2 sin(pi g) / (2 mu1^2 alpha_l)."""
    a_l = math.sqrt(1.0 - (solid.k * v) ** 2)
    return v * v * math.sin(math.pi * g) ** 2 / (6 * math.pi * solid.mu1 ** 2 * a_l * g * (1 - g) * (2 - g))


def outer_parts(v: float, solid: Solid) -> dict:
    """The pieces of G2 (``_outer``) for one supershear speed v: {"p" = 1/v, "s_R" = 1/c_R, "gamma", "E_r",
    "I", "R_p" = |R(p)|} (module docstring):

        I = int_0^inf R(iy) e^E(iy) / ((y^2 + s_R^2)(y^2 + p^2)) dy,   E(iy) = int_p^1 2u g(1/u) / (u^2 + y^2) du,
        E_r = lim (E(zeta) + g log(p - zeta)), zeta -> p
            = int_p^1 [(g(1/u) - g)/(u - p) + g(1/u)/(u + p)] du + g log(1 - p).

    The faces' traction is -I (tau_0 - tau_r) per unit C of W.  Quadrature: u = 1 - (1 - p) t^2 (g(1/u) ~
    sqrt(1 - u) at the S slowness), y = p tan(pi t / 2) (the integrand falls as 1/y^2)."""
    m, k, p = solid.mu1, solid.k, 1.0 / v
    s_R = 1.0 / solid.c_R
    g = float(supershear_exponent(v, solid))
    u = 1.0 - (1.0 - p) * _T * _T
    du = 2.0 * (1.0 - p) * _T * _WT
    gu = supershear_exponent(1.0 / u, solid)
    E_r = float(np.sum(du * ((gu - g) / (u - p) + gu / (u + p)))) + g * math.log(1.0 - p)
    th = 0.5 * math.pi * _T
    y = p * np.tan(th)
    E_iy = (2.0 * u[None, :] * gu[None, :] / (u[None, :] ** 2 + y[:, None] ** 2)) @ du
    f = _rayleigh_imag(y, solid) * np.exp(E_iy) / ((y * y + s_R * s_R) * (y * y + p * p)) * p / np.cos(th) ** 2
    R_p = math.hypot((1 - 2 * m * p * p) ** 2, 4 * m * m * p * p * math.sqrt(p * p - k * k) * math.sqrt(1 - p * p))
    return {"p": p, "s_R": s_R, "gamma": g, "E_r": E_r, "I": 0.5 * math.pi * float(np.sum(_WT * f)), "R_p": R_p}


def _outer(v: float, solid: Solid) -> float:
    """G2(v) = pi g (1 + g) kappa / sin(pi g), with K* = kappa (tau_0 - tau_r) L^g the intensity of the singular
    crack expanding at v (module docstring): from W at the tip (``outer_parts``),

        G2 = pi (1 + g) |R(p)| e^E_r p^-g / (2 p (s_R^2 - p^2) I)."""
    o = outer_parts(v, solid)
    p, g = o["p"], o["gamma"]
    return math.pi * (1 + g) * o["R_p"] * math.exp(o["E_r"]) * p ** (-g) / (2 * p * (o["s_R"] ** 2 - p * p) * o["I"])


def broberg(v, solid: Solid) -> dict:
    """The factors of Kammer et al.'s Eq. 1 at supershear speeds c_s < v < c_l (module docstring): {"gamma",
    "G1" (inner: the cohesive zone), "G2" (outer: the expanding crack), "log_G" = log(G1 G2^(1/gamma)), "G" =
    G1 G2^(1/gamma), Kammer and Albertini's master curve G_my}, arrays (floats for a scalar v)."""
    vv, scalar = _speeds(v)
    if np.any((vv <= 1.0) | (vv >= solid.c_l)):
        raise ValueError(f"v = {v}: accepted c_s < v < c_l, 1 < v < {solid.c_l:.6g} (c_s)")
    g = supershear_exponent(vv, solid)
    G1 = np.array([_inner(x, gx, solid) for x, gx in zip(vv, g)])
    G2 = np.array([_outer(x, solid) for x in vv])
    logG = np.log(G1) + np.log(G2) / g
    with np.errstate(over="ignore"):
        G = np.exp(logG)
    return {key: _out(val, scalar) for key, val in
            {"gamma": g, "G1": G1, "G2": G2, "log_G": logG, "G": G}.items()}


def energy_ratio(v, d_over_a, solid: Solid):
    """Broberg's velocity function G/G_0 of a crack of half-length a expanding at v with a linear cohesive zone of
    length d at each tip, G_0 = pi (tau_0 - tau_r)^2 a H(0)/2 the static release: g_II(v) below c_R (in the
    limit d << a), and above c_s

        G/G_0 = 2 G1 G2^2 (d/a)^(1 - 2 gamma) / (pi H(0)),

    0 in the singular limit d/a -> 0 except at gamma = 1/2 (v = sqrt(2 mu1) c_s), where it does not depend on d.
    NaN between c_R and c_s (no steady tip there).  ``d_over_a`` is one number (not used below c_R)."""
    vv, scalar = _speeds(v)
    out = np.full(vv.shape, math.nan)
    sub = vv < solid.c_R
    if sub.any():
        out[sub] = expanding_g(vv[sub], solid)
    sup = (vv > 1.0) & (vv < solid.c_l)
    if sup.any():
        b = broberg(vv[sup], solid)
        out[sup] = 2 * b["G1"] * b["G2"] ** 2 * np.asarray(d_over_a, float) ** (1 - 2 * b["gamma"]) / \
            (math.pi * solid.H0)
    return _out(out, scalar)


def _log_length(v, r: float, solid: Solid):
    """log(L/l_0) of Eq. 1 (``kammer_length``), finite where L/l_0 under- or overflows."""
    b = broberg(v, solid)
    return -(np.asarray(b["log_G"]) + math.log(r) / np.asarray(b["gamma"]))


def kammer_length(v, r: float, solid: Solid):
    """L/l_0 = 1 / (G1 G2^(1/gamma) r^(1/gamma)): Kammer et al.'s Eq. 1 solved for the half-length at which a
    supershear front runs at v under r = (tau_0 - tau_r)/(tau_p - tau_r) (module docstring)."""
    with np.errstate(over="ignore", under="ignore"):
        return np.exp(_log_length(v, r, solid))


def _branch(r: float, solid: Solid, n: int = 240):
    """Speeds on (c_s, c_l), clustered at both ends, log(L/l_0) there, and the index where the stable branch
    starts: the last local minimum of L(v) (its speed grows with L above it), or 0 where L grows from c_s on.
    (Within about 1e-3 c_s of c_s, L(v) falls to 0 for r above 1/G2(c_s) ~ 0.2: a sliver no front resolves, and
    no grid point here is that close.)"""
    t = (np.arange(n) + 0.5) / n
    v = 1.0 + (solid.c_l - 1.0) * 0.5 * (1.0 - np.cos(math.pi * t))
    logL = _log_length(v, r, solid)
    mins = [i for i in range(1, n - 1) if logL[i] <= logL[i - 1] and logL[i] < logL[i + 1]]
    return v, logL, (mins[-1] if mins else 0)


def minimal_supershear_length(r: float, solid: Solid) -> tuple[float, float]:
    """(l_m/l_0, v_m): the shortest half-length of Eq. 1's stable supershear branch and its speed, the local
    minimum of L(v) below which a supershear front cannot be sustained (Kammer et al. 2018, Fig. 3B); (NaN,
    NaN) where L(v) has no such minimum: there L grows with v from c_s on and the branch reaches any length
    (``minimal_length_limit`` gives the r)."""
    from scipy.optimize import minimize_scalar
    v, logL, i = _branch(r, solid)
    if i == 0:
        return math.nan, math.nan
    res = minimize_scalar(lambda x: float(_log_length(x, r, solid)), bounds=(v[i - 1], v[i + 1]),
                          method="bounded", options={"xatol": 1e-10})
    return float(math.exp(res.fun)), float(res.x)


def minimal_length_limit(solid: Solid, tol: float = 1e-4) -> float:
    """The r = tau0_over_taup above which Eq. 1 has no minimal supershear length (``minimal_supershear_length``
    is NaN), by bisection on the grid of ``_branch`` (a minimum shallower than its spacing is missed: about
    1e-3 in r): 0.483 at c_s/c_l = 0.577, 0.498 at 0.612, 0.453 for the Born continuum at nu = 0.2."""
    lo, hi = 0.05, 0.95
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _branch(mid, solid)[2] > 0 else (lo, mid)
    return 0.5 * (lo + hi)


def kammer_speed(length, r: float, solid: Solid):
    """The speed (c_s) of a supershear front of half-length L/l_0 = ``length`` by Eq. 1 on its stable branch
    (``_branch``: above the minimal length's speed, where v grows with L); NaN below the minimal length."""
    from scipy.optimize import brentq
    L, scalar = _speeds(length)
    v, logL, i = _branch(r, solid)
    out = np.full(L.shape, math.nan)
    for j, Lj in enumerate(np.log(L)):
        up = np.flatnonzero(logL[i:] >= Lj)
        if Lj < logL[i] or not len(up):
            continue
        hi = i + up[0]
        if hi == i:
            out[j] = v[i]
            continue
        out[j] = brentq(lambda x: float(_log_length(x, r, solid)) - Lj, v[hi - 1], v[hi], xtol=1e-12)
    return _out(out, scalar)


# --- cohesive zones ---------------------------------------------------------------------------------------
def zone_contraction(v, solid: Solid):
    """X_c(v)/X_c0 = 1/A_II(v) = H(0)/H(v) for a steady sub-Rayleigh tip whose cohesive traction is any function
    of slip: the steady problem is the static one with M replaced by M/A_II(v) (Rice 1980; Freund 1990, Eqs.
    6.2.32-35; Svetlizky & Fineberg 2014 use it), so the zone shrinks to 0 at c_R.  At nu = 0.2 (plane strain),
    at 0.2, 0.5, 0.8, 0.9 of the solid's own c_R: 0.985, 0.894, 0.646, 0.452 classically, 0.987, 0.911, 0.703,
    0.531 for the Born continuum (whose c_R is 0.947 c_s, not 0.911)."""
    return 1.0 / np.asarray(velocity_factor(v, solid))


# Palmer & Rice (1973): a zone whose traction falls linearly in distance from tau_p to tau_r behind a static tip
# is X_c0 = (9 pi/16) M Gamma / (tau_p - tau_r)^2 long.
PALMER_RICE = 9.0 * math.pi / 16.0


def static_zone(gamma, drop, modulus, law: str = "linear_slip"):
    """X_c0, the static cohesive zone of a mode II tip: c M Gamma / dtau^2 (lengths in the unit of Gamma / dtau;
    dtau = tau_p - tau_r, M the static modulus, ``Solid.modulus``).  ``law`` "linear_distance": traction linear
    in distance, c = 9 pi/16 (Palmer & Rice 1973; the slip then weakens only nearly linearly and Gamma =
    (4/9) dtau delta_end); "linear_slip": traction linear in slip, tau = tau_p - dtau delta/D_c, Gamma = dtau D_c/2,
    c = ``linear_slip_zone()`` = 1.46229 (0.8275 of Palmer & Rice's), solved here."""
    c = {"linear_distance": PALMER_RICE}.get(law)
    if c is None:
        if law != "linear_slip":
            raise ValueError(f"law {law!r}: accepted 'linear_slip', 'linear_distance'")
        c = linear_slip_zone()
    return c * np.asarray(modulus, float) * np.asarray(gamma, float) / np.asarray(drop, float) ** 2


def _wlog(n: int, w, c):
    """int w^n ln|w - c| dw, n = 1, 2 (antiderivatives; x ln|x| -> 0 at x = 0)."""
    x = w - c
    L = np.log(np.abs(np.where(x == 0, 1.0, x)))
    if n == 1:
        return (w * w - c * c) / 2 * L - w * w / 4 - c * w / 2
    return (w ** 3 - c ** 3) / 3 * L - w ** 3 / 9 - c * w * w / 6 - c * c * w / 3


def slip_kernel(nodes) -> np.ndarray:
    """A[i, j] = int_0^1 phi_j(w) k(sigma_i, w) dw: the slip delta(s) = (2/(pi M)) int_0^R t(u) k du of a static
    semi-infinite mode II crack, bounded at its tip, whose faces carry t(u) at u behind the tip (Rice 1980), in
    s = R sigma^2, u = R w^2: k(sigma, w) = 4 sigma - 2 w ln|(w + sigma)/(w - sigma)| (the Jacobian 2w in).
    phi_j are the hat functions of ``nodes`` (0 .. 1), each integral in closed form (product integration)."""
    w = np.asarray(nodes, float)
    sig, wa, wb = w[:, None], w[None, :-1], w[None, 1:]
    h = wb - wa
    A = np.zeros((len(w), len(w)))
    for c, sign in ((-sig, -2.0), (sig, 2.0)):           # -2w ln|w + sigma| + 2w ln|w - sigma|
        i1, i2 = _wlog(1, wb, c) - _wlog(1, wa, c), _wlog(2, wb, c) - _wlog(2, wa, c)
        A[:, :-1] += sign * (wb * i1 - i2) / h
        A[:, 1:] += sign * (i2 - wa * i1) / h
    A[:, :-1] += 4 * sig * h / 2
    A[:, 1:] += 4 * sig * h / 2
    return A


def linear_slip_solution(nodes: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(w, delta/D_c at the nodes w = sqrt(s/R), lam) of the static zone of linear slip weakening: with
    t = dtau (1 - delta/D_c) on the zone, delta/D_c = lam A (1 - delta/D_c) (``slip_kernel``,
    lam = 2 dtau R / (pi M D_c)), R the first length at which the slip reaches D_c at the zone's end (the first
    root in lam: the slip then rises monotonically; larger roots overshoot D_c inside)."""
    from scipy.optimize import brentq
    w = np.linspace(0.0, 1.0, nodes)
    A = slip_kernel(w)
    rhs = A @ np.ones(nodes)
    slip = lambda x: np.linalg.solve(np.eye(nodes) + x * A, x * rhs)  # noqa: E731
    lam = brentq(lambda x: slip(x)[-1] - 1.0, 0.3, 0.6, xtol=1e-14)
    return w, slip(lam), lam


@functools.lru_cache(maxsize=4)
def linear_slip_zone(nodes: int = 401) -> float:
    """c of X_c0 = c M Gamma / dtau^2 for linear slip weakening (``linear_slip_solution``): c = pi lam, as
    Gamma = dtau D_c / 2.  Piecewise-linear product integration on ``nodes`` and ``2 nodes - 1`` nodes,
    Richardson-extrapolated (second order): 1.462292 (1.462295 on 401 nodes alone, 1.462292 on 1601)."""
    coarse, fine = linear_slip_solution(nodes)[2], linear_slip_solution(2 * nodes - 1)[2]
    return math.pi * (fine + (fine - coarse) / 3.0)


def lefm_zone(v, solid: Solid, tau_p: float, tau_r: float, d_c: float):
    """X_c_lefm(v) = X_c0 H(0)/H(v), X_c0 = c M Gamma / (tau_p - tau_r)^2, Gamma = (tau_p - tau_r) D_c / 2: the
    width of the linear slip-weakening zone behind a mode II tip steady at 0 <= v < c_R (``static_zone``,
    ``zone_contraction``), M = ``solid.modulus``.  Tractions in rho c_s^2 of the solid, the width in the unit of
    d_c.  The law is rigid below tau_p here: an elastic share before the peak is not in it."""
    drop = tau_p - tau_r
    x0 = static_zone(0.5 * drop * d_c, drop, solid.modulus)
    return x0 * zone_contraction(v, solid)


def supershear_zone(v, solid: Solid):
    """X_c rho c_s^2 (tau_p - tau_r)^2 / Gamma = 1/G1(v) = 2 pi mu1^2 alpha_l / (v^2 sin^2(pi gamma) w_d): the
    linear cohesive zone behind a steady supershear tip that takes Gamma (Broberg 1999, Eq. 6.3.69)."""
    vv, scalar = _speeds(v)
    g = supershear_exponent(vv, solid)
    return _out(np.array([1.0 / _inner(x, gx, solid) for x, gx in zip(vv, g)]), scalar)


# --- Andrews' transition ------------------------------------------------------------------------------------
# S above which a 2D crack does not turn supershear (Andrews 1985; Burridge 1973 for the steady limit): tau_p -
# tau_0 below 1.77 (tau_0 - tau_r).
ANDREWS_S_2D = 1.77
# Xia, Rosakis, Kanamori & Rice (Science 2004): their fit to Andrews' (1976, Fig. 6) transition lengths of a 2D
# slip-weakening crack, L_trans / L_c = 9.8 (1.77 - S)^-3.
ANDREWS_F_COEF = 9.8


def andrews_f(S):
    """Andrews' transition factor f(S) = L_trans / L_c = 9.8 (1.77 - S)^-3 (Xia et al. 2004's fit to Andrews
    1976, Fig. 6), S = (tau_p - tau_0)/(tau_0 - tau_r); NaN from S = 1.77 up (no transition in 2D) and for NaN.
    f(0.5) = 4.8, f(1.0) = 21.5, f(1.2) = 52.9."""
    S = np.asarray(S, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(S < ANDREWS_S_2D, ANDREWS_F_COEF / (ANDREWS_S_2D - S) ** 3, math.nan)


def andrews_lc(modulus: float, tau_p, tau_0, tau_res, d_c):
    """Andrews' (1976) critical half-length of a mode II slip-weakening crack (units of d_c):

        L_c = M (tau_p - tau_res) D_c / (pi (tau_0 - tau_res)^2)

    the Griffith half-length of a crack under the stress drop tau_0 - tau_res (K_II = (tau_0 - tau_res)
    sqrt(pi L), G = K_II^2 / (2 M)) whose fracture energy is that of the linear slip-weakening law,
    Gamma = (tau_p - tau_res) D_c / 2.  M is the static mode II modulus, G = K^2 / (2 M): mu / (1 - nu) in
    plane strain (Andrews' (2/pi) mu (lambda + mu)/(lambda + 2 mu) is M/pi), mu (1 + nu) in plane stress, which
    is Xia et al.'s (1 + nu) / pi form; for the Born lattice ``cracks.mode2_compliance`` gives 1 / M.  Tractions
    and M in one unit (stress), d_c a length."""
    drop = np.asarray(tau_0, float) - np.asarray(tau_res, float)
    return modulus * (np.asarray(tau_p, float) - np.asarray(tau_res, float)) * np.asarray(d_c, float) / \
        (math.pi * drop * drop)


def andrews_lc_gamma(modulus: float, gamma, tau_0, tau_res):
    """L_c = 2 M Gamma / (pi (tau_0 - tau_res)^2): ``andrews_lc`` for a law with an elastic share, whose D_c is
    taken as D_c,eff = 2 Gamma / (tau_p - tau_res) (so that (tau_p - tau_res) D_c,eff = 2 Gamma); Gamma an energy
    per unit area in the unit of M times a length."""
    drop = np.asarray(tau_0, float) - np.asarray(tau_res, float)
    return 2.0 * modulus * np.asarray(gamma, float) / (math.pi * drop * drop)
