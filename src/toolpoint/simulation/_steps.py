"""The time-domain simulation's step loops, compiled (numba).

One step of :mod:`~toolpoint.simulation.time_domain` is a few dozen small array operations over the batch's points
(chip, surface, force, the modal state's exact map). In NumPy each is a call of ~1 µs whatever its size, so a
batch of a few points — a shop's test cut is a batch of two, its noisy run and its noise-free twin — cost ~60 µs a
step, 64,000 steps a second of cutting, whatever the points. Compiled, a step costs what its arithmetic costs
(``benchmarks/bench_simulation.py --cut-only`` prints the figures). The expressions are those of the NumPy code term
for term; the sums over teeth and slices run in loop order, so results may differ from a NumPy sum in the last bit.

Every array argument is a writable C-contiguous array of a fixed dtype (one compiled signature, cached on disk).
The angle tables (s, c, inside, fs, cx, cy, ex, ey: (T, N, L, P), :meth:`time_domain._Cut.tables`) hold step i at
row i − t0; ``read`` (R, N) is the flat row (ring row × N + tooth) each tooth reads at step i, by i mod R.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True, inline="always")
def _chip(k, w, p, x, y, s, c, inside, fs, cx, cy, ex, ey, edge, read, rho, buf):  # pragma: no cover - compiled
    """Force (F_x, F_y) of point p at table row k from the displacement (x, y) at the step's midpoint; writes the
    surfaces it leaves into ring row w (equation (1) and (2) of :mod:`~toolpoint.simulation.time_domain`)."""
    N, L = buf.shape[1], buf.shape[2]
    sx = 0.0
    sy = 0.0
    for j in range(N):
        fr = read[w, j]
        rr, jj = fr // N, fr % N
        for ll in range(L):
            nrm = s[k, j, ll, p] * x + c[k, j, ll, p] * y - rho[j]
            prev = buf[rr, jj, ll, p]
            h = fs[k, j, ll, p] + prev - nrm
            if inside[k, j, ll, p] and h > 0:
                buf[w, j, ll, p] = nrm
                sx += h * cx[k, j, ll, p]
                sy += h * cy[k, j, ll, p]
                if edge:
                    sx += ex[k, j, ll, p]
                    sy += ey[k, j, ll, p]
            else:
                buf[w, j, ll, p] = prev + fs[k, j, ll, p]
    return sx, sy


@numba.njit(cache=True, nogil=True)
def rigid_steps(a, b, t0, M, R, s, c, inside, fs, cx, cy, ex, ey, edge, read, rho, buf, F):  # pragma: no cover
    """Steps a ≤ i < b of the rigid tool (no displacement): F[i mod M] = (F_x, F_y) (M, 2, P); updates ``buf``."""
    P = buf.shape[3]
    for i in range(a, b):
        k, w, row = i - t0, i % R, i % M
        for p in range(P):
            fx, fy = _chip(k, w, p, 0.0, 0.0, s, c, inside, fs, cx, cy, ex, ey, edge, read, rho, buf)
            F[row, 0, p] = fx
            F[row, 1, p] = fy


@numba.njit(cache=True, nogil=True)
def modal_pass(E, G, Eh, Gh, W0, W1, Cout, F, f_prev, eta, record, r_out, mid_out):  # pragma: no cover
    """The exact step map η ← E η + G u, u = W0 F_x + W1 F_y, over the forces F (T, 2, P), in place on ``eta``
    (m, P). With ``record``: r_out[i] = Re(C η) at each step's start and mid_out[i] = Re(C (E_h η + G_h u_prev)) at
    its midpoint (u_prev the previous step's input, from ``f_prev`` (2, P) before the first)."""
    T, P, m = F.shape[0], F.shape[2], eta.shape[0]
    for p in range(P):
        px, py = f_prev[0, p], f_prev[1, p]
        for i in range(T):
            fx, fy = F[i, 0, p], F[i, 1, p]
            r0 = 0j
            r1 = 0j
            m0 = 0j
            m1 = 0j
            for q in range(m):
                e = eta[q, p]
                if record:
                    up = W0[q] * px + W1[q] * py
                    hq = Eh[q, p] * e + Gh[q, p] * up
                    r0 += Cout[0, q] * e
                    r1 += Cout[1, q] * e
                    m0 += Cout[0, q] * hq
                    m1 += Cout[1, q] * hq
                eta[q, p] = E[q, p] * e + G[q, p] * (W0[q] * fx + W1[q] * fy)
            if record:
                r_out[i, 0, p] = r0.real
                r_out[i, 1, p] = r1.real
                mid_out[i, 0, p] = m0.real
                mid_out[i, 1, p] = m1.real
            px, py = fx, fy


@numba.njit(cache=True, nogil=True)
def run_steps(a, b, t0, M, R, Pf, i0, s, c, inside, fs, cx, cy, ex, ey, edge, read, rho, buf, E, G, Eh, Gh, W0,
              W1, Cout, eta, mid, r, ring, dev, opr, rec_r, rec_f, amp, block):  # pragma: no cover - compiled
    """Steps a ≤ i < b of the regenerative cut, in place on the state (``eta`` (m, P); ``mid``, ``r`` (2, P): the
    displacement at the step's midpoint and start), the surface ring ``buf`` (R, N, L, P) and the records (as
    ``time_domain._run``'s loop: ``ring`` (Pf, 2, P) the last period's displacement, ``dev`` (revolutions, P) its
    squared deviation summed per revolution, ``opr`` the once-per-revolution samples, ``rec_r`` and ``rec_f`` from
    step i0 on). ``block`` (M, P): the force noise's relative fluctuation of each step of the current revolution,
    scaled by ``amp`` (P,)."""
    P = buf.shape[3]
    m = eta.shape[0]
    fx = np.empty(P)
    fy = np.empty(P)
    for i in range(a, b):
        k = i - t0
        rev = i // M
        if i % M == 0:
            for q in range(2):
                for p in range(P):
                    opr[rev, q, p] = r[q, p]
        row = i % Pf
        for p in range(P):
            d0 = r[0, p] - ring[row, 0, p]
            d1 = r[1, p] - ring[row, 1, p]
            dev[rev, p] += d0 * d0 + d1 * d1
            ring[row, 0, p] = r[0, p]
            ring[row, 1, p] = r[1, p]
        w = i % R
        for p in range(P):
            sx, sy = _chip(k, w, p, mid[0, p], mid[1, p], s, c, inside, fs, cx, cy, ex, ey, edge, read, rho, buf)
            g = 1.0 + amp[p] * block[i % M, p]
            fx[p] = sx * g
            fy[p] = sy * g
        if i >= i0:
            for p in range(P):
                rec_r[i - i0, 0, p] = r[0, p]
                rec_r[i - i0, 1, p] = r[1, p]
                rec_f[i - i0, 0, p] = fx[p]
                rec_f[i - i0, 1, p] = fy[p]
        # the modal state's exact step under the held force; the displacement at the next step's midpoint and start
        for p in range(P):
            m0 = 0j
            m1 = 0j
            r0 = 0j
            r1 = 0j
            for q in range(m):
                uq = W0[q] * fx[p] + W1[q] * fy[p]
                e = E[q, p] * eta[q, p] + G[q, p] * uq
                eta[q, p] = e
                hq = Eh[q, p] * e + Gh[q, p] * uq
                m0 += Cout[0, q] * hq
                m1 += Cout[1, q] * hq
                r0 += Cout[0, q] * e
                r1 += Cout[1, q] * e
            mid[0, p] = m0.real
            mid[1, p] = m1.real
            r[0, p] = r0.real
            r[1, p] = r1.real
