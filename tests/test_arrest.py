"""The arrest prediction (parslip.analysis.arrest) against the handbook and an independent quadrature.

- A uniform drop on an edge crack gives K = 1.1215 dtau sqrt(pi L) (Tada, Paris & Irwin 2000), which the
  weight function's polynomial must reproduce.
- A drop confined to [0, b] (dtau on it, -tau_r beyond: the interface ahead of a precursor holds less than the
  residual) has K(L) by scipy's adaptive quadrature of the singular form (weight (1 - s)^-1/2, no change of
  variable); its root G(L) = Gamma, found by brentq, is the arrest the module must predict to one site.
"""
import math

import numpy as np
import pytest
from scipy import integrate, optimize

from parslip.analysis import arrest


def test_uniform_drop_is_the_handbook_edge_crack():
    for L in (7.0, 40.0, 333.0):
        K = arrest.edge_k(np.full(400, 0.3), L)
        assert K == pytest.approx(1.1215 * 0.3 * math.sqrt(math.pi * L), rel=2e-4)


def _k_quad(b, dtau, tau_r, L):
    """K of the step drop by the singular form 2/sqrt(pi L) int_0^L p(x) F(x/L) / sqrt(1 - x^2/L^2) dx."""
    def part(lo, hi, p):
        if hi < 1.0:                              # away from the tip: regular
            return integrate.quad(lambda s: p * arrest.edge_factor(s) / math.sqrt(1.0 - s * s), lo, hi)[0]
        f = lambda s: p * arrest.edge_factor(s) / math.sqrt(1.0 + s)   # 1/sqrt(1-s^2) = (1-s)^-1/2 (1+s)^-1/2
        return integrate.quad(f, lo, hi, weight="alg", wvar=(0.0, -0.5))[0]   # the weight (1 - s)^-1/2
    s_b = min(b / L, 1.0)
    total = part(0.0, s_b, dtau) + (part(s_b, 1.0, -tau_r) if s_b < 1.0 else 0.0)
    return 2.0 / math.sqrt(math.pi * L) * L * total


def test_arrest_of_a_step_drop_matches_an_independent_root():
    b, dtau, tau_r, H0 = 60, 0.05, 0.02, 3.0
    drop = np.r_[np.full(b, dtau), np.full(400, -tau_r)]
    G = arrest.release_curve(drop, H0)
    gamma = 0.5 * G[b - 1]                       # reached inside the drop, so the crack runs past b and stops
    L_zero = optimize.brentq(lambda L: _k_quad(b, dtau, tau_r, L), b, 20 * b)     # K = 0: the drive is gone
    L_root = optimize.brentq(lambda L: 0.5 * H0 * _k_quad(b, dtau, tau_r, L) ** 2 - gamma, b, L_zero)
    assert arrest.predicted_length(G, gamma) == pytest.approx(L_root, abs=1.0)
    assert arrest.predicted_length(G, 2 * G.max()) != arrest.predicted_length(G, 2 * G.max())   # NaN: no front
    assert arrest.predicted_length(np.linspace(1, 2, 50), 0.5) == 50.0                        # never falls: crosses


def test_uniform_drop_on_an_interior_crack_is_griffiths():
    """A crack of length L = 2c under a uniform drop: K = dtau sqrt(pi c) at either tip."""
    for L in (7.0, 40.0, 333.0):
        assert arrest.interior_k(np.full(400, 0.3), L) == pytest.approx(0.3 * math.sqrt(math.pi * L / 2), rel=1e-6)


def test_interior_arrest_of_a_step_drop_matches_an_independent_root():
    """The interior crack's K by scipy's quadrature of its singular form, 1/sqrt(pi L/2) int_0^L p(s)
    sqrt(s/(L - s)) ds with the weight (L - s)^-1/2 left to quad; the root of G = Gamma by brentq."""
    b, dtau, tau_r, H0 = 60, 0.05, 0.02, 3.0

    def k_quad(L):
        alg = dict(weight="alg", wvar=(0.0, -0.5))           # the weight (L - s)^-1/2 on [lo, L]
        if L <= b:
            total = integrate.quad(lambda s: dtau * math.sqrt(s), 0.0, L, **alg)[0]
        else:
            total = (integrate.quad(lambda s: dtau * math.sqrt(s / (L - s)), 0.0, b)[0]
                     + integrate.quad(lambda s: -tau_r * math.sqrt(s), b, L, **alg)[0])
        return total / math.sqrt(math.pi * L / 2)

    drop = np.r_[np.full(b, dtau), np.full(400, -tau_r)]
    G = arrest.release_curve(drop, H0, "interior")
    assert G[b - 1] == pytest.approx(0.5 * H0 * k_quad(b) ** 2, rel=1e-3)
    gamma = 0.5 * G[b - 1]
    L_zero = optimize.brentq(k_quad, b + 1e-9, 20 * b)
    L_root = optimize.brentq(lambda L: 0.5 * H0 * k_quad(L) ** 2 - gamma, b, L_zero)
    assert arrest.predicted_length(G, gamma) == pytest.approx(L_root, abs=1.0)
