#!/usr/bin/env python3
"""Continuum check for `cargo xtask validate crack-penny`: the jump across an insulated penny
crack at the centre of the finite cube, against the infinite-body formula
[T](r) = (4q/(pi lambda)) sqrt(a^2 - r^2).

The cube [0, L]^3 has T = 0 on y = 0, T = 1 on y = L, adiabatic sides, and the crack is the
disc r < a in the plane y = L/2. By symmetry only one eighth is solved (x, z > L/2 mirror
planes, adiabatic; T - 1/2 odd in y, so T = 1/2 on y = L/2 outside the crack). Cell-centred
finite volumes on an n^3 grid of that eighth; the crack's faces are cut by the part of each
face the disc covers (8 x 8 sub-samples). The face temperature on the crack is extrapolated
from the first two cells with zero normal gradient, T_f = (9 T_1 - T_2) / 8.

Prints, per a/L and n, the area-mean jump over the cells wholly on the crack against the
formula (q = Q/A of the cracked cube), and Q/Q0. Needs numpy, scipy and pyamg
(pip install scipy pyamg); n = 128 takes about 30 s per case.
"""
import sys
import time

import numpy as np
import pyamg
import scipy.sparse as sp


def solve(n, ratio, sub=8):
    L, lam = 1.0, 1.0
    a, half = ratio * L, L / 2
    h = half / n
    idx = np.arange(n**3).reshape(n, n, n)  # i (x), j (y), k (z)
    centre = (np.arange(n) + 0.5) * h  # offsets from the cube's centre
    rows, cols, vals = [], [], []
    diag, b = np.zeros(n**3), np.zeros(n**3)
    g = lam * h  # face conductance lam h^2 / h
    for ax in range(3):
        lo, hi = [slice(None)] * 3, [slice(None)] * 3
        lo[ax], hi[ax] = slice(0, n - 1), slice(1, n)
        p, q = idx[tuple(lo)].ravel(), idx[tuple(hi)].ravel()
        rows += [p, q]
        cols += [q, p]
        vals += [-g * np.ones(p.size)] * 2
        np.add.at(diag, p, g)
        np.add.at(diag, q, g)
    top = idx[:, n - 1, :].ravel()
    diag[top] += 2 * g
    b[top] += 2 * g
    X, Z = np.meshgrid(centre, centre, indexing="ij")
    s = (np.arange(sub) + 0.5) / sub
    open_part = np.zeros((n, n))
    for u in s:
        for v in s:
            open_part += np.hypot(X - 0.5 * h + u * h, Z - 0.5 * h + v * h) >= a
    open_part /= sub * sub
    bottom = idx[:, 0, :].ravel()
    diag[bottom] += 2 * g * open_part.ravel()
    b[bottom] += g * open_part.ravel()  # 2 g x 1/2
    A = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n**3, n**3)
    ) + sp.diags(diag)
    T = pyamg.smoothed_aggregation_solver(A).solve(b, tol=1e-11, accel="cg").reshape(n, n, n)
    q = np.sum(2 * g * (1.0 - T[:, n - 1, :])) / half**2
    jump = 2 * ((9 * T[:, 0, :] - T[:, 1, :]) / 8 - 0.5)
    r = np.hypot(X, Z)
    reference = 4 * q / (np.pi * lam) * np.sqrt(np.maximum(a * a - r * r, 0))
    whole = open_part == 0
    return jump[whole].sum() / reference[whole].sum() - 1, q / (lam / L)


if __name__ == "__main__":
    sizes = [int(x) for x in sys.argv[1:]] or [32, 64, 128]
    for ratio in [1 / 8, 1 / 6, 1 / 4]:
        for n in sizes:
            t0 = time.time()
            e, flow = solve(n, ratio)
            print(f"a/L = 1/{round(1 / ratio)}, n = {n}: mean jump / formula - 1 = {100 * e:+.2f} %, "
                  f"Q/Q0 = {flow:.4f} ({time.time() - t0:.1f} s)", flush=True)
