"""The semi-discretisation's step loop over the cut, compiled (numba).

:meth:`toolpoint.stability.sdm._System.monodromy` builds each point's Floquet matrix from m steps over the cut. Each
step is a handful of products of small matrices (n × d, d × d, n × n with n the model's states and d ≤ 2 moving
directions): in NumPy, stacked over the points, each product of a 12 × 4 by a 4 × 12 matrix costs its call's
overhead, not its arithmetic, and building the step maps took more than the step loop itself (an EM16-50-like model,
80 points, m = 80, s = 4: 22 ms for the maps, 15 ms for the delayed terms, 15 ms for the loop; 2026-12-04). Here a
point's steps run in one loop, and a step's maps are built where they are used and not stored.

The expressions are those of the module docstring of :mod:`~toolpoint.stability.sdm` term for term; sums run in loop
order, so results differ from the NumPy products in the last bits. Every array argument is a C-contiguous float64
array (one compiled signature, cached on disk).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def floquet(P, G0, G1, Pfree, H, C, depth, lo, Lw, s, Phi, Ycut):  # pragma: no cover - compiled
    """Floquet matrices of B points, in place: ``Phi`` (B, D, D) and the map to the cut's end ``Ycut`` (B, n, D).

    P (B, n, n) = e^{AΔt}; G0 (B, n, p) = Γ0 − Γ1 and G1 (B, n, p) = Γ1 (the exact step integrals); Pfree (B, n, n)
    the free flight's e^{A(T − t_c)}; H (K, m, p, d) the directional factors per step and C (K, d, n) the moving
    directions' outputs (K = B: each point its own model, K = 1: one for all); depth (B,) in m; ``lo`` (m,) the first
    delayed node of step i's window and ``Lw`` (m, 2, w) its interpolation weights at the step's two ends; the
    delayed displacement is kept at every s-th step.

    Per step, with U0 = a(Γ0 − Γ1)H_i, U1 = aΓ1H_i, K = (I + C U1)⁻¹ (d × d, Woodbury) and W = U1 K:
    M_i = P − U0 C − W (C P − C U0 C), E0_i = U0 − W C U0, E1_i = W, and the state's map over the nodes so far
    Y ← M_i Y + [E0_i, E1_i] (the delayed nodes' weights).
    """
    B, n, D = Ycut.shape
    m, p, d = H.shape[1], H.shape[2], H.shape[3]
    w = Lw.shape[2]
    # one point's work arrays, reused for every point: Y and T (n × D), M (n × n); by shape U0, U1, W, E0 (n × d),
    # CP, R (d × n), CU0, A, K (d × d)
    Y, T, M = np.zeros((n, D)), np.zeros((n, D)), np.zeros((n, n))
    nd, dn, dd = np.zeros((4, n, d)), np.zeros((2, d, n)), np.zeros((3, d, d))
    U0, U1, W, E0 = nd[0], nd[1], nd[2], nd[3]
    CP, R = dn[0], dn[1]
    CU0, A, K = dd[0], dd[1], dd[2]
    for b in range(B):
        kb = b if H.shape[0] > 1 else 0
        kc = b if C.shape[0] > 1 else 0
        a = depth[b]
        for r in range(d):
            for c in range(n):
                acc = 0.0
                for k in range(n):
                    acc += C[kc, r, k] * P[b, k, c]
                CP[r, c] = acc
        Y[:, :] = 0.0
        for r in range(n):
            Y[r, r] = 1.0
        Phi[b, n: n + d, :] = 0.0
        for r in range(d):
            for c in range(n):
                Phi[b, n + r, c] = C[kc, r, c]
        act = n
        for i in range(m):
            # U0 = a(Γ0 − Γ1)H_i, U1 = aΓ1H_i (n × d)
            for r in range(n):
                for e in range(d):
                    s0 = 0.0
                    s1 = 0.0
                    for q in range(p):
                        s0 += G0[b, r, q] * H[kb, i, q, e]
                        s1 += G1[b, r, q] * H[kb, i, q, e]
                    U0[r, e] = a * s0
                    U1[r, e] = a * s1
            # C U0 and I + C U1 (d × d)
            for r in range(d):
                for e in range(d):
                    s0 = 0.0
                    s1 = 0.0
                    for k in range(n):
                        s0 += C[kc, r, k] * U0[k, e]
                        s1 += C[kc, r, k] * U1[k, e]
                    CU0[r, e] = s0
                    A[r, e] = s1 + (1.0 if r == e else 0.0)
            if d == 1:
                K[0, 0] = 1.0 / A[0, 0]
            elif d == 2:
                det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
                K[0, 0] = A[1, 1] / det
                K[0, 1] = -A[0, 1] / det
                K[1, 0] = -A[1, 0] / det
                K[1, 1] = A[0, 0] / det
            else:
                K[:, :] = np.linalg.inv(A)
            for r in range(n):
                for e in range(d):
                    acc = 0.0
                    for k in range(d):
                        acc += U1[r, k] * K[k, e]
                    W[r, e] = acc
            # R = C P − C U0 C (d × n); E0 = U0 − W C U0 (n × d)
            for r in range(d):
                for c in range(n):
                    acc = CP[r, c]
                    for k in range(d):
                        acc -= CU0[r, k] * C[kc, k, c]
                    R[r, c] = acc
            for r in range(n):
                for e in range(d):
                    acc = U0[r, e]
                    for k in range(d):
                        acc -= W[r, k] * CU0[k, e]
                    E0[r, e] = acc
            # M = P − U0 C − W R (n × n)
            for r in range(n):
                for c in range(n):
                    acc = P[b, r, c]
                    for k in range(d):
                        acc -= U0[r, k] * C[kc, k, c] + W[r, k] * R[k, c]
                    M[r, c] = acc
            # Y[:, :act] ← M Y[:, :act]; then the delayed nodes' terms of both ends of the step
            for r in range(n):
                for c in range(act):
                    T[r, c] = 0.0
                for k in range(n):
                    mk = M[r, k]
                    for c in range(act):
                        T[r, c] += mk * Y[k, c]
            for r in range(n):
                for c in range(act):
                    Y[r, c] = T[r, c]
            c0 = n + lo[i] * d
            for r in range(n):
                for j in range(w):
                    l0 = Lw[i, 0, j]
                    l1 = Lw[i, 1, j]
                    for e in range(d):
                        Y[r, c0 + j * d + e] += E0[r, e] * l0 + W[r, e] * l1
            act = max(act, c0 + w * d)
            if (i + 1) % s == 0:
                jn = (i + 1) // s
                for r in range(d):
                    for c in range(D):
                        acc = 0.0
                        for k in range(n):
                            acc += C[kc, r, k] * Y[k, c]
                        Phi[b, n + jn * d + r, c] = acc
        for r in range(n):
            for c in range(D):
                acc = 0.0
                for k in range(n):
                    acc += Pfree[b, r, k] * Y[k, c]
                Phi[b, r, c] = acc
                Ycut[b, r, c] = Y[r, c]
