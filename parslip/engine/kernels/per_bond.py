"""The reference engine's per-bond kernels (``engine.reference_engine``): one Verlet step on flat arrays.

Responsible for the arithmetic only: no MPI, no files.  The caller (the
engine) alternates these with the halo exchanges.  Every kernel loops over
nodes or sites in local order and sums a node's terms in a fixed order
(six neighbour slots, then the interface bond, then the external load), so
a node's update is bit-for-bit the same however the lattice is cut.

Arrays: ``u`` displacements (n_local, 2) in a; ``nb`` neighbour local
indices (n_owned, 6), -1 where the slot is empty; ``block`` per node, which
indexes ``kn``/``kt`` (stiffness per block, m c^2/a^2).  Interface sites:
``partner[s]`` is the global index of the bottom site bonded to local top
site s, or -1.
"""
import numpy as np
from numba import njit

FREE, FIXED, DRIVEN = 0, 1, 2
BREAKS, FORMS = 0, 1


@njit(cache=True, inline="always")
def _bond_force(u, i, j, nx, ny, kd, kt):
    """Force on node i from its bond to j along reference direction (nx, ny):
    (k_n - k_t) [(u_j - u_i).n] n + k_t (u_j - u_i)."""
    dx = u[j, 0] - u[i, 0]
    dy = u[j, 1] - u[i, 1]
    p = kd * (dx * nx + dy * ny)
    return p * nx + kt * dx, p * ny + kt * dy


@njit(cache=True)
def bulk_forces(u, nb, block, kn, kt, dirs, n_owned, f):
    """Born bond forces (paper Eq. 2.1) on the owned nodes, into ``f``.

    F_i = sum_j (k_n - k_t) [(u_j - u_i).n_ij] n_ij + k_t (u_j - u_i),
    with n_ij the reference bond direction: a linear network.
    """
    for i in range(n_owned):
        b = block[i]
        kd = kn[b] - kt[b]
        fx = 0.0
        fy = 0.0
        for k in range(6):
            j = nb[i, k]
            if j < 0:
                continue
            gx, gy = _bond_force(u, i, j, dirs[k, 0], dirs[k, 1], kd, kt[b])
            fx += gx
            fy += gy
        f[i, 0] = fx
        f[i, 1] = fy


@njit(cache=True)
def _gap(u, ref_x, it, ib, delta0):
    """(x_ij, y_ij) of an interface pair: top node minus bottom node, in a."""
    return (ref_x[it] - ref_x[ib]) + (u[it, 0] - u[ib, 0]), delta0 + (u[it, 1] - u[ib, 1])


@njit(cache=True)
def interface_update(u, ref_x, top_node, top_owned, partner, x0, bot_node, bot_g0,
                     delta0, delta_b, reform_zero, taken, claim, counters):
    """Break stretched bonds, then re-form free top nodes, at positions u(t).

    1. A bond breaks when its length sqrt(x_ij^2 + y_ij^2) reaches delta_b.
    2. Each free top node claims the nearest free bottom node within delta0
       (ties: lower bottom index).
    3. Claims are granted in increasing top-site order, so when two free
       top nodes reach the same bottom node, the lower global index wins;
       the loser waits a step.  Local top sites are in global order, so the
       rule is the same on every rank.
    A re-formed bond's rest offset x0 is its x_ij at that moment (starts
    unstressed in x), or 0 with ``reform_zero``.
    Halo sites are updated too, as copies: their claims decide the owned
    sites' conflicts.  Only owned sites count in ``counters``.
    """
    nt = top_node.shape[0]
    nbs = bot_node.shape[0]
    db2 = delta_b * delta_b
    d02 = delta0 * delta0
    for s in range(nt):
        q = partner[s] - bot_g0
        if partner[s] < 0 or q < 0 or q >= nbs:
            continue
        dx, dy = _gap(u, ref_x, top_node[s], bot_node[q], delta0)
        if dx * dx + dy * dy >= db2:
            partner[s] = -1
            if top_owned[s]:
                counters[BREAKS] += 1
    taken[:] = 0
    for s in range(nt):
        q = partner[s] - bot_g0
        if partner[s] >= 0 and 0 <= q < nbs:
            taken[q] = 1
    for s in range(nt):
        claim[s] = -1
        if partner[s] >= 0:
            continue
        it = top_node[s]
        # Bottom site q sits at reference x = q (column q, no row offset).
        qc = int(np.floor(ref_x[it] + u[it, 0] + 0.5)) - bot_g0
        best = np.inf
        for q in range(qc - 1, qc + 2):
            if q < 0 or q >= nbs or taken[q]:
                continue
            dx, dy = _gap(u, ref_x, it, bot_node[q], delta0)
            d2 = dx * dx + dy * dy
            if d2 <= d02 and d2 < best:
                best = d2
                claim[s] = q
    for s in range(nt):
        q = claim[s]
        if q < 0 or taken[q]:
            continue
        taken[q] = 1
        partner[s] = q + bot_g0
        if reform_zero:
            x0[s] = 0.0
        else:
            x0[s] = _gap(u, ref_x, top_node[s], bot_node[q], delta0)[0]
        if top_owned[s]:
            counters[FORMS] += 1


@njit(cache=True)
def interface_forces(u, ref_x, top_node, top_owned, partner, x0, bot_node, bot_g0,
                     delta0, kx, ky, f, react):
    """Interface bond forces: f_x = -k_x (x_ij - x_ij^0), f_y = -k_y (y_ij - delta0) on the top node.

    Added to ``f`` of the owned top node; the reaction is written (not
    added: a bottom node has at most one bond) into ``react`` of the bottom
    node, which may be a halo copy that the caller sends to its owner.
    """
    nbs = bot_node.shape[0]
    for s in range(top_node.shape[0]):
        q = partner[s] - bot_g0
        if not top_owned[s] or partner[s] < 0 or q < 0 or q >= nbs:
            continue
        it = top_node[s]
        ib = bot_node[q]
        dx, dy = _gap(u, ref_x, it, ib, delta0)
        fx = -kx * (dx - x0[s])
        fy = -ky * (dy - delta0)
        f[it, 0] += fx
        f[it, 1] += fy
        react[ib, 0] = -fx
        react[ib, 1] = -fy


@njit(cache=True)
def verlet_update(u, u_prev, f, react, fext, load, kind, u_drive0, drive_shift, drive_on,
                  dt, zeta, n_owned):
    """Damped Verlet with dt^2 (the paper's Eq. 2.7 drops the square):

        u(t+dt) (1 + zeta dt/2) = 2 u(t) - (1 - zeta dt/2) u(t-dt) + dt^2 F(t)

    with the damping on the central-difference velocity, m = 1.  F is the
    bond force + interface reaction + load * fext.  FIXED nodes stay put;
    DRIVEN nodes have x prescribed as u_drive0 + drive_shift while
    ``drive_on``, y free.  Returns the first owned local index whose new
    state is not finite, or -1.
    """
    c = 0.5 * zeta * dt
    inv = 1.0 / (1.0 + c)
    keep = 1.0 - c
    dt2 = dt * dt
    bad = -1
    for i in range(n_owned):
        if kind[i] == FIXED:
            continue
        # "+ 0.0" turns a -0.0 reaction into +0.0, as the reverse exchange
        # does on many ranks, so one rank and many agree to the bit.
        fx = f[i, 0] + (react[i, 0] + 0.0) + load * fext[i, 0]
        fy = f[i, 1] + (react[i, 1] + 0.0) + load * fext[i, 1]
        nx = (2.0 * u[i, 0] - keep * u_prev[i, 0] + dt2 * fx) * inv
        ny = (2.0 * u[i, 1] - keep * u_prev[i, 1] + dt2 * fy) * inv
        if drive_on and kind[i] == DRIVEN:
            nx = u_drive0[i] + drive_shift
        u_prev[i, 0] = u[i, 0]
        u_prev[i, 1] = u[i, 1]
        u[i, 0] = nx
        u[i, 1] = ny
        if bad < 0 and not (np.isfinite(nx) and np.isfinite(ny)):
            bad = i
    return bad


@njit(cache=True)
def node_stress(u, nb, block, kn, kt, dirs, n_owned, scale, out):
    """Virial stress per owned node, sigma_ab = sum_j f_a^ij n_b^ij a / (2 Omega).

    ``scale`` = 1/(2 Omega rho c_r^2) = 1/(2 c_r^2) gives units of rho c_r^2.
    out[:, 0..2] = sigma_xx, sigma_yy, sigma_xy, where sigma_xy = sum f_x n_y
    is the x-traction on horizontal planes (the interface shear).
    """
    for i in range(n_owned):
        b = block[i]
        kd = kn[b] - kt[b]
        sxx = 0.0
        syy = 0.0
        sxy = 0.0
        for k in range(6):
            j = nb[i, k]
            if j < 0:
                continue
            nx = dirs[k, 0]
            ny = dirs[k, 1]
            fx, fy = _bond_force(u, i, j, nx, ny, kd, kt[b])
            sxx += fx * nx
            syy += fy * ny
            sxy += fx * ny
        out[i, 0] = sxx * scale
        out[i, 1] = syy * scale
        out[i, 2] = sxy * scale


@njit(cache=True)
def potential_energy(u, ref_x, nb, block, kn, kt, dirs, n_owned, fext, load,
                     top_node, top_owned, partner, x0, bot_node, bot_g0, delta0, kx, ky, out):
    """Energy per owned node, in m c^2:

    bonds 0..2 of each node (each bulk bond once) 1/2 [k_n (du.n)^2 + k_t |du_perp|^2],
    the interface bond on its top node 1/2 k_x (x_ij - x0)^2 + 1/2 k_y (y_ij - delta0)^2,
    and the load's potential -load * fext . u.
    """
    for i in range(n_owned):
        b = block[i]
        e = -load * (fext[i, 0] * u[i, 0] + fext[i, 1] * u[i, 1])
        for k in range(3):
            j = nb[i, k]
            if j < 0:
                continue
            dx = u[j, 0] - u[i, 0]
            dy = u[j, 1] - u[i, 1]
            dn = dx * dirs[k, 0] + dy * dirs[k, 1]
            e += 0.5 * (kn[b] * dn * dn + kt[b] * (dx * dx + dy * dy - dn * dn))
        out[i] = e
    nbs = bot_node.shape[0]
    for s in range(top_node.shape[0]):
        q = partner[s] - bot_g0
        if not top_owned[s] or partner[s] < 0 or q < 0 or q >= nbs:
            continue
        dx, dy = _gap(u, ref_x, top_node[s], bot_node[q], delta0)
        out[top_node[s]] += 0.5 * kx * (dx - x0[s]) ** 2 + 0.5 * ky * (dy - delta0) ** 2
