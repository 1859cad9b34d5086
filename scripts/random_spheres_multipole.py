#!/usr/bin/env python3
"""Effective conductivity of a periodic cell holding many identical spheres at arbitrary
positions (the random epoxy/silica realisations of `shared/refs/multi-inclusion-fft-realisations.json`),
by the multipole method, with an optional imperfect (Kapitza) interface on every sphere.

Independent of any DEM code; the reference of `multi-inclusion-interface` (issue 32): the same
method as `scripts/sphere_array_multipole.py` (whose translation theorem, normalisations and
per-order interface condition it imports), extended from a Bravais lattice with identical
multipoles on every sphere to a cell of n spheres, each with its own multipoles — the method of
A. S. Sangani & C. Yao, "Bulk thermal conductivity of composites with spherical inclusions",
J. Appl. Phys. 63 (1988) 1334 (not consulted here; no number of theirs is used).

Method
------
Lengths in units of the sphere radius a; cell side c; matrix conductivity 1. Near sphere alpha,
in the matrix,

    T(x) = sum_{l,m} [ A^a_lm r^l + B^a_lm r^-(l+1) ] Y_lm,   l >= 1 (no sphere carries a source)

    A^a_kl = (applied mean gradient G)_kl
             + sum_b sum_{n,m} C(k,l;n,m) S_{n+k,m-l}(r_b - r_a) B^b_nm
             - (4 pi / (3 V)) sum_b B^b_1l d_{k1}                                       (1)

with C the translation coefficient of `sphere_array_multipole.translation_coef` and the shifted
lattice sums

    S_NM(d) = sum_R Y_NM(d + R) / |d + R|^(N+1)     (R over the cell lattice; R = 0 left out when d = 0)

taken as Ewald sums (Hobson's theorem applied to the Ewald split of the periodic Green function):

    S_NM(d) = sum_R Y_NM(d+R) Q(N+1/2, kappa^2 |d+R|^2) / |d+R|^(N+1)
              + (4 pi / V) (-i)^N / (2N-1)!! sum_{k != 0} k^(N-2) Y_NM(k) exp(i k.d - k^2/(4 kappa^2)).

Leaving out k = 0 makes G the MEAN gradient over the cell; the uniform background this implies
adds the last term of (1) (its r^2 potential acts on dipoles only): with identical B on every
sphere it is the Lorentz term -f B_1l of the lattice script. Boundary condition per order
(perfect or Kapitza interface): B^a_lm = -beta_l A^a_lm, beta_l from `betas`. The effective
tensor follows from the dipoles p^a (the l = 1 coefficients as a vector):

    (lambda_e / lambda_m) G = G - (4 pi / V) sum_a p^a .

Truncation at order L (every l <= L, every m: (L+1)^2 - 1 unknowns per sphere). The error of the
truncation is read from the ladder L = 1, 3, 5, ..., and the perfect-interface value is compared
with the realisation's own FFT (64^3, 128^3, extrapolated; its error 1e-4 to 1e-3).

Checks (`check`): the shifted Ewald sums against direct sums; a cell holding the simple-cubic,
BCC and FCC lattices as 8, 2 and 4 arbitrary "random" spheres reproduces the lattice script at
the same truncation order (every m) to round-off.

Usage
-----
  python3 scripts/random_spheres_multipole.py check
  python3 scripts/random_spheres_multipole.py table -o validation/data/multi-inclusion-interface-multipole.json
        [--fractions 0.1 0.3 0.5] [--realisations 2] [--lmax 7]

Needs numpy and scipy (a scratch venv outside the repository).
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
from scipy.special import gammaincc, sph_harm_y
from scipy.sparse.linalg import LinearOperator, gmres

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sphere_array_multipole import (  # noqa: E402
    Array,
    _angles,
    _ln_double_factorial_odd,
    betas,
    cell_side,
    translation_coef,
)

LAMBDA_M = 0.195
LAMBDA_I = 1.5
ALPHAS = [0.0, 0.01, 0.03, 0.1, 0.3, 1.0]


def harmonic_list(nmax):
    """(N, M) for 2 <= N <= nmax, every M, and their positions."""
    hs = [(N, M) for N in range(2, nmax + 1) for M in range(-N, N + 1)]
    return hs, {h: i for i, h in enumerate(hs)}


def unknowns(L):
    return [(l, m) for l in range(1, L + 1) for m in range(-l, l + 1)]


class Cell:
    """n spheres (centres in units of a) in a periodic cube of side c (units of a)."""

    def __init__(self, centres, c, kappa=None, hmax=None):
        self.x = np.asarray(centres, dtype=float) % c
        self.c = c
        self.V = c**3
        self.n = len(self.x)
        self.kappa = kappa if kappa is not None else 3.0 / c * 1.2
        self.hmax = hmax

    def sums(self, nmax, d, self_pair):
        """S_NM(d) for rows of d (P, 3), minimum-image wrapped; self_pair (P,) marks d = 0."""
        hs, _ = harmonic_list(nmax)
        Ns = np.array([h[0] for h in hs])
        Ms = np.array([h[1] for h in hs])
        c, kappa = self.c, self.kappa
        g = np.arange(-1, 2)
        R = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3).astype(float) * c
        out = np.zeros((len(d), len(hs)), dtype=complex)
        # real space, chunked over pairs
        chunk = max(1, 20000 // len(R))
        for s in range(0, len(d), chunk):
            dd = d[s:s + chunk]
            v = (dd[:, None, :] + R[None, :, :]).reshape(-1, 3)
            r, th, ph = _angles(np.where(np.linalg.norm(v, axis=1)[:, None] > 1e-9, v, 1.0))
            zero = np.linalg.norm(v, axis=1) <= 1e-9
            for N in range(2, nmax + 1):
                sel = Ns == N
                w = gammaincc(N + 0.5, (kappa * r) ** 2) / r ** (N + 1)
                w[zero] = 0.0
                y = sph_harm_y(N, Ms[sel][:, None], th[None, :], ph[None, :]) * w[None, :]
                out[s:s + chunk, sel] += y.reshape(sel.sum(), len(dd), len(R)).sum(axis=2).T
        # reciprocal space
        hmax = self.hmax or int(math.ceil(2.0 * kappa * 6.5 * c / (2.0 * math.pi)))
        gk = np.arange(-hmax, hmax + 1)
        H = np.stack(np.meshgrid(gk, gk, gk, indexing="ij"), -1).reshape(-1, 3).astype(float)
        H = H[np.any(H != 0, axis=1) & (np.linalg.norm(H, axis=1) <= hmax)]
        kv = 2.0 * math.pi * H / c
        k, kth, kph = _angles(kv)
        W = np.zeros((len(kv), len(hs)), dtype=complex)
        for N in range(2, nmax + 1):
            sel = Ns == N
            lnw = (N - 2) * np.log(k) - k**2 / (4 * kappa**2) - _ln_double_factorial_odd(N)
            pref = (4 * math.pi / self.V) * (-1j) ** N * np.exp(lnw)
            W[:, sel] = (sph_harm_y(N, Ms[sel][None, :], kth[:, None], kph[:, None]) * pref[:, None])
        for s in range(0, len(d), 2000):
            out[s:s + 2000] += np.exp(1j * d[s:s + 2000] @ kv.T) @ W
        return out

    def matrix(self, L):
        """The interaction matrix T (n u x n u), u = (L+1)^2 - 1, Lorentz term included."""
        idx = unknowns(L)
        u = len(idx)
        hs, pos = harmonic_list(2 * L)
        C = np.zeros((u, u))
        J = np.zeros((u, u), dtype=int)
        for i, (k, l) in enumerate(idx):
            for j, (nn, m) in enumerate(idx):
                C[i, j] = translation_coef(k, l, nn, m) if abs(m - l) <= nn + k else 0.0
                J[i, j] = pos[(nn + k, m - l)] if abs(m - l) <= nn + k else 0
        a, b = np.meshgrid(np.arange(self.n), np.arange(self.n), indexing="ij")
        a, b = a.ravel(), b.ravel()
        d = self.x[b] - self.x[a]
        d -= self.c * np.round(d / self.c)
        S = self.sums(2 * L, d, a == b)
        T = np.empty((self.n, u, self.n, u), dtype=complex)
        for p in range(len(a)):
            T[a[p], :, b[p], :] = C * S[p][J]
        dip = [i for i, (l, m) in enumerate(idx) if l == 1]
        for i in dip:
            T[:, i, :, i] -= 4.0 * math.pi / (3.0 * self.V)
        return T.reshape(self.n * u, self.n * u), idx


def applied(G):
    """Coefficients c_m (m = -1, 0, 1) of G.x = r sum_m c_m Y_1m."""
    gx, gy, gz = G
    s = math.sqrt(3.0 / (8.0 * math.pi))
    return {-1: (gx + 1j * gy) / (2 * s), 0: gz / math.sqrt(3.0 / (4.0 * math.pi)), 1: -(gx - 1j * gy) / (2 * s)}


def dipole(cm):
    """The vector of c_m (m = -1, 0, 1)."""
    s = math.sqrt(3.0 / (8.0 * math.pi))
    return np.array([s * (cm[-1] - cm[1]), -1j * s * (cm[-1] + cm[1]), math.sqrt(3.0 / (4.0 * math.pi)) * cm[0]])


def solve(T, idx, n, V, L, contrast, h, G, direct_limit=2500):
    """lambda_e . G / lambda_m for truncation L (T built at this L)."""
    u = len(idx)
    b = betas(L, contrast, h)
    bl = np.tile(np.array([b[l] for (l, m) in idx]), n)
    a = applied(G)
    rhs1 = np.array([a[m] if l == 1 else 0.0 for (l, m) in idx], dtype=complex)
    rhs = -bl * np.tile(rhs1, n)
    N = n * u
    if N <= direct_limit:
        B = np.linalg.solve(np.eye(N) + bl[:, None] * T, rhs)
    else:
        op = LinearOperator((N, N), matvec=lambda v: v + bl * (T @ v), dtype=complex)
        B, info = gmres(op, rhs, rtol=1e-11, atol=0.0, restart=200, maxiter=20)
        if info != 0:
            raise RuntimeError(f"gmres did not converge (info {info})")
    Bs = B.reshape(n, u)
    i1 = {m: idx.index((1, m)) for m in (-1, 0, 1)}
    p = sum(dipole({m: Bs[s, i1[m]] for m in (-1, 0, 1)}) for s in range(n))
    return np.real(np.asarray(G, dtype=float) - 4.0 * math.pi / V * p)


def check():
    """Shifted sums against direct sums; the lattices as random cells against the lattice script."""
    rng = np.random.default_rng(3)
    c = 6.0
    cell = Cell(np.zeros((1, 3)), c)
    d = rng.uniform(-c / 2, c / 2, size=(3, 3))
    ew = cell.sums(8, d, np.zeros(3, bool))
    hs, _ = harmonic_list(8)
    g = np.arange(-40, 41)
    R = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3).astype(float) * c
    worst = 0.0
    for p in range(len(d)):
        v = d[p] + R
        v = v[np.linalg.norm(v, axis=1) <= 40 * c]
        r, th, ph = _angles(v)
        for j, (N, M) in enumerate(hs):
            if N < 5:
                continue  # slowly or conditionally convergent direct sums
            direct = np.sum(sph_harm_y(N, M, th, ph) / r ** (N + 1))
            worst = max(worst, abs(direct - ew[p, j]) / max(abs(ew[p, j]), 1e-3 / 3.0 ** (N + 1)))
    print(f"shifted Ewald sums against direct sums (N = 5..8, |d+R| <= 40 c): worst relative {worst:.1e}")
    kap = Cell(np.zeros((1, 3)), c, kappa=1.3 * cell.kappa, hmax=14).sums(8, d, np.zeros(3, bool))
    print(f"two Ewald splittings differ by {np.max(np.abs(kap - ew)) / np.max(np.abs(ew)):.1e} (max, relative)")
    L = 7
    for lat, f, cells in [("sc", 0.4, 2), ("bcc", 0.5, 1), ("fcc", 0.6, 1)]:
        ref = Array(lat, f, L, full=True).solve(10.0, None, L)[0]
        refh = Array(lat, f, L, full=True).solve(10.0, 2.0, L)[0]
        cs = cell_side(lat, f)
        from sphere_array_multipole import LATTICES

        basis = np.array(LATTICES[lat][0])
        g = np.arange(cells)
        T0 = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
        pts = np.concatenate([(T0 + bb) * cs for bb in basis]) + rng.uniform(0, cs, 3)
        cl = Cell(pts, cs * cells)
        T, idx = cl.matrix(L)
        v = solve(T, idx, cl.n, cl.V, L, 10.0, None, (0.0, 1.0, 0.0))
        vh = solve(T, idx, cl.n, cl.V, L, 10.0, 2.0, (1.0, 0.0, 0.0))
        print(f"{lat} f = {f} as {cl.n} spheres, L = {L}: lambda_yy {v[1]:.12f} vs lattice {ref:.12f} "
              f"(diff {v[1] - ref:.1e}; off-diagonal {max(abs(v[0]), abs(v[2])):.1e}); "
              f"h a/lam_m = 2: lambda_xx {vh[0]:.12f} vs {refh:.12f} (diff {vh[0] - refh:.1e})")


def tail_error(lad, lmax):
    """Estimated truncation error of lad[lmax] (lad: value by odd order L): the larger of the
    last change and a geometric tail d r/(1-r), r the ratio of the last two changes (r >= 0.9:
    10 d, no convergence claimed)."""
    if lmax < 5:
        return float("inf")
    d1 = abs(lad[lmax] - lad[lmax - 2])
    d2 = abs(lad[lmax - 2] - lad[lmax - 4])
    r = d1 / d2 if d2 > 0 else 0.0
    return max(d1, d1 * r / (1 - r) if r < 0.9 else 10 * d1)


def realisation_table(fractions, n_real, lmax, refs_path):
    refs = json.load(open(refs_path))
    contrast = LAMBDA_I / LAMBDA_M
    rows = []
    for f in fractions:
        fr = refs["by_volume_fraction"][f"{f:g}"]
        for r in fr["realisations"][:n_real]:
            t0 = time.time()
            D = r["D"]
            c = 2.0 / D
            cell = Cell(np.array(r["centres"]) * c, c)
            ladder = {str(a): {} for a in ALPHAS}
            for L in range(1, lmax + 1, 2):
                T, idx = cell.matrix(L)
                for a in ALPHAS:
                    h = None if a == 0.0 else 1.0 / a
                    ladder[str(a)][L] = float(solve(T, idx, cell.n, cell.V, L, contrast, h, (0.0, 1.0, 0.0))[1])
                del T
                print(f"  f {f} realisation {r['realisation']} L {L}: "
                      + " ".join(f"{ladder[str(a)][L]:.6f}" for a in ALPHAS), flush=True)
            out = {"f": f, "realisation": r["realisation"], "n_spheres": cell.n, "L": lmax,
                   "fft_extrapolated_y": r["extrapolated_y"], "seconds": round(time.time() - t0, 1), "alphas": []}
            perfect = ladder[str(0.0)]
            for a in ALPHAS:
                lad = ladder[str(a)]
                ratio = {L: lad[L] / perfect[L] for L in lad}
                out["alphas"].append({
                    "alpha": a,
                    "lambda_yy_W_per_mK": LAMBDA_M * lad[lmax],
                    "estimated_rel_error": tail_error(lad, lmax) / lad[lmax],
                    "ratio_to_perfect": ratio[lmax],
                    "ratio_estimated_rel_error": tail_error(ratio, lmax) / ratio[lmax],
                    "ladder_W_per_mK": {str(L): LAMBDA_M * x for L, x in lad.items()},
                })
            p = out["alphas"][0]["lambda_yy_W_per_mK"]
            out["perfect_vs_fft_rel"] = p / r["extrapolated_y"] - 1.0
            print(f"f {f} realisation {r['realisation']}: perfect {p:.6f} vs FFT {r['extrapolated_y']:.6f} "
                  f"({100 * out['perfect_vs_fft_rel']:+.3f} %), {out['seconds']} s", flush=True)
            rows.append(out)
    return rows


def merge(paths, out):
    """One table of the rows of `paths`, keeping for each (f, realisation) the deepest order."""
    best = {}
    for p in paths:
        for r in json.load(open(p))["rows"]:
            key = (r["f"], r["realisation"])
            if key not in best or r["L"] > best[key]["L"]:
                best[key] = r
    rows = [best[k] for k in sorted(best)]
    doc = {
        "about": "lambda_yy of the FFT realisations of shared/refs/multi-inclusion-fft-realisations.json "
                 "(epoxy 0.195, silica 1.5 W/(m K)) with an interface conductance h on every sphere, "
                 "alpha = lambda_m/(h a); the reference of the periodic mode of multi-inclusion-interface",
        "source": "scripts/random_spheres_multipole.py (multipole method, Ewald sums; validation/notes/"
                  "multi-inclusion-interface-multipole.md)",
        "error_statement": "estimated_rel_error: truncation error of lambda_yy at order L from the last changes of "
                           "the ladder in L (the larger of the last change and its geometric tail; 10x the last "
                           "change when the ratio of changes is >= 0.9); perfect_vs_fft_rel: the perfect-interface "
                           "value against the realisation's own FFT (whose error is 1e-4 to 1e-3)",
        "alphas": ALPHAS,
        "rows": rows,
    }
    json.dump(doc, open(out, "w"), indent=1)
    for r in rows:
        print(f"f {r['f']} realisation {r['realisation']} L {r['L']}: perfect vs FFT {100 * r['perfect_vs_fft_rel']:+.3f} %, "
              "errors " + " ".join(f"{a['estimated_rel_error']:.0e}" for a in r["alphas"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    sub.add_parser("check")
    p = sub.add_parser("table")
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--fractions", type=float, nargs="+", default=[0.1, 0.2, 0.3, 0.4, 0.5])
    p.add_argument("--realisations", type=int, default=2)
    p.add_argument("--lmax", type=int, default=7)
    p.add_argument("--refs", default=os.path.join(os.path.dirname(__file__), "../../shared/refs/multi-inclusion-fft-realisations.json"))
    m = sub.add_parser("merge")
    m.add_argument("-o", "--out", required=True)
    m.add_argument("tables", nargs="+")
    a = ap.parse_args()
    if a.cmd == "check":
        check()
        return
    if a.cmd == "merge":
        merge(a.tables, a.out)
        return
    rows = realisation_table(a.fractions, a.realisations, a.lmax, a.refs)
    json.dump({"rows": rows}, open(a.out, "w"), indent=1)


if __name__ == "__main__":
    main()
