"""Fronts as cracks: the energy that reaches a front's tip, by two independent routes, and what its breaks take.

A rupture front is read as a dynamic shear (mode II) crack running along the interface.  Three measures,
each a pure function of arrays plus a thin function of a run:

route 1, ``contour_g``      the energy flux into a closed lattice contour (a square of half-side r) around the
                            tip, from one whole-lattice snapshot: G = (F - dE/dt - P_damp) / V (below);
route 2, ``field_g``        the dynamic mode II singular field fitted to the interface shear traction ahead of
                            the tip, tau(xi) = tau_0 + K_II / sqrt(2 pi xi) (``mode2_fit``), turned into G by
                            the velocity function of the Born continuum (``mode2_compliance``);
``gamma_sites``             Gamma, the energy the front's breaks released per unit length of its path.

``mode2_fit_shifted`` is the other K_II fit, the paper's appendix B form sigma = K_II / sqrt(2 pi (xi + x_p))
(no offset), which the paper study and its mode II figure use.  ``process_zone`` gives the Palmer-Rice length Lambda both routes' distances are counted in
(``palmer_rice_length``).  ``front_energy`` gives every scalar of one front at once.

The per-front fields (``fronts.FIELDS``: ``parslip fronts --json``, ``front.<name>``), means over the front's
steady stretch (route 1's weighted by the tip's local speed, ``route1_mean``), null where the data is missing: ``G_contour_inner``, ``G_contour_outer`` (route 1, from
snapshots inside the stretch), ``G_field`` (route 2, from the interface frames), ``Gamma`` and
``Gamma_source``.  Each is computed on first use, the routes once per front; route 1 reads a snapshot only
when its boxes fit in the lattice at the tip, so an ordinary run (sparse snapshots, a thin block) costs
nothing there.

Route 1, from lattice bonds, not continuum fields.  The snapshot holds every node's position p(n) at a drive
step n and its half-step velocity (p(n) - p(n-1))/dt, hence p(n-1) too, and its cells hold every bulk bond
and every intact interface bond: two consecutive states of the whole lattice.  Every bond is linear,
f_i = K (p_j - p_i - d0) on node i (bulk: K = (k_n - k_t) n n^T + k_t I, d0 the reference bond; interface:
K = diag(k_x, k_y), d0 = (-x0, -delta0) from the top site to its partner), so the energy flux into a region R
across the bonds its contour cuts is exact on the lattice,

    F = sum over cut bonds (i in R, j out) of 1/2 f_i . (v_i + v_j),     f_i = K (d(n) + d(n-1)) / 2,

the power the bond delivers to R at step n - 1/2 if R holds half of each cut bond's energy.  For a front
running at V, the energy in a region fixed in the lab changes as the pattern translates,
dE_R/dt = -V dE/dX, and a lattice column is a symmetry of both lattices, so dE/dX is the centred difference
of the energy held by R shifted one spacing a forward and back (kinetic 1/2 m v^2 of its nodes, the bonds it
holds, half of those it cuts).  V is the tip's local speed at the snapshot (``tip_speed_at``), not the
stretch's one fitted speed, which would bias every front that speeds up or slows down.  Then

    G V = F - dE_R/dt - P_damp,        P_damp = zeta m sum_(i in R) v_i^2   ("absolute" damping, m u'' = f - zeta m u')

or, with ``time.damping = "bonds"`` (a dashpot beta K (v_j - v_i) on each bulk bond, beta = zeta / k_n of its
block), F taken with each cut bond's whole force and P_damp = sum of beta dv.K dv over the bonds R holds (half
of a cut one),

is the energy per unit time the breaks inside R take: G in m c_r^2 / a, an energy per unit length of
advance.  So route 1 is a closure check of the bookkeeping: by energy conservation the flux into a contour
equals what the breaks inside it take (``interface_take`` reads the same from the events), whatever the
interface's law.  It does not test G = Gamma; route 2, the near-tip field that Svetlizky & Fineberg (Nature
2014) measure G from, does.  A run with ``interface.contact`` is refused (``route1_blocker``): its contact
springs are three-node elements a snapshot does not hold, and their switches make and take energy.

Only data on the contour enters F and dE/dX: no derivative of a continuum field near the tip.  The continuum
J = integral of [(W + T) n_x - sigma_ij n_j du_i/dx] ds is the same flux; the lattice sum is used because
stresses and gradients near a lattice tip are not those of a continuum, while the bond sums are exact.  With friction behind the tip (bonds that re-form and break again inside R) F also carries what they
dissipate: the contour at two radii says how much.

Route 1 needs snapshots during the front's steady stretch, and snapshots are spread evenly over the drive.
Without writing them all: run to just before the front with a checkpoint at the end, then extend the run
from it with a dense cadence (``drive.duration`` and ``output.snapshots`` may change on a restart), e.g.

    parslip run S --out R --set drive.duration=T_pre --set checkpoint.every=T_pre --set output.snapshots=1
    parslip run S --out R --restart R.ckpt.h5 --set drive.duration=T_end --set output.snapshots=N

which writes only the snapshots of the new cadence that fall after T_pre.

Route 2.  The Born lattice's long-wave limit is an elastic continuum with moduli C_abkl = (rho/2) sum over the
six bonds of K_ak n_b n_l (``born_moduli``): sigma = lambda' tr(eps) I + 2 mu' eps + 2 eta omega with
mu' + eta = rho c_s^2 (``model.physics``).  Its bulk waves are isotropic, but the eta term (a null Lagrangian
in the bulk) changes the tractions on a free surface, so a crack's K-G relation is not the classical one when
k_t != 0.  ``mode2_compliance`` computes it: for a crack steady at speed v, Stroh's formalism with
C*_a1k1 = C_a1k1 - rho v^2 delta_ak gives G = 1/2 K^T Re(i A B^-1) K (the crack-closure integral of the
near-tip field u = sqrt(2/pi) Re[A <sqrt(x + p_alpha y)> B^-1] K), which for k_t = 0 is Freund's
G = v^2 alpha_s K_II^2 / (2 mu c_s^2 D(v)), D = 4 alpha_s alpha_l - (1 + alpha_s^2)^2 (``freund_mode2``).
The lattice obeys it: a static lattice crack held at the rim by a K field releases H(0) K^2 / 2 per spacing
within 2 % (the classical solid is 10 % off).  The fit needs the square-root field to reach the window, and
the blocks' far rows bound it to a fraction of their height: route 2 reads only blocks ``FIELD_HEIGHT``
process zones tall (``field_resolved``; the measured shortfalls in its docstring and tests/test_cracks.py).
``site_energies`` puts each route's values at the tip's sites (``tip`` in the JSON).

Units: lengths in a unless said, energies in m c_r^2, G and Gamma in m c_r^2 / a, tractions in rho c_r^2,
K_II in rho c_r^2 a^(1/2), speeds in c_r.  Internal arrays (positions, velocities, stiffnesses) are in the
run's internal units (a = m = 1, velocity unit c_ref; ``model.physics``).
"""
from __future__ import annotations

import math

import numpy as np

from ..model.damping import Damping
from ..model.lattice import DIRECTIONS
from ..model.physics import DENSITY
from .fronts import front_field, tip_values

# Palmer & Rice (1973): the slip-weakening zone of a shear crack, Lambda = (9 pi / 16) M Gamma / tau_p^2.
PALMER_RICE = 9.0 * math.pi / 16.0
# The two contours of route 1 and the fit window of route 2, in process-zone lengths Lambda.
CONTOUR_RADII = (1.5, 3.0)
FIT_WINDOW = (1.0, 3.0)
# How tall (in Lambda) each elastic block must be for route 2's window to lie in the singular field: in
# static lattice cracks with the run's interface (tests/test_cracks.py), the fit at FIT_WINDOW returns 0.65-0.72
# of the lattice's G between blocks 5 Lambda tall, 0.83-0.94 at 10 Lambda, 1.0-1.07 at 20 Lambda.
FIELD_HEIGHT = 10.0
# The front's steady stretch: the middle 60 % of the sites it broke (as Front.steady_speed).
STEADY = (0.2, 0.8)


# --- the Born continuum -----------------------------------------------------------------------------------
def born_moduli(kn: float, kt: float, rho: float = DENSITY) -> np.ndarray:
    """C[a, b, k, l] (m c^2 / a^2, 2D stress per strain) of the triangular Born lattice's long-wave limit:
    sigma_ab = C_abkl du_k/dx_l with sigma_ab the a-force on a plane of normal b, C = (rho / 2) sum over the
    six unit bonds n of K_ak n_b n_l, K = (k_n - k_t) n n^T + k_t I (a = 1)."""
    C = np.zeros((2, 2, 2, 2))
    for n in DIRECTIONS:
        K = (kn - kt) * np.outer(n, n) + kt * np.eye(2)
        C += 0.5 * rho * np.einsum("ak,b,l->abkl", K, n, n)
    return C


def _stroh(C: np.ndarray, v: float, rho: float):
    """Stroh's eigenvectors (A, B) and roots p (Im p > 0) of a crack steady at speed v along x."""
    Cs = C.copy()
    Cs[:, 0, :, 0] -= rho * v * v * np.eye(2)
    Q, R, T = Cs[:, 0, :, 0], Cs[:, 0, :, 1], Cs[:, 1, :, 1]
    Ti = np.linalg.inv(T)
    N = np.block([[-Ti @ R.T, Ti], [R @ Ti @ R.T - Q, -R @ Ti]])
    w, X = np.linalg.eig(N)
    up = np.argsort(-w.imag)[:2]
    if not np.all(w[up].imag > 1e-12):
        raise ValueError(f"v = {v}: no decaying Stroh roots (at or above the shear speed)")
    return X[:2, up], X[2:, up], w[up]


def mode2_compliance(v: float, kn: float, kt: float, rho: float = DENSITY) -> float:
    """H(v) in G = 1/2 H K_II^2 for a mode II crack steady at speed v (internal units) in the Born continuum
    of (k_n, k_t): H = Re(i A B^-1)_xx (Stroh, module docstring), in a^2 / (m c^2).  v -> 0 is the static
    value; for k_t = 0 it is Freund's v^2 alpha_s / (mu c_s^2 D)."""
    A, B, _ = _stroh(born_moduli(kn, kt, rho), max(v, 1e-3 * math.sqrt(kn + kt)), rho)
    return float(np.real(1j * A @ np.linalg.inv(B))[0, 0])


def freund_mode2(v: float, c_s: float, c_l: float, mu: float) -> float:
    """Freund's (1990, Eq. 5.3.10) H(v) = v^2 alpha_s / (mu c_s^2 D(v)) of an isotropic solid, G = 1/2 H K_II^2:
    alpha = sqrt(1 - v^2/c^2), D = 4 alpha_s alpha_l - (1 + alpha_s^2)^2; it tends to (1 - nu)/mu as v -> 0 and
    diverges at the classical Rayleigh speed."""
    a_s, a_l = math.sqrt(1 - (v / c_s) ** 2), math.sqrt(1 - (v / c_l) ** 2)
    D = 4 * a_s * a_l - (1 + a_s ** 2) ** 2
    return v * v * a_s / (mu * c_s * c_s * D)


def crack_field(x, y, v: float, K: float, kn: float, kt: float, rho: float = DENSITY):
    """The near-tip displacement (N, 2) and velocity (N, 2) of a mode II crack steady at speed v along +x in
    the Born continuum, tip at the origin, crack on y = 0, x < 0: u = sqrt(2/pi) Re[A <sqrt(z_a)> B^-1] K,
    z_a = x + p_a y, K = (K_II, 0); velocity -v du/dx.  Traction K_II / sqrt(2 pi x) ahead, none on the faces."""
    A, B, p = _stroh(born_moduli(kn, kt, rho), v, rho)
    Bk = np.linalg.solve(B, np.array([K, 0.0]))
    z = np.asarray(x, float)[:, None] + p[None, :] * np.asarray(y, float)[:, None]
    sq = np.sqrt(z.astype(complex))
    u = math.sqrt(2 / math.pi) * np.real((sq * Bk[None, :]) @ A.T)
    du = math.sqrt(2 / math.pi) * np.real((0.5 / sq * Bk[None, :]) @ A.T)
    return u, -v * du


def palmer_rice_length(kx: float, kn: float, kt: float, a: float = 1.0) -> float:
    """Palmer-Rice process zone Lambda = (9 pi/16) M Gamma / tau_p^2, in a.

    Gamma / tau_p^2 = a / (2 k_x) for a bond that holds a linear shear traction k_x s / a up to its break
    (Gamma = k_x s_b^2 / (2 a), tau_p = k_x s_b / a, whatever s_b).  M is the Born continuum's static mode II
    modulus, 1 / H(0) of ``mode2_compliance``: the mu / (1 - nu) of Palmer and Rice, which is G = (1 - nu)
    K^2 / (2 mu) in an isotropic solid; with k_t != 0 it is not rho c_s^2 / (1 - nu)."""
    M = 1.0 / mode2_compliance(0.0, kn, kt)
    return PALMER_RICE * M * a / (2.0 * kx)


# --- route 1: the energy flux into a lattice contour --------------------------------------------------------
def bulk_bond_stiffness(d_ref: np.ndarray, kn: np.ndarray, kt: np.ndarray) -> np.ndarray:
    """K (nb, 2, 2) of bulk bonds with reference vectors d_ref (nb, 2): (k_n - k_t) n n^T + k_t I."""
    n = d_ref / np.linalg.norm(d_ref, axis=1)[:, None]
    return (np.asarray(kn) - np.asarray(kt))[:, None, None] * n[:, :, None] * n[:, None, :] + \
        np.asarray(kt)[:, None, None] * np.eye(2)[None]


def contour_flux(ref, p, p_prev, dt: float, bonds: dict, box: tuple, V: float, zeta: float = 0.0,
                 mass: float = 1.0) -> dict:
    """Route 1 (module docstring) for one pair of consecutive states of a lattice.

    ref (N, 2): reference positions (a), which decide what lies inside the box; p, p_prev (N, 2): positions at
    steps n and n - 1; dt: the step (internal time); bonds: {"i", "j" (nb,), "K" (nb, 2, 2), "d0" (nb, 2)},
    the force on i being K (p_j - p_i - d0), and optionally "beta" (nb,), each bond's dashpot time (a/c;
    ``time.damping = "bonds"``: beta K (v_j - v_i) on i too, 0 for an undamped bond); box = (x_c, y_c, r):
    the square |x - x_c| <= r, |y - y_c| <= r; V: the tip's signed speed along x (internal units); zeta:
    absolute damping rate.  With dashpots, F carries their force on the cut bonds and P_damp their power
    beta (v_j - v_i).K(v_j - v_i), whole for a bond inside and half for one cut: together they are the power
    the dashpots deliver to R's nodes.  Returns {"G" (energy per unit length, internal), "flux", "dEdt",
    "damping" (powers, internal), "cut" (bonds cut)}."""
    i, j, K, d0 = bonds["i"], bonds["j"], bonds["K"], bonds["d0"]
    vel = (p - p_prev) / dt
    d1 = p[j] - p[i] - d0
    d2 = p_prev[j] - p_prev[i] - d0
    f = 0.5 * np.einsum("bij,bj->bi", K, d1 + d2)                           # on i, at step n - 1/2
    beta = bonds.get("beta")
    if beta is not None:                           # the bonds' dashpots: beta K (v_j - v_i) on i, v at n - 1/2
        f_dash = np.asarray(beta, float)[:, None] * np.einsum("bij,bj->bi", K, vel[j] - vel[i])
        f = f + f_dash
    e_bond = 0.25 * (np.einsum("bi,bij,bj->b", d1, K, d1) + np.einsum("bi,bij,bj->b", d2, K, d2))
    e_node = 0.5 * mass * np.sum(vel ** 2, axis=1)
    x_c, y_c, r = box

    def inside(shift):
        return (np.abs(ref[:, 0] - x_c - shift) <= r) & (np.abs(ref[:, 1] - y_c) <= r)

    def energy(shift):
        m = inside(shift)
        return float(e_node[m].sum() + 0.5 * np.dot(m[i].astype(float) + m[j], e_bond))

    m = inside(0.0)
    side = m[i].astype(float) - m[j]                                          # +1: i inside, -1: j inside
    flux = float(0.5 * np.sum(side * np.einsum("bi,bi->b", f, vel[i] + vel[j])))
    dEdt = -V * (energy(1.0) - energy(-1.0)) / 2.0
    damping = float(zeta * mass * np.sum(vel[m] ** 2))
    if beta is not None:                           # each dashpot's power, half of it for a bond the contour cuts
        held = 0.5 * (m[i].astype(float) + m[j])
        damping += float(np.dot(held, np.einsum("bi,bi->b", f_dash, vel[j] - vel[i])))
    return {"G": (flux - dEdt - damping) / abs(V), "flux": flux, "dEdt": dEdt, "damping": damping,
            "cut": int(np.count_nonzero(side))}


# --- route 2: the singular field ahead of the tip -----------------------------------------------------------
def mode2_fit(xi, tau):
    """(K_II, tau_0) of tau = tau_0 + K_II / sqrt(2 pi xi) by least squares, linear in (tau_0, K_II): xi > 0
    the distance ahead of the tip (a), tau the interface shear traction (K_II in tau's unit times a^(1/2)).

    One profile (xi, tau of shape (n,)) gives two floats; profiles stacked on a leading axis (shape (m, n),
    NaN where a point is left out) give two arrays of m, each the fit of its own row: with z = 1 / sqrt(2 pi
    xi), K_II = sum (z - <z>)(tau - <tau>) / sum (z - <z>)^2 and tau_0 = <tau> - K_II <z> over the row's
    points.  NaN with fewer than 3 points."""
    xi, tau = np.asarray(xi, float), np.asarray(tau, float)
    ok = np.isfinite(xi) & np.isfinite(tau) & (xi > 0)
    n = ok.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(ok, 1.0 / np.sqrt(2 * math.pi * np.where(ok, xi, 1.0)), 0.0)
        zm = z.sum(axis=-1) / n
        tm = np.where(ok, tau, 0.0).sum(axis=-1) / n
        dz = np.where(ok, z - zm[..., None], 0.0)
        dt = np.where(ok, tau - tm[..., None], 0.0)
        K = (dz * dt).sum(axis=-1) / (dz * dz).sum(axis=-1)
    K, tau0 = np.where(n >= 3, K, math.nan), np.where(n >= 3, tm - K * zm, math.nan)
    return (float(K), float(tau0)) if K.ndim == 0 else (K, tau0)


def mode2_fit_shifted(xi, sigma) -> tuple[float, float]:
    """(K_II, x_p) of sigma = K_II / sqrt(2 pi (xi + x_p)), the paper's appendix B form (no offset: the
    singular field with its origin shifted by x_p), xi > 0 the distance ahead of the tip.

    The model is linear in xi after a change of variable,
        sigma^-2 = (2 pi / K^2) xi + 2 pi x_p / K^2,
    so a straight-line least-squares fit of sigma^-2 on xi gives slope A and intercept B, K_II = sign(sigma)
    sqrt(2 pi / A), x_p = B / A, over the points of the sign sigma has nearest the tip.  Units: xi and x_p
    in one length unit (l in the paper study), K_II in sigma's unit times its square root.  (nan, nan) when
    the profile does not fall off ahead of the tip (A <= 0) or has fewer than 2 such points."""
    xi, sigma = np.asarray(xi, float), np.asarray(sigma, float)
    if len(xi) < 2 or np.any(sigma == 0):
        return math.nan, math.nan
    sign = float(np.sign(sigma[np.argmin(xi)]))
    keep = np.sign(sigma) == sign
    if keep.sum() < 2:
        return math.nan, math.nan
    a, b = np.polyfit(xi[keep], 1.0 / sigma[keep] ** 2, 1)
    if a <= 0:
        return math.nan, math.nan
    return sign * math.sqrt(2 * math.pi / a), b / a


def subshear(v: float, kn: float, kt: float, rho: float = DENSITY) -> bool:
    """Whether a crack steady at speed v (internal units) in the Born continuum of (k_n, k_t) has the two
    decaying Stroh roots (``_stroh``) that ``mode2_compliance`` needs: v below the shear speed."""
    try:
        _stroh(born_moduli(kn, kt, rho), max(v, 1e-3 * math.sqrt(kn + kt)), rho)
    except ValueError:
        return False
    return True


def field_g(K: float, v: float, kn: float, kt: float, rho: float = DENSITY) -> float:
    """G = 1/2 H(v) K_II^2 (``mode2_compliance``), all internal units."""
    return 0.5 * mode2_compliance(v, kn, kt, rho) * K * K


# --- Gamma: what the breaks took ------------------------------------------------------------------------------
def break_energy(syy, kx, ky, delta0: float, delta_b: float, c_r: float = 1.0):
    """A bond's stored energy at its break (m c^2, internal) when only a frame before the break is known, and
    its rest offset x0 is 0 (``interface.reform_x0 = "zero"``, and every bond that never re-formed): the bond
    breaks where its length reaches delta_b; its gap y = delta0 - f_y / k_y is read off the frame's normal
    traction (f_y = -syy rho c_r^2 a on the top node, syy in rho c_r^2), its shear stretch is then
    sqrt(delta_b^2 - y^2), and E = 1/2 k_x (delta_b^2 - y^2) + 1/2 k_y (y - delta0)^2.  The gap of the frame
    is not the gap at the break step: an estimate, used when the events carry no energy."""
    y = delta0 + np.asarray(syy, float) * DENSITY * c_r * c_r / np.asarray(ky, float)
    return 0.5 * np.asarray(kx) * np.maximum(delta_b ** 2 - y ** 2, 0.0) + 0.5 * np.asarray(ky) * (y - delta0) ** 2


# --- the measures on a run ------------------------------------------------------------------------------------
def _material(run):
    from ..model.physics import Material
    s = run.scene
    return Material.from_scene(s["material.nu"], s["material.model"], s["material.velocity_unit"],
                               s["material.bottom_kn"], s["material.bottom_kt"], s.get("material.kn_spring", "along"))


def process_zone(run) -> float:
    """Lambda (a) of a run: ``palmer_rice_length`` with the block's k_n, k_t and the sites' median k_x."""
    m = _material(run)
    kx = float(np.median(run.interface["kx"])) if "kx" in run.interface else float(run.scene["interface.kx"])
    return palmer_rice_length(kx, m.kn_top, m.kt_top)


def steady_stretch(front, share: tuple = STEADY) -> dict:
    """The front's steady stretch: the sites it broke between the fractions ``share`` of its path, their
    indices into ``front.tip`` ("lo", "hi"), times "t0", "t1" (l/c_r), and the straight line fitted through
    their arrivals, x_tip(t) = "x_at"(t) (l), of signed speed "V" (c_r)."""
    tt, xx = np.asarray(front.tip["t"], float), np.asarray(front.tip["x"], float)
    n = len(tt)
    lo, hi = int(share[0] * n), max(int(share[1] * n), int(share[0] * n) + 2)
    V, x0 = np.polyfit(tt[lo:hi], xx[lo:hi], 1)
    return {"lo": lo, "hi": hi, "t0": float(tt[lo]), "t1": float(tt[hi - 1]), "V": float(V),
            "x_at": lambda t: x0 + V * np.asarray(t, float)}


def _refuse(run, what: str, value, accepted: str):
    from ..errors import ConfigError
    raise ConfigError(f"{what} = {value!r} in {run.path}: {accepted}")


class _LatticeGeometry:
    """A run's nodes (reference positions in a, block, column) from its scene, where route 1's boxes may lie,
    and (``bulk_bonds``, from the first snapshot's cells) its bulk bonds: stiffness and reference vector."""

    def __init__(self, run):
        from ..model.lattice import Lattice
        s = run.scene
        self.run = run
        self.lat = Lattice(s["lattice.top_rows"], s["lattice.top_cols"], s["lattice.bottom_rows"],
                           s["lattice.bottom_cols"], s["interface.delta0"], "elastic")
        nodes = self.lat.nodes_in_columns(0, self.lat.ncols)
        self.ref = np.stack([nodes["x"], nodes["y"]], axis=1)
        self.block, self.col = nodes["block"], nodes["col"]
        self.bulk = None
        top, bot = self.lat.top, self.lat.bottom
        self.y_interface = 0.5 * (top.y0 + (bot.rows - 1) * np.sqrt(3) / 2)
        # The box must stay clear of the driven top row and the fixed bottom row, whose forces it cannot see.
        self.y_free = (np.sqrt(3) / 2, top.y0 + (top.rows - 2) * np.sqrt(3) / 2)
        self.x_free = (top.col0, top.col0 + top.cols - 1)

    def box(self, x_tip: float, l: float, r_max: float):
        """(x_c, y_c) of the boxes about a tip at x_tip (l), or None when the largest (half-side r_max, a)
        leaves the free part of either block."""
        x_c, y_c = self.lat.top.col0 + x_tip * l - 0.5, self.y_interface
        if (x_c - r_max - 1 < self.x_free[0] or x_c + r_max + 1 > self.x_free[1]
                or y_c - r_max < self.y_free[0] or y_c + r_max > self.y_free[1]):
            return None
        return x_c, y_c

    def bulk_bonds(self, cells, interface):
        """Fill the bulk bonds (node pairs, reference vectors, stiffnesses) from a snapshot's cells, once."""
        if self.bulk is not None:
            return
        bulk = cells[interface == 0]
        m = _material(self.run)
        kn = np.where(self.block[bulk[:, 0]] == 1, m.kn_top, m.kn_bottom)
        kt = np.where(self.block[bulk[:, 0]] == 1, m.kt_top, m.kt_bottom)
        self.bulk = bulk
        self.d0 = self.ref[bulk[:, 1]] - self.ref[bulk[:, 0]]
        self.K = bulk_bond_stiffness(self.d0, kn, kt)
        self.kn = kn


def _bonds(run, geo, snap) -> dict:
    """Every bond of a snapshot in ``contour_flux``'s form: the bulk bonds, and each intact interface bond
    from its top node to its substrate node with K = diag(k_x, k_y), d0 = (-x0, -delta0), x0 = 0; with
    ``time.damping = "bonds"``, "beta": zeta / k_n of its block on a bulk bond, 0 on an interface bond (the
    engine's dashpots, ``model.damping``)."""
    cells, flag = snap["cells"], snap["interface"]
    iface = cells[(flag == 1) & (cells[:, 0] != cells[:, 1])]
    site = geo.col[iface[:, 0]] - geo.lat.top.col0
    kx, ky = run.interface["kx"][site], run.interface["ky"][site]
    Ki = np.zeros((len(iface), 2, 2))
    Ki[:, 0, 0], Ki[:, 1, 1] = kx, ky
    d0 = np.zeros((len(iface), 2))
    d0[:, 1] = -float(run.scene["interface.delta0"])
    out = {"i": np.concatenate([geo.bulk[:, 0], iface[:, 0]]), "j": np.concatenate([geo.bulk[:, 1], iface[:, 1]]),
           "K": np.concatenate([geo.K, Ki]), "d0": np.concatenate([geo.d0, d0])}
    damping = _damping(run)
    if damping.rated:
        out["beta"] = np.concatenate([damping.beta(geo.kn), np.zeros(len(iface))])
    return out


def _damping(run) -> Damping:
    """The run's damping (``model.damping``), from its scene."""
    s = run.scene
    return Damping(zeta=float(s.get("time.zeta", 0.0)), form=s.get("time.damping", "absolute"))


def route1_blocker(run) -> tuple | None:
    """Why route 1 cannot read this run, as (key, value, what route 1 needs), or None when it can."""
    s = run.scene
    if s.get("lattice.substrate", "elastic") != "elastic":
        return "lattice.substrate", s.get("lattice.substrate"), "route 1 needs an elastic substrate"
    if s.get("interface.reform_x0", "zero") != "zero":
        return ("interface.reform_x0", s["interface.reform_x0"],
                "route 1 reads interface bonds from positions, so it needs rest offsets 0 ('zero')")
    if s.get("time.damping", "absolute") not in ("absolute", "bonds"):
        return "time.damping", s["time.damping"], "route 1 subtracts 'absolute' or 'bonds' damping"
    if s.get("interface.contact", 0.0) > 0:
        # A contact is a three-node spring a snapshot does not hold (its cells are the bonds), and its switches
        # on and off make and take energy inside the box (the budget's contact_switched): route 1's flux and
        # box energy would miss both.
        return ("interface.contact", s["interface.contact"],
                "route 1 reads the energy flux through the bonds a snapshot holds, and a contact's force is not "
                "one of them: it needs interface.contact = 0")
    return None


def contour_g_run(run, front, radii: tuple = CONTOUR_RADII) -> list[dict]:
    """Route 1 on every snapshot inside the front's steady stretch (``steady_stretch``): G (m c_r^2 / a) in a
    square of half-side r Lambda about the tip for each r of ``radii``, the tip the front's own at the
    snapshot (``tip_at``), the box centred on the interface, V the tip's local speed there (``tip_speed_at``:
    the box's energy translates with the tip as it is then, dE/dt = -V dE/dX, and G is the flux per unit of
    its advance then; the stretch's one fitted speed would bias both wherever the front speeds up or slows
    down).  Rows {"t" (l/c_r), "x_tip" (l), "V" (c_r, local), "V_stretch" (c_r), "G" (list, one per radius),
    "radii" (a), "parts" (``contour_flux``'s dicts, internal units)}.  A snapshot whose largest box leaves the
    free part of either block is skipped before it is read, so a run whose blocks are thinner than the boxes
    costs nothing.  A run route 1 cannot read (``route1_blocker``) is refused with one line."""
    from ..io import contract
    blocker = route1_blocker(run)
    if blocker:
        _refuse(run, *blocker)
    lam, st = process_zone(run), steady_stretch(front)
    c_r, dt, l = float(run.attrs["c_r"]), float(run.attrs["dt"]), float(run.attrs["l"])
    # The body drag's rate; the bonds' dashpots travel with the bonds (``_bonds``).
    zeta = _damping(run).drag
    times = np.asarray(run.snapshot_times, float)
    inside = np.flatnonzero((times >= st["t0"]) & (times <= st["t1"]))
    geo = _LatticeGeometry(run) if len(inside) else None
    rows, r_max = [], max(radii) * lam
    for k in inside:
        t = float(times[k])
        x_tip = float(tip_at(front, t))
        centre = geo.box(x_tip, l, r_max)
        if centre is None:
            continue
        snap = contract.read_snapshot_arrays(run.path, int(k))
        geo.bulk_bonds(snap["cells"], snap["interface"])
        p, vel = snap["points"][:, :2], snap["velocity"][:, :2]
        bonds = _bonds(run, geo, snap)
        near = np.max(np.abs(geo.ref - centre), axis=1) <= r_max + 2       # only the bonds the boxes reach
        keep = near[bonds["i"]] | near[bonds["j"]]
        bonds = {name: a[keep] for name, a in bonds.items()}
        V = float(tip_speed_at(front, t))
        parts = [contour_flux(geo.ref, p, p - dt * vel, dt, bonds, (*centre, r * lam), V * c_r, zeta)
                 for r in radii]
        rows.append({"t": t, "x_tip": x_tip, "V": V, "V_stretch": st["V"], "G": [q["G"] / c_r ** 2 for q in parts],
                     "radii": [r * lam for r in radii], "parts": parts})
    return rows


def tip_at(front, t) -> np.ndarray:
    """The tip's position x_tip(t) (l) at times t (l/c_r) along its own path: the arrivals (t, x) of
    ``front.tip`` interpolated linearly, so exact at each break and within one site between two."""
    return np.interp(np.asarray(t, float), np.asarray(front.tip["t"], float), np.asarray(front.tip["x"], float))


def tip_speed_at(front, t) -> np.ndarray:
    """The tip's local speed (c_r, signed) at times t (l/c_r): the catalogue's local speeds ``front.tip["v"]``
    (each fitted over 2 h + 1 sites of the path, ``fronts.Front``) interpolated linearly between the arrivals;
    a site without a speed (a burst, NaN) is left out.  A front drawn without them (no "v") gets the local
    slope of its arrivals, the centred difference dx/dt over h sites each side (h = ``fronts.WINDOW``)."""
    tt, xx = np.asarray(front.tip["t"], float), np.asarray(front.tip["x"], float)
    v = front.tip.get("v")
    if v is None:
        from .fronts import WINDOW
        n = len(tt)
        lo, hi = np.maximum(np.arange(n) - WINDOW, 0), np.minimum(np.arange(n) + WINDOW, n - 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = (xx[hi] - xx[lo]) / (tt[hi] - tt[lo])
    v = np.asarray(v, float)
    ok = np.isfinite(v)
    return np.interp(np.asarray(t, float), tt[ok], v[ok]) if ok.any() else np.full(np.shape(t), math.nan)


def field_g_run(run, front, window: tuple = FIT_WINDOW) -> list[dict]:
    """Route 2 on every interface frame inside the front's steady stretch: ``mode2_fit`` of /interface/sxy
    over the sites xi = window[0] Lambda .. window[1] Lambda ahead of the tip, a frame whose window leaves the
    contact skipped; G = ``field_g`` at the stretch's speed.  Rows {"t", "x_tip", "V", "K_II" (rho c_r^2
    a^(1/2)), "tau_0" (rho c_r^2), "G" (m c_r^2 / a)}.  The frames are fitted together (one array operation),
    and H(v) is computed once: the stretch has one speed.  No rows for a stretch at or above the shear speed
    (``subshear``): there H(v) does not exist.

    The tip is the front's own at each frame (``tip_at``), not the stretch's fitted line: the fit puts the
    singularity at xi = 0, so a tip misplaced by a few a (a front that speeds up or slows down over the
    stretch departs from its line by that much) moves K_II by tens of percent at xi ~ Lambda, up and down
    along the stretch.  H(v) varies slowly (a few percent over +-0.1 c_r at 0.8 c_r), the tip's position
    does not."""
    lam, st, m = process_zone(run), steady_stretch(front), _material(run)
    c_r, l = float(run.attrs["c_r"]), float(run.attrs["l"])
    x, t = np.asarray(run.x, float), np.asarray(run.times, float)
    d = 1.0 if st["V"] >= 0 else -1.0
    want = int(math.floor((window[1] - window[0]) * lam * len(x) / l))     # sites a whole window holds, at least
    ks = np.flatnonzero((t >= st["t0"]) & (t <= st["t1"]))
    x_tip = tip_at(front, t[ks]).reshape(-1)
    xi = d * (x[None, :] - x_tip[:, None]) * l
    sel = (xi >= window[0] * lam) & (xi <= window[1] * lam)
    whole = np.count_nonzero(sel, axis=1) >= want
    ks, x_tip, xi, sel = ks[whole], x_tip[whole], xi[whole], sel[whole]
    if not len(ks):
        return []
    if not subshear(abs(st["V"]) * c_r, m.kn_top, m.kt_top):
        return []                     # at or above c_s the field has no K_II / sqrt(xi) term for H(v) to weigh
    sxy = np.asarray(run.interface["sxy"][ks], float)
    K, tau0 = mode2_fit(np.where(sel, xi, np.nan), np.where(sel, sxy, np.nan))
    G = field_g(K * DENSITY * c_r * c_r, abs(st["V"]) * c_r, m.kn_top, m.kt_top) / c_r ** 2
    return [{"t": float(t[k]), "x_tip": float(xt), "V": st["V"], "K_II": float(Kk), "tau_0": float(t0),
             "G": float(g)} for k, xt, Kk, t0, g in zip(ks, x_tip, K, tau0, G)]


def _has_energy(ev) -> bool:
    """Whether the events carry their stored energies (a file written before they did reads NaN)."""
    return ev is not None and "energy" in ev and bool(np.isfinite(ev["energy"]).any())


def gamma_run(run, front) -> dict:
    """Gamma per site on the front's steady stretch (m c_r^2 / a: one site per spacing a): the stored energy of
    the bond at the break by which the front's tip reached the site, from the event's ``energy`` when the run
    recorded it, else ``break_energy`` from the last frame before the break.  {"x" (l), "Gamma", "source"}."""
    st = steady_stretch(front)
    ev, c_r, iface = run.events, float(run.attrs["c_r"]), run.interface
    sites = np.clip(np.rint(np.asarray(front.tip["x"]) * len(run.x) - 0.5).astype(int), 0, len(run.x) - 1)
    sl = slice(st["lo"], st["hi"])
    if _has_energy(ev):
        brk = np.flatnonzero(np.asarray(ev["kind"]) == 1)
        n = len(run.x)
        key = np.asarray(ev["step"], np.int64)[brk] * n + np.asarray(ev["site"], np.int64)[brk]
        order = np.argsort(key, kind="stable")
        want = np.asarray(front.tip["step"], np.int64)[sl] * n + sites[sl]
        at = np.clip(np.searchsorted(key[order], want), 0, max(len(key) - 1, 0))
        hit = (key[order][at] == want) if len(key) else np.zeros(len(want), bool)
        g = np.where(hit, np.asarray(ev["energy"], float)[brk][order][at] if len(key) else np.nan, np.nan)
        return {"x": np.asarray(front.tip["x"])[sl], "Gamma": g, "source": "events"}
    frames = np.maximum(np.asarray(front.tip["frame"])[sl] - 1, 0)
    s = sites[sl]
    delta_b = iface["delta_b"][s] if "delta_b" in iface else float(run.scene["interface.delta_b"])
    g = break_energy(iface["syy"][frames, s], iface["kx"][s], iface["ky"][s], float(run.scene["interface.delta0"]),
                     delta_b, c_r) / c_r ** 2
    return {"x": np.asarray(front.tip["x"])[sl], "Gamma": g, "source": "frames"}


def interface_take(run, front, radii: tuple = CONTOUR_RADII, net: bool = True) -> list[float]:
    """What the interface takes inside each contour of route 1, per unit advance (m c_r^2 / a), from the events'
    stored energies: over the steady stretch (t0 to t1), the energy of every break minus that of every
    re-formation (``net``; False: the breaks alone) whose site lay within r Lambda of the tip at its step, the
    tip where route 1 centres its boxes (``tip_at``, the front's own path), over the tip's advance from t0 to
    t1.  By energy conservation this is what route 1's flux at that radius must carry, read off the bonds
    instead of the fields: a closure check of route 1 that shares none of its data.  NaN without
    /interface/events/energy."""
    ev = run.events
    if not _has_energy(ev):
        return [math.nan for _ in radii]
    lam, st, l = process_zone(run), steady_stretch(front), float(run.attrs["l"])
    t = np.asarray(ev["time"], float)
    sel = (t >= st["t0"]) & (t <= st["t1"])
    if not net:
        sel &= np.asarray(ev["kind"]) == 1
    dist = np.abs((run.x[ev["site"][sel]] - tip_at(front, t[sel])) * l)
    sign = np.where(ev["kind"][sel] == 1, 1.0, -1.0)
    e = sign * np.asarray(ev["energy"], float)[sel]
    advance = abs(float(tip_at(front, st["t1"]) - tip_at(front, st["t0"]))) * l
    return [float(e[dist <= r * lam].sum() / advance) if advance > 0 else math.nan for r in radii]


def front_energy(run, front, radii: tuple = CONTOUR_RADII, window: tuple = FIT_WINDOW) -> dict:
    """The per-front scalars, means over the front's steady stretch: G_contour_inner, G_contour_outer (route 1
    at the two radii, ``route1_mean``), G_field (route 2), Gamma (m c_r^2 / a), v (c_r, unsigned), Lambda (a), and how many
    snapshots and frames each mean holds (NaN where none); take_inner, take_outer (``interface_take``) and
    breaks_inner, breaks_outer (the same without the re-formations).  Route 1 is empty (NaN) for a run it
    cannot read (``route1_blocker``)."""
    c = [] if route1_blocker(run) else contour_g_run(run, front, radii)
    f = field_g_run(run, front, window)
    g = gamma_run(run, front)
    take = interface_take(run, front, radii)
    breaks = interface_take(run, front, radii, net=False)

    def mean(a):
        a = np.asarray(a, float)
        a = a[np.isfinite(a)]
        return float(a.mean()) if len(a) else math.nan
    inner, outer = (math.nan if g is None else g for g in (route1_mean(c, 0), route1_mean(c, -1)))
    return {"G_contour_inner": inner, "G_contour_outer": outer,
            "G_field": mean([r["G"] for r in f]), "Gamma": mean(g["Gamma"]), "Gamma_source": g["source"],
            "v": abs(steady_stretch(front)["V"]), "Lambda": process_zone(run), "snapshots": len(c), "frames": len(f),
            "take_inner": take[0], "take_outer": take[-1], "breaks_inner": breaks[0], "breaks_outer": breaks[-1]}


# --- the per-front fields -------------------------------------------------------------------------------------
SCENE_KEYS = ("material.nu", "material.model", "material.velocity_unit", "material.bottom_kn", "material.bottom_kt")


def measurable(run, front) -> bool:
    """Whether a front has a steady stretch to measure G and Gamma on: a run with its material and units
    (``c_r``, ``l``), a front that moved, and a stretch whose arrivals span a time (a front broken all at once
    has no speed)."""
    if run is None or front.direction == 0 or len(front.tip["t"]) < 3:
        return False
    if any(k not in run.scene for k in SCENE_KEYS) or any(k not in run.attrs for k in ("c_r", "l")):
        return False
    st = STEADY
    tt = np.asarray(front.tip["t"], float)
    lo, hi = int(st[0] * len(tt)), max(int(st[1] * len(tt)), int(st[0] * len(tt)) + 2)
    return float(np.ptp(tt[lo:hi])) > 0


def _memo(front, key: str, compute):
    """``compute()`` once per front: the four fields share their routes' rows."""
    store = front.__dict__.setdefault("_cracks", {})
    if key not in store:
        store[key] = compute()
    return store[key]


def route1_mean(rows: list[dict], k: int) -> float | None:
    """Route 1's G over a stretch at radius ``k`` of its rows (``contour_g_run``): the energy per unit advance,
    sum of G_i |V_i| over sum of |V_i| (each snapshot's power over the tip's local speed), None without a row.
    For a steady front it is the mean of the G_i; for one that pauses, a snapshot in the pause (V near 0,
    G_i the ratio of two small numbers) weighs as little as the tip advanced then."""
    g = np.array([r["G"][k] for r in rows], float)
    w = np.abs(np.array([r["V"] for r in rows], float))
    ok = np.isfinite(g) & np.isfinite(w)
    return float(np.sum(g[ok] * w[ok]) / np.sum(w[ok])) if ok.any() and np.sum(w[ok]) > 0 else None


def _mean(values) -> float | None:
    """The mean of the finite values, None when there is none."""
    a = np.asarray(values, float)
    a = a[np.isfinite(a)]
    return float(a.mean()) if len(a) else None


def _contour_rows(run, front) -> list[dict]:
    """Route 1's rows, [] where it reads nothing: a front without a steady stretch, a run route 1 cannot read
    (``route1_blocker``), or no snapshot inside the stretch (the rows come cheap then: none is read)."""
    if not measurable(run, front) or route1_blocker(run) or "dt" not in run.attrs:
        return []
    return _memo(front, "contour", lambda: contour_g_run(run, front))


ROUTE1_DOC = ("over the snapshots inside the front's steady stretch (the middle 60 % of its sites), with the "
              "tip's local speed at each, weighted by it (energy per unit advance: route1_mean): null without such a snapshot (write them by a restart with a "
              "dense output.snapshots cadence: docs/guide/analysis.md, G and Gamma), where the box leaves the "
              "free lattice (a block thinner than the box), or for a run route 1 cannot read (rigid substrate, "
              "interface.reform_x0 other than zero, interface.contact > 0: route1_blocker)")


@front_field("G_contour_inner", "m c_r^2/a", "G by route 1 (analysis.cracks): the energy flux into a lattice "
             f"square of half-side {CONTOUR_RADII[0]:g} Lambda about the tip per unit advance (Lambda the "
             "Palmer-Rice process zone), " + ROUTE1_DOC)
def g_contour_inner(run, front) -> float | None:
    """Route 1's G at the inner radius (``contour_g_run``) over the stretch's snapshots (``route1_mean``)."""
    return route1_mean(_contour_rows(run, front), 0)


@front_field("G_contour_outer", "m c_r^2/a", f"the same at {CONTOUR_RADII[-1]:g} Lambda: inner and outer agree "
             "where what the interface dissipates between them (re-formed bonds breaking again) is small")
def g_contour_outer(run, front) -> float | None:
    """Route 1's G at the outer radius (``contour_g_run``) over the stretch's snapshots (``route1_mean``)."""
    return route1_mean(_contour_rows(run, front), -1)


@front_field("G_field", "m c_r^2/a", "G by route 2 (analysis.cracks): G = H(v) K_II^2 / 2 (H the Born "
             "continuum's mode II velocity function at the stretch's speed), K_II from tau = tau_0 + K_II / "
             f"sqrt(2 pi xi) fitted to /interface/sxy at {FIT_WINDOW[0]:g}-{FIT_WINDOW[1]:g} Lambda ahead of the "
             "tip; mean over the interface frames inside the steady stretch; null without sxy, where no frame "
             f"holds a whole window on the contact, or where a block is under {FIELD_HEIGHT:g} Lambda tall (the "
             "square-root field does not reach the window: field_resolved)")
def g_field(run, front) -> float | None:
    """Route 2's G (``field_g_run``), mean over the stretch's frames; null where a block is too thin for the
    singular field to reach the fit window (``field_resolved``)."""
    if not measurable(run, front) or "sxy" not in run.interface or not field_resolved(run):
        return None
    return _mean([r["G"] for r in _memo(front, "field", lambda: field_g_run(run, front))])


def field_resolved(run, height: float = FIELD_HEIGHT) -> bool:
    """Whether the near-tip field route 2 fits can exist: each elastic block at least ``height`` Lambda tall
    (rows times the row height sqrt(3)/2 a).  The blocks' far rows (driven, held) bound the square-root field
    to a fraction of their height, and the window reaches 3 Lambda: in static lattice cracks the fit returns
    two thirds of G between blocks 5 Lambda tall (100 rows against Lambda = 16.7 a, k_x = 0.1;
    the paper's 10 rows hold only the block's beam response) and G within 10 % at 20 Lambda
    (``FIELD_HEIGHT``).  A running front loses more: the field's higher-order terms grow with speed."""
    s, reach = run.scene, height * process_zone(run)
    heights = [s.get("lattice.top_rows", 0)]
    if s.get("lattice.substrate", "elastic") == "elastic":
        heights.append(s.get("lattice.bottom_rows", 0))
    return min(heights) * math.sqrt(3.0) / 2.0 >= reach


def _gamma(run, front) -> dict | None:
    """``gamma_run`` once per front, None where it has nothing to read (no event energies and no frames'
    syy, kx, ky)."""
    if not measurable(run, front):
        return None
    if _has_energy(run.events):                     # gamma_run reads the events then, by each break's step
        if "step" not in front.tip:
            return None
    elif "frame" not in front.tip or any(k not in run.interface for k in ("syy", "kx", "ky")):
        return None
    return _memo(front, "gamma", lambda: gamma_run(run, front))


@front_field("Gamma", "m c_r^2/a", "the energy the front's breaks released per unit length: the stored energy "
             "of the bond at each break of its tip (one site per a), mean over the steady stretch; from the "
             "events' energy, else estimated from the last frame before each break (Gamma_source)")
def gamma_field(run, front) -> float | None:
    """Gamma (``gamma_run``), mean over the stretch's sites."""
    g = _gamma(run, front)
    return None if g is None else _mean(g["Gamma"])


@front_field("Gamma_source", "-", "where Gamma comes from: events (each break's stored energy, exact) or "
             "frames (estimated from the normal traction of the frame before each break)")
def gamma_source(run, front) -> str | None:
    g = _gamma(run, front)
    return None if g is None else g["source"]


def _at_sites(front, x_tip, values) -> np.ndarray:
    """``values`` measured with the tip at ``x_tip`` (l) placed at the nearest site of ``front.tip`` (the mean
    where several fall on one site), NaN at every other site."""
    xs = np.asarray(front.tip["x"], float)
    out, count = np.zeros(len(xs)), np.zeros(len(xs))
    if len(values):
        site = np.abs(xs[None, :] - np.asarray(x_tip, float)[:, None]).argmin(axis=1)
        np.add.at(out, site, np.asarray(values, float))
        np.add.at(count, site, 1.0)
    with np.errstate(invalid="ignore"):
        return np.where(count > 0, out / np.maximum(count, 1.0), np.nan)


@tip_values("cracks")
def site_energies(run, front) -> dict:
    """The per-front fields' per-site values along ``front.tip`` (m c_r^2 / a, NaN where not measured):
    G_contour_inner, G_contour_outer at the site nearest the tip of each snapshot inside the steady stretch,
    G_field at the site nearest the tip of each frame fitted (a frame every few sites), Gamma at every site
    of the stretch.  The same rows the per-front means read, computed once."""
    n = len(front.tip["x"])
    out = {name: np.full(n, np.nan) for name in ("G_contour_inner", "G_contour_outer", "G_field", "Gamma")}
    c = _contour_rows(run, front)
    if c:
        x = [r["x_tip"] for r in c]
        out["G_contour_inner"] = _at_sites(front, x, [r["G"][0] for r in c])
        out["G_contour_outer"] = _at_sites(front, x, [r["G"][-1] for r in c])
    if g_field(run, front) is not None:
        f = _memo(front, "field", lambda: field_g_run(run, front))
        out["G_field"] = _at_sites(front, [r["x_tip"] for r in f], [r["G"] for r in f])
    g = _gamma(run, front)
    if g is not None:
        st = steady_stretch(front)
        out["Gamma"][st["lo"]:st["hi"]] = g["Gamma"]
    return out
