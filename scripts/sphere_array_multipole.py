#!/usr/bin/env python3
"""Effective conductivity of periodic arrays of identical spheres (SC, BCC, FCC) by the
multipole (Rayleigh) method, with an optional imperfect (Kapitza) interface, and its own error.

Independent of any DEM code; a reference for `validation/data/sphere-arrays-multipole.json`
(method and checks: `validation/notes/sphere-arrays.md`).

Method
------
Lord Rayleigh, "On the influence of obstacles arranged in rectangular order upon the properties
of a medium", Phil. Mag. 34 (1892) 481-502; extended to arbitrary multipole order by
R. C. McPhedran & D. R. McKenzie, Proc. R. Soc. Lond. A 359 (1978) 45-63 (simple cubic) and
D. R. McKenzie, R. C. McPhedran & G. H. Derrick, Proc. R. Soc. Lond. A 362 (1978) 211-232
(BCC, FCC); A. S. Sangani & A. Acrivos, Proc. R. Soc. Lond. A 386 (1983) 263-275 (periodic
fundamental solution with Ewald/Hasimoto sums); imperfect interface: H. Cheng & S. Torquato,
Proc. R. Soc. Lond. A 453 (1997) 145-161 (the same method with an interface resistance; not
consulted here: the per-order boundary condition below is derived independently). None of these
papers' tables could be reached from here; no number of theirs is used.

Spheres of radius a (lengths are in units of a below), conductivity lam_i, matrix lam_m; a mean
temperature gradient G along the cube axis z. Near the sphere at the origin, in the matrix,

    T(x) = sum_{l,m} [ A_lm r^l + B_lm r^-(l+1) ] Y_lm(x/r),

Y_lm the orthonormal complex spherical harmonics (Condon-Shortley phase, scipy sph_harm_y).
Every sphere carries the same B_lm (periodicity). The regular part A_lm is the applied field
plus the fields of all other spheres, re-expanded about the origin:

    A_kl = G sqrt(4 pi/3) d_{k1} d_{l0} - f B_1l d_{k1}
           + sum_{n,m} (-1)^(n+l) C(k,l;n,m) S_{n+k, m-l} B_nm                       (1)

    C(k,l;n,m) = sqrt(4 pi (2n+1) / ((2k+1)(2n+2k+1)))
                 * sqrt( (N+M)! (N-M)! / ((k+l)!(k-l)!(n+m)!(n-m)!) ),  N = n+k, M = m-l

(the translation of an irregular solid harmonic Y_nm/r^(n+1) into regular ones r^k Y_kl about
a point at distance > r; checked numerically by `check translation`), and the lattice sums

    S_NM = sum_{j != 0} Y_NM(r_j/|r_j|) / |r_j|^(N+1)        (N even; odd N vanish).

The dipole-dipole sum (N = 2) is only conditionally convergent. It is taken as the Ewald sum
(the periodic potential with a uniform neutralising background, i.e. G is the MEAN gradient
over the cell): then S_2M is the Ewald value (zero for the three cubic lattices) and the
background's r^2 term adds the Lorentz cavity term -(4 pi n/3) B_1l = -f B_1l in (1)
(n = number density; f = n 4 pi/3 in units of a). All S_NM are computed by Ewald summation
(P. P. Ewald, Ann. Phys. 64 (1921) 253; for solid-harmonic sums by Hobson's theorem:

    S_NM = sum_{j!=0} Y_NM(r_j) Q(N+1/2, kappa^2 r_j^2) / r_j^(N+1)
           + (-1)^(N/2) (4 pi / V) / (2N-1)!! sum_{k!=0} F(k) k^(N-2) Y_NM(k) exp(-k^2/(4 kappa^2)),

Q the regularised upper incomplete gamma function, V the cubic cell volume, F(k) the structure
factor of the cell's basis), and compared with direct sums (`check sums`).

Boundary condition at r = a, per order l (derived in the note). Perfect interface (T and
lam dT/dr continuous):  B_lm = -beta_l a^(2l+1) A_lm,
    beta_l = l (lam_i - lam_m) / (l lam_i + (l+1) lam_m).
Kapitza interface of conductance h (q_r continuous, T_in - T_out = q_r / h): the same with
lam_i replaced, order by order, by
    lam_l' = lam_i / (1 + l lam_i / (h a)).
For l = 1 this is Hasselman & Johnson (J. Compos. Mater. 21 (1987) 508) equivalent sphere.

Solving (1) with the boundary condition for B_lm, l odd <= L, m = 0 mod 4 (the field along a
fourfold axis: T odd in z, invariant under a quarter turn about z), gives

    lam_e / lam_m = 1 - 3 f sqrt(3/(4 pi)) B_10 / G        (a = 1)

(the mean flux from the dipole moment; exact for any interface law, derivation in the note).
L = 1 gives Clausius-Mossotti / Maxwell (with lam_1' for an interface, Hasselman-Johnson).

Error: the truncation order L is raised in steps of 2 until three successive changes are below
1e-10 relative or L reaches --lmax; the reported error is the larger of the last three changes and a
geometric-tail estimate d_L * r/(1-r), r the largest ratio d_k/d_(k-2) of successive changes over
the last four steps (see `error_estimate`).

Usage
-----
  python3 scripts/sphere_array_multipole.py case sc 0.3 10          # one case
  python3 scripts/sphere_array_multipole.py case sc 0.3 10 --h 1    # h a / lam_m = 1
  python3 scripts/sphere_array_multipole.py check all               # the self-checks
  python3 scripts/sphere_array_multipole.py fd sc 0.3 10 32 48 64 96 128 -o fd1.json
        # finite-volume brute force (SC only): a grid ladder, extrapolated, against the multipole
  python3 scripts/sphere_array_multipole.py fd sc 0.3 10 32 48 64 96 128 --h 0.1 --shifts 8 -o fd2.json
        # with an interface: the mean over 8 random sub-cell shifts of the sphere per grid
  python3 scripts/sphere_array_multipole.py table -o validation/data/sphere-arrays-multipole.json \
        --fv fd1.json fd2.json ...   # the table, with the checks and the FV ladders in its header

The committed table embeds ladders for SC f = 0.3 (contrast 10, 0.1; h a/lam_m = 0.1, 10 with 8
shifts), 0.4, 0.45 (contrast 10), 0.5 (contrast 10, 50: 32..128; h a/lam_m = 0.1, 10: 64 80 96
112 with 4 shifts).

Needs numpy and scipy (a scratch venv outside the repository:
python3 -m venv /tmp/venv-ref && /tmp/venv-ref/bin/pip install numpy scipy).
"""
import argparse
import json
import math
import sys
import time

import numpy as np
from scipy.special import gammaincc, gammaln, sph_harm_y

LATTICES = {
    # basis of the conventional cubic cell (side c), and the touching fraction
    "sc": ([(0.0, 0.0, 0.0)], math.pi / 6.0),
    "bcc": ([(0.0, 0.0, 0.0), (0.5, 0.5, 0.5)], math.sqrt(3.0) * math.pi / 8.0),
    "fcc": (
        [(0.0, 0.0, 0.0), (0.0, 0.5, 0.5), (0.5, 0.0, 0.5), (0.5, 0.5, 0.0)],
        math.sqrt(2.0) * math.pi / 6.0,
    ),
}


def cell_side(lattice, f):
    """Side of the cubic cell, in units of the sphere radius, for volume fraction f."""
    basis, f_touch = LATTICES[lattice]
    if not 0.0 < f < f_touch:
        raise ValueError(f"{lattice}: f = {f} outside (0, {f_touch:.6f})")
    return (len(basis) * 4.0 * math.pi / 3.0 / f) ** (1.0 / 3.0)


def _angles(v):
    r = np.linalg.norm(v, axis=-1)
    th = np.arccos(np.clip(v[..., 2] / r, -1.0, 1.0))
    ph = np.arctan2(v[..., 1], v[..., 0])
    return r, th, ph


def _ln_double_factorial_odd(n):
    """ln((2n-1)!!) = ln((2n)! / (2^n n!))."""
    return gammaln(2 * n + 1) - n * math.log(2.0) - gammaln(n + 1)


def lattice_points(lattice, c, rcut):
    basis, _ = LATTICES[lattice]
    h = int(math.ceil(rcut / c)) + 1
    g = np.arange(-h, h + 1)
    T = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3).astype(float)
    pts = np.concatenate([(T + np.array(b)) * c for b in basis])
    r = np.linalg.norm(pts, axis=1)
    keep = (r > 1e-12) & (r <= rcut)
    return pts[keep]


def lattice_sums(lattice, c, nmax, ms=None, kappa=None, rcut_cells=6.0, hmax=6):
    """Ewald lattice sums S[N][M] = sum_{j!=0} Y_NM(r_j) / r_j^(N+1) for even N <= nmax.

    ms(N) gives the M to compute (default: multiples of 4, |M| <= N). Returns a dict
    {(N, M): complex}."""
    if ms is None:
        ms = lambda N: [M for M in range(-N, N + 1) if M % 4 == 0]
    basis, _ = LATTICES[lattice]
    V = c**3
    if kappa is None:
        kappa = math.sqrt(math.pi) / c
    # real space
    pts = lattice_points(lattice, c, rcut_cells * c)
    r, th, ph = _angles(pts)
    # reciprocal space (cubic cell with basis): k = 2 pi h / c
    g = np.arange(-hmax, hmax + 1)
    H = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3).astype(float)
    H = H[np.any(H != 0, axis=1)]
    kv = 2.0 * math.pi * H / c
    F = np.zeros(len(H))
    for b in basis:
        F += np.cos(2.0 * math.pi * H @ np.array(b))
    keepk = np.abs(F) > 1e-9
    kv, F = kv[keepk], F[keepk]
    k, kth, kph = _angles(kv)
    out = {}
    for N in range(2, nmax + 1, 2):
        q = gammaincc(N + 0.5, (kappa * r) ** 2)
        wr = q / r ** (N + 1)
        lnw = (N - 2) * np.log(k) - k**2 / (4 * kappa**2) - _ln_double_factorial_odd(N)
        wk = (-1) ** (N // 2) * (4 * math.pi / V) * F * np.exp(lnw)
        for M in ms(N):
            yr = sph_harm_y(N, M, th, ph)
            yk = sph_harm_y(N, M, kth, kph)
            out[(N, M)] = np.sum(yr * wr) + np.sum(yk * wk)
    return out


def direct_sums(lattice, c, nmax, ms, rcut_cells=20.0):
    """Plain spherical-cutoff sums, for the check of the Ewald sums (absolutely convergent for
    N >= 4; N = 4 converges slowly)."""
    pts = lattice_points(lattice, c, rcut_cells * c)
    r, th, ph = _angles(pts)
    out = {}
    for N in range(4, nmax + 1, 2):
        w = 1.0 / r ** (N + 1)
        for M in ms(N):
            out[(N, M)] = np.sum(sph_harm_y(N, M, th, ph) * w)
    return out


def _ln_norm_R(n, m):
    return 0.5 * math.log(4 * math.pi / (2 * n + 1)) - 0.5 * (gammaln(n + m + 1) + gammaln(n - m + 1))


def _ln_norm_I(n, m):
    return 0.5 * math.log(4 * math.pi / (2 * n + 1)) + 0.5 * (gammaln(n + m + 1) + gammaln(n - m + 1))


def translation_coef(k, l, n, m):
    """Y_nm(x-b)/|x-b|^(n+1) = sum_{k,l} translation_coef(k,l,n,m) r^k Y_kl(x) Y_{n+k,m-l}(b)/b^(n+k+1)."""
    N, M = n + k, m - l
    return (-1) ** (n + l) * math.exp(_ln_norm_R(k, l) + _ln_norm_I(N, M) - _ln_norm_I(n, m))


def indices(L, full=False):
    """Unknowns (l, m): l odd <= L, and m = 0 mod 4 (or every m when full)."""
    return [(l, m) for l in range(1, L + 1, 2) for m in range(-l, l + 1) if full or m % 4 == 0]


def betas(L, contrast, h=None):
    """beta_l, l = 0..L, for lam_i/lam_m = contrast (math.inf: perfectly conducting) and an
    interface conductance h (in units lam_m / a; None = perfect interface)."""
    out = np.zeros(L + 1)
    for l in range(1, L + 1):
        if h is None:
            if math.isinf(contrast):
                out[l] = 1.0
            else:
                out[l] = l * (contrast - 1.0) / (l * contrast + l + 1.0)
        else:
            lam = h / l if math.isinf(contrast) else contrast / (1.0 + l * contrast / h)
            out[l] = l * (lam - 1.0) / (l * lam + l + 1.0)
    return out


class Array:
    """One lattice at one volume fraction: lattice sums and the interaction matrix up to lmax."""

    def __init__(self, lattice, f, lmax, full=False):
        self.lattice, self.f, self.lmax, self.full = lattice, f, lmax, full
        self.c = cell_side(lattice, f)
        ms = (lambda N: list(range(-N, N + 1))) if full else None
        self.sums = lattice_sums(lattice, self.c, 2 * lmax, ms=ms)
        self.idx = indices(lmax, full)
        n = len(self.idx)
        T = np.zeros((n, n), dtype=complex)
        for i, (k, l) in enumerate(self.idx):
            for j, (nn, m) in enumerate(self.idx):
                N, M = nn + k, m - l
                T[i, j] = translation_coef(k, l, nn, m) * self.sums[(N, M)]
                if k == 1 and nn == 1 and l == m:
                    T[i, j] -= f  # the background's Lorentz term (Ewald convention)
        self.T = T

    def solve(self, contrast, h=None, L=None):
        """lam_e/lam_m truncated at order L (odd, <= lmax)."""
        L = self.lmax if L is None else L
        sel = [i for i, (l, m) in enumerate(self.idx) if l <= L]
        idx = [self.idx[i] for i in sel]
        T = self.T[np.ix_(sel, sel)]
        b = betas(L, contrast, h)
        bl = np.array([b[l] for (l, m) in idx])
        A = np.eye(len(idx)) + bl[:, None] * T
        rhs = np.zeros(len(idx), dtype=complex)
        i10 = idx.index((1, 0))
        G = 1.0
        rhs[i10] = -bl[i10] * G * math.sqrt(4 * math.pi / 3)
        B = np.linalg.solve(A, rhs)
        val = 1.0 - 3.0 * self.f * math.sqrt(3.0 / (4 * math.pi)) * B[i10] / G
        return val.real, B, idx


def error_estimate(vals):
    """vals: lam_e at L = 1, 3, 5, ... Estimated truncation error of the last one: the larger of
    the last three changes and a geometric tail d r/(1-r), d the last change, r the LARGEST ratio of successive changes
    over the last four steps (the ratio oscillates from step to step near touching; r >= 0.95 is
    treated as no convergence: 20 d)."""
    if len(vals) < 3:
        return float("inf")
    d = [abs(vals[i + 1] - vals[i]) for i in range(len(vals) - 1)]
    rs = [d[i + 1] / d[i] for i in range(max(0, len(d) - 5), len(d) - 1) if d[i] > 0]
    r = max(rs) if rs else 0.0
    tail = d[-1] * r / (1.0 - r) if r < 0.95 else 20.0 * d[-1]
    return max(max(d[-3:]), tail)


def converge(lattice, f, contrast, h=None, lmax=61, tol=1e-10, arr=None):
    """Raise L until three successive changes < tol (relative) or L = lmax. Returns a dict."""
    arr = arr or Array(lattice, f, lmax)
    vals, Ls = [], []
    for L in range(1, arr.lmax + 1, 2):
        v, _, _ = arr.solve(contrast, h, L)
        vals.append(v)
        Ls.append(L)
        if len(vals) >= 4 and all(abs(vals[-k] - vals[-k - 1]) < tol * v for k in (1, 2, 3)):
            break
    err = error_estimate(vals)
    return {
        "lattice": lattice,
        "f": f,
        "contrast": contrast,
        "h_a_over_lambda_m": h,
        "lambda_e_over_lambda_m": vals[-1],
        "L": Ls[-1],
        "change_from_L_minus_2": vals[-1] - vals[-2],
        "change_from_L_minus_4": vals[-1] - vals[-3],
        "estimated_abs_error": err,
        "estimated_rel_error": err / vals[-1],
        "ladder": dict(zip(Ls, vals)),
    }


def maxwell(f, contrast, h=None):
    b = betas(1, contrast, h)[1]
    return 1.0 + 3.0 * f * b / (1.0 - f * b)


def hasselman_johnson(f, contrast, h):
    """analytic.md section 8 (Hasselman & Johnson 1987), lam_m = 1, alpha = a_K/a = 1/h."""
    li, al = contrast, 1.0 / h
    num = li * (1 + 2 * al) + 2 + 2 * f * (li * (1 - al) - 1)
    den = li * (1 + 2 * al) + 2 - f * (li * (1 - al) - 1)
    return num / den


# ----------------------------------------------------------------------------- checks


def rayleigh_k(lattice):
    """K in lam_e/lam_m = 1 + 3 f b1 / (1 - f b1 - K b1 b3 f^(10/3) + ...), from the lattice
    sums (b1, b3 = beta_1, beta_3): K = sum_m T[(1,0),(3,m)] T[(3,m),(1,0)] / f^(10/3)."""
    f = 0.01
    arr = Array(lattice, f, 3)
    i10 = arr.idx.index((1, 0))
    s = sum(arr.T[i10, j] * arr.T[j, i10] for j, (l, m) in enumerate(arr.idx) if l == 3)
    return (s / f ** (10.0 / 3.0)).real


def check_translation():
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(5):
        x = rng.normal(size=3) * 0.25
        bv = rng.normal(size=3)
        bv *= 1.5 / np.linalg.norm(bv)
        for n, m in [(1, 0), (3, -2), (5, 4), (7, 7)]:
            r, th, ph = _angles(x - bv)
            exact = sph_harm_y(n, m, th, ph) / r ** (n + 1)
            rx, thx, phx = _angles(x)
            rb, thb, phb = _angles(bv)
            s = 0.0
            for k in range(0, 60):
                for l in range(-k, k + 1):
                    if abs(m - l) > n + k:
                        continue
                    s += (translation_coef(k, l, n, m) * rx**k * sph_harm_y(k, l, thx, phx)
                          * sph_harm_y(n + k, m - l, thb, phb) / rb ** (n + k + 1))
            worst = max(worst, abs(s - exact) / abs(exact))
    print(f"translation formula: worst relative error {worst:.2e} (60 terms, |x|/|b| ~ 0.2)")
    return worst


def check_sums():
    worst = {}
    for lat in LATTICES:
        c = cell_side(lat, 0.3)
        ms = lambda N: list(range(-N, N + 1))
        e = lattice_sums(lat, c, 12, ms=ms)
        e2 = lattice_sums(lat, c, 12, ms=ms, kappa=1.6 * math.sqrt(math.pi) / c, rcut_cells=5, hmax=9)
        d = direct_sums(lat, c, 12, ms=ms, rcut_cells=24.0)
        s2 = max(abs(e[(2, M)]) for M in range(-2, 3))
        nz = max(abs(e[(N, M)]) for N in range(4, 13, 2) for M in range(-N, N + 1) if M % 4)
        kap = max(abs(e[k] - e2[k]) / abs(e[(k[0], 0)]) for k in e if k[0] >= 4)
        dd = {N: max(abs(e[(N, M)] - d[(N, M)]) for M in range(-N, N + 1)) / abs(e[(N, 0)])
              for N in range(4, 13, 2)}
        print(f"{lat}: S_2M (Ewald) max |.| = {s2:.1e}; S_NM for M != 0 mod 4: {nz:.1e}; "
              f"two Ewald splittings differ by {kap:.1e}; Ewald vs direct (r < 24 c) rel.: "
              + ", ".join(f"N={N}: {v:.1e}" for N, v in dd.items()))
        worst[lat] = (s2, nz, kap, dd)
    return worst


def check_all():
    print("== translation theorem")
    check_translation()
    print("== lattice sums")
    check_sums()
    print("== symmetry: m = 0 mod 4 against every m, L = 11")
    for lat, f in [("sc", 0.5), ("bcc", 0.6), ("fcc", 0.7)]:
        a = Array(lat, f, 11).solve(10.0)[0]
        b = Array(lat, f, 11, full=True).solve(10.0)[0]
        print(f"{lat} f={f} contrast 10: {a:.12f} vs {b:.12f} (diff {a - b:.1e})")
    print("== L = 1 is Clausius-Mossotti (Maxwell); with an interface, Hasselman-Johnson")
    for lat in LATTICES:
        for con, h in [(10.0, None), (0.1, None), (10.0, 1.0), (50.0, 0.1), (10.0, 10.0)]:
            arr = Array(lat, 0.2, 1)
            v = arr.solve(con, h, 1)[0]
            ref = maxwell(0.2, con, h) if h is None else hasselman_johnson(0.2, con, h)
            print(f"  {lat} contrast {con} h {h}: L=1 {v:.15f}  formula {ref:.15f}  diff {v - ref:.1e}")
    print("== interface limits: h -> inf gives the perfect interface, h -> 0 the insulating sphere")
    for lat, f in [("sc", 0.4), ("fcc", 0.6)]:
        arr = Array(lat, f, 21)
        p = arr.solve(10.0, None)[0]
        ph = arr.solve(10.0, 1e9)[0]
        z = arr.solve(0.0, None)[0]
        zh = arr.solve(10.0, 1e-9)[0]
        print(f"  {lat} f={f}: perfect {p:.10f} h=1e9 {ph:.10f}; insulating {z:.10f} h=1e-9 {zh:.10f}")
    print("== dilute limit: lam_e = 1 + 3 f b1 / (1 - f b1 - K b1 b3 f^(10/3))")
    for lat in LATTICES:
        print(f"  {lat}: K = {rayleigh_k(lat):.5f}")
    for lat in LATTICES:
        K = rayleigh_k(lat)
        for con in [10.0, 0.1, math.inf]:
            b = betas(3, con)
            for f in [0.001, 0.01, 0.05]:
                v = converge(lat, f, con, lmax=15)["lambda_e_over_lambda_m"]
                mx = maxwell(f, con)
                r3 = 1 + 3 * f * b[1] / (1 - f * b[1] - K * b[1] * b[3] * f ** (10 / 3))
                print(f"  {lat} contrast {con} f={f}: multipole {v:.12f}  Maxwell {mx:.12f} "
                      f"(diff {v - mx:+.2e})  with f^10/3 term {r3:.12f} (diff {v - r3:+.2e}, "
                      f"f^(14/3) = {f ** (14 / 3):.1e})")


# ----------------------------------------------------------------------------- brute force


def fv_solve(lattice, f, contrast, n, sub=4, tol=1e-10, verbose=False, h_int=None, shift=(0.0, 0.0, 0.0)):
    """Finite-volume brute force on an n^3 grid of the SC unit cell (one sphere, periodic images):
    two-point fluxes between cell centres; the conductance of each face is the parallel mean,
    over sub x sub lines normal to the face, of each line's exact series resistance between the
    two cell centres (its length inside the sphere is computed exactly). Periodic fluctuation
    under a unit mean gradient along z, PCG preconditioned by the homogeneous periodic
    Laplacian (FFT). An interface conductance h_int (units lam_m/a) sits on the faces whose two
    cell centres lie on opposite sides of the sphere surface: in series with the face's bulk
    conductance, a resistance 1/(h_int |n.e|) per unit area, |n.e| the normal's component along
    the line of centres where that line crosses the surface (= its half-chord / a). With it, the
    three families of faces together pass h_int dT per unit interface area (sum of (n.e)^2 = 1).
    shift moves the sphere's centre by shift * (grid step) along x, y, z (averaging over shifts
    smooths the staircase of the node-based interface). Returns lam_e/lam_m (lam_m = 1)."""
    if lattice != "sc":
        raise ValueError("the brute force is written for the simple cubic cell only")
    c = cell_side("sc", f)
    hgrid = c / n

    def wrap(x):  # minimum image, in [-c/2, c/2)
        return (x + 0.5 * c) % c - 0.5 * c

    lam_i = contrast
    ctrs = [0.5 * c + shift[k] * hgrid for k in range(3)]
    xs = (np.arange(n) + 0.5) * hgrid  # cell centres
    off = (np.arange(sub) + 0.5) / sub - 0.5  # sub-line offsets across a face, in cells
    lam = []
    for d in range(3):
        t1, t2 = [a for a in range(3) if a != d]
        # face between cell i and i+1 along d: segment [xs[i], xs[i] + h] along d
        lam_d = np.zeros((n, n, n))
        for o1 in off:
            for o2 in off:
                # transverse coordinates of the line, squared distance to the sphere axis
                u = wrap(xs + o1 * hgrid - ctrs[t1])
                v = wrap(xs + o2 * hgrid - ctrs[t2])
                rho2 = u[:, None] ** 2 + v[None, :] ** 2  # (t1, t2)
                s = np.sqrt(np.clip(1.0 - rho2, 0.0, None))  # half-chord (a = 1)
                lo = wrap(xs - ctrs[d])  # segment start along d, relative to the centre
                hi = lo + hgrid
                ins = 0.0
                for img in (-c, 0.0, c):  # the sphere and its images along the line
                    ins = ins + np.clip(np.minimum(hi[:, None, None], s[None] + img)
                                        - np.maximum(lo[:, None, None], -s[None] + img), 0.0, None)
                res = ins / lam_i + (hgrid - ins) / 1.0
                lam_line = hgrid / res  # (d, t1, t2)
                lam_d += lam_line
        lam_d /= sub * sub
        if h_int is not None:
            # the interface lies between two nodes when one centre is inside the sphere and the
            # other outside; the face then carries 1/(h_int |n.e|) in series, n.e taken where
            # the line joining the two centres crosses the surface (|n.e| = its half-chord / a)
            rc2 = wrap(xs - ctrs[t1])[:, None] ** 2 + wrap(xs - ctrs[t2])[None, :] ** 2  # central line
            sc = np.sqrt(np.clip(1.0 - rc2, 0.0, None))
            lo = wrap(xs - ctrs[d])
            hi = wrap(xs + hgrid - ctrs[d])
            inside_p = lo[:, None, None] ** 2 + rc2[None] < 1.0
            inside_q = hi[:, None, None] ** 2 + rc2[None] < 1.0
            cut = inside_p != inside_q
            pen = np.where(cut, 1.0 / (h_int * np.maximum(sc[None], 1e-300)), 0.0)
            lam_d = hgrid / (hgrid / lam_d + pen)
        # reorder axes (d, t1, t2) -> (x, y, z)
        order = [d, t1, t2]
        lam.append(np.transpose(lam_d, np.argsort(order)))
    h2 = hgrid * hgrid

    def K(t):
        out = np.zeros_like(t)
        for d in range(3):
            dt = np.roll(t, -1, axis=d) - t  # t_{p+d} - t_p
            flux = lam[d] * dt
            out -= flux - np.roll(flux, 1, axis=d)
        return out / h2

    G = 1.0
    rhs = (lam[2] - np.roll(lam[2], 1, axis=2)) * G / hgrid
    kk = 2.0 * np.pi * np.fft.fftfreq(n)
    eig = sum((2.0 - 2.0 * np.cos(k)) for k in np.meshgrid(kk, kk, kk, indexing="ij")) / h2
    lref = math.sqrt(max(lam_i, 1.0) * min(lam_i, 1.0)) if lam_i > 0 else 1.0
    eig[0, 0, 0] = 1.0

    def prec(r):
        z = np.fft.ifftn(np.fft.fftn(r) / (lref * eig)).real
        return z - z.mean()

    t = np.zeros((n, n, n))
    r = rhs - K(t)
    z = prec(r)
    p = z.copy()
    rz = np.vdot(r, z)
    r0 = np.linalg.norm(rhs)
    it = 0
    while np.linalg.norm(r) > tol * r0 and it < 2000:
        Kp = K(p)
        alpha = rz / np.vdot(p, Kp)
        t += alpha * p
        r -= alpha * Kp
        z = prec(r)
        rz_new = np.vdot(r, z)
        p = z + (rz_new / rz) * p
        rz = rz_new
        it += 1
    # mean flux along z (with lam_m = 1, G = 1): lam_e = < lam_z (t_{p+z} - t_p + G h) / h >
    dtz = np.roll(t, -1, axis=2) - t
    lam_e = np.mean(lam[2] * (dtz + G * hgrid) / hgrid) / G
    if verbose:
        print(f"    n={n}: {it} PCG iterations, lam_e = {lam_e:.8f}")
    return lam_e, it


def fv_extrapolate(ns, vals):
    """Least-squares extrapolations to h = 0 of a finite-volume ladder, h = 1/n: models
    v = v0 + c1 h (+ c2 h^2, or + c2 h^1.5), on the finest 3 and 4 grids. Their spread is the
    brute force's own uncertainty."""
    ns, vals = np.asarray(ns, float), np.asarray(vals, float)
    out = {}
    for k in (3, 4):
        if len(ns) < k:
            continue
        h, v = 1.0 / ns[-k:], vals[-k:]
        for name, extra in (("h", []), ("h+h^2", [h * h]), ("h+h^1.5", [h**1.5])):
            if len(extra) + 2 > k:
                continue
            A = np.stack([np.ones_like(h), h] + extra, 1)
            out[f"{name} on finest {k}"] = float(np.linalg.lstsq(A, v, rcond=None)[0][0])
    return out


def fd_check(lattice, f, contrast, ns, out_path=None, sub=4, h=None, shifts=0):
    """A finite-volume ladder against the multipole value. shifts > 0: at each grid, the mean over
    that many random sub-cell shifts of the sphere (seeded), with its standard error; the
    extrapolation then fits the means (the staircase of a node-based interface is noise in n)."""
    ladder = []
    rng = np.random.default_rng(0)
    for n in ns:
        t0 = time.time()
        if shifts:
            sh = rng.uniform(-0.5, 0.5, (shifts, 3))
            runs = [fv_solve(lattice, f, contrast, n, sub=sub, h_int=h, shift=x) for x in sh]
            vs = [r[0] for r in runs]
            v, it = float(np.mean(vs)), max(r[1] for r in runs)
            se = float(np.std(vs, ddof=1) / math.sqrt(len(vs)))
        else:
            v, it = fv_solve(lattice, f, contrast, n, sub=sub, h_int=h)
            se = None
        row = {"n": n, "lambda_e": v, "pcg_iterations": it, "seconds": round(time.time() - t0, 1)}
        if shifts:
            row.update({"shifts": shifts, "standard_error": se})
        ladder.append(row)
        print(f"  n={n:4d}: lam_e = {v:.8f}" + (f" +- {se:.1e} ({shifts} shifts)" if shifts else "")
              + f" ({it} PCG iterations, {time.time() - t0:.1f} s)")
    ext = fv_extrapolate([r["n"] for r in ladder], [r["lambda_e"] for r in ladder])
    ref = converge(lattice, f, contrast, h)
    m = ref["lambda_e_over_lambda_m"]
    print(f"  multipole (L = {ref['L']}): {m:.10f}")
    for k, v in ext.items():
        print(f"  extrapolated ({k}): {v:.6f}  ({(v - m) / m:+.2e} from the multipole)")
    res = {"lattice": lattice, "f": f, "contrast": contrast, "h_a_over_lambda_m": h,
           "sub_lines_per_face": sub * sub,
           "ladder": ladder, "extrapolations": ext, "multipole": m, "multipole_L": ref["L"],
           "finest_rel_diff": (ladder[-1]["lambda_e"] - m) / m,
           "extrapolation_rel_diff_range": ([(min(ext.values()) - m) / m, (max(ext.values()) - m) / m]
                                            if ext else None)}
    if out_path:
        with open(out_path, "w") as fh:
            json.dump(res, fh, indent=1)
    return res


# ----------------------------------------------------------------------------- table


TABLE_FRACTIONS = {
    "sc": [0.05, 0.1, 0.2, 0.3, 0.4, 0.5],
    "bcc": [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.65],
    "fcc": [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7],
}
TABLE_CONTRASTS = [0.1, 10.0, 50.0]
INTERFACE_H = [0.1, 1.0, 10.0]
INTERFACE_FRACTIONS = {"sc": [0.1, 0.3, 0.5], "bcc": [0.1, 0.3, 0.65], "fcc": [0.1, 0.3, 0.7]}


def _row(r, extra):
    row = {k: r[k] for k in ("lattice", "f", "contrast", "h_a_over_lambda_m")}
    row["lambda_e_over_lambda_m"] = round(r["lambda_e_over_lambda_m"], 12)
    row["cell_side_over_radius"] = round(cell_side(r["lattice"], r["f"]), 12)
    row["L"] = r["L"]
    for k in ("change_from_L_minus_2", "change_from_L_minus_4", "estimated_abs_error",
              "estimated_rel_error"):
        row[k] = float(f"{r[k]:.2e}")
    row.update(extra)
    return row


def build_table(lmax=61, fv_files=None):
    """Every case of the table, each converged in L (Array rebuilt with a larger lmax when the
    first one is not enough)."""
    rows, limits, iface = [], [], []
    t0 = time.time()
    for lat, fs in TABLE_FRACTIONS.items():
        for f in fs:
            arr = None
            for lm in (31, lmax, lmax + 20):
                arr = Array(lat, f, lm)
                res = [converge(lat, f, con, None, arr=arr) for con in TABLE_CONTRASTS]
                res += [converge(lat, f, con, None, arr=arr) for con in (math.inf, 0.0)]
                hs = INTERFACE_H if f in INTERFACE_FRACTIONS[lat] else []
                resi = [converge(lat, f, 10.0, h, arr=arr) for h in hs]
                if all(r["L"] < lm or r["estimated_rel_error"] < 1e-9 for r in res + resi):
                    break
            for r in res[: len(TABLE_CONTRASTS)]:
                rows.append(_row(r, {"maxwell": round(maxwell(f, r["contrast"]), 12)}))
            for r, name in zip(res[len(TABLE_CONTRASTS):], ("inf", 0)):
                row = _row(r, {"maxwell": round(maxwell(f, r["contrast"]), 12)})
                row["contrast"] = name
                limits.append(row)
            for r in resi:
                iface.append(_row(r, {"hasselman_johnson": round(hasselman_johnson(f, 10.0, r["h_a_over_lambda_m"]), 12)}))
            print(f"{lat} f={f}: lmax {arr.lmax}, {time.time() - t0:.0f} s", file=sys.stderr)
    worst = max(rows + iface, key=lambda r: r["estimated_rel_error"])
    worst_all = max(rows + iface + limits, key=lambda r: r["estimated_rel_error"])
    checks = table_checks(fv_files)
    checks["hashin_shtrikman_bounds"] = hs_check(rows + [r for r in limits if r["contrast"] != "inf"])
    return {
        "about": ABOUT,
        "source": SOURCE,
        "method": METHOD,
        "error_statement": ERROR_STATEMENT,
        "units": "lambda_e_over_lambda_m: effective conductivity over the matrix's (the tensor is isotropic "
                 "for the three cubic lattices); f: sphere volume fraction; contrast: lambda_i/lambda_m; "
                 "h_a_over_lambda_m: interface conductance h times the sphere radius a over lambda_m "
                 "(null: perfect interface); cell_side_over_radius: side of the conventional cubic cell "
                 "(SC: 1 sphere, BCC: 2, FCC: 4) over a; L: the multipole order used (odd l <= L); "
                 "change_from_L_minus_k: lambda_e(L) - lambda_e(L - k); estimated_*_error: truncation "
                 "error estimate of lambda_e (see error_statement); maxwell / hasselman_johnson: the "
                 "dipole-only (L = 1) value, for context",
        "touching_fraction": {k: v[1] for k, v in LATTICES.items()},
        "worst_estimated_rel_error": worst["estimated_rel_error"],
        "worst_case": {k: worst[k] for k in ("lattice", "f", "contrast", "h_a_over_lambda_m")},
        "worst_estimated_rel_error_including_limit_rows": worst_all["estimated_rel_error"],
        "checks": checks,
        "rows": rows,
        "interface_rows": iface,
        "limit_rows_note": "perfectly conducting (contrast 'inf') and insulating (contrast 0) spheres at the "
                           "same fractions, the limits the published tables (Sangani & Acrivos 1983; "
                           "McPhedran & McKenzie 1978; McKenzie, McPhedran & Derrick 1978) tabulate",
        "limit_rows": limits,
    }


ABOUT = (
    "Effective conductivity of periodic arrays of identical spheres (simple cubic, body-centred "
    "cubic, face-centred cubic) in a matrix: the reference for demcon's periodic sphere-array "
    "validation case (issue 32). Volume fractions from dilute (0.05) to nearly touching (SC 0.5, "
    "BCC 0.65, FCC 0.7; touching at pi/6, sqrt(3) pi/8, sqrt(2) pi/6), contrasts lambda_i/lambda_m "
    "0.1, 10, 50 (rows), an imperfect (Kapitza) interface h a/lambda_m = 0.1, 1, 10 at contrast 10 "
    "(interface_rows), and the perfectly conducting / insulating limits (limit_rows). Each value "
    "carries the multipole order used and its own estimated truncation error; all are far below the "
    "0.1 % target of the validation case. Independent of any DEM code: computed by "
    "scripts/sphere_array_multipole.py (numpy + scipy); method, equations and checks in "
    "validation/notes/sphere-arrays.md. Compare periodic runs (mean gradient, periodic fluctuation) "
    "to it."
)
SOURCE = (
    "scripts/sphere_array_multipole.py (`table -o ...`), a multipole (Rayleigh) solution: Lord "
    "Rayleigh, Phil. Mag. 34 (1892) 481; R. C. McPhedran & D. R. McKenzie, Proc. R. Soc. Lond. A 359 "
    "(1978) 45; D. R. McKenzie, R. C. McPhedran & G. H. Derrick, Proc. R. Soc. Lond. A 362 (1978) 211; "
    "A. S. Sangani & A. Acrivos, Proc. R. Soc. Lond. A 386 (1983) 263; interface: H. Cheng & "
    "S. Torquato, Proc. R. Soc. Lond. A 453 (1997) 145; dipole limit with an interface: Hasselman & "
    "Johnson, J. Compos. Mater. 21 (1987) 508. No number was copied from these papers."
)
METHOD = (
    "T = sum_lm (A_lm r^l + B_lm r^-(l+1)) Y_lm about each sphere; the regular part A is the mean "
    "gradient plus the other spheres' multipoles re-expanded (translation theorem for solid "
    "harmonics, Ewald-summed lattice sums S_NM = sum' Y_NM / r^(N+1), the conditionally convergent "
    "dipole sum taken with the neutralising background, which gives the Lorentz term -f B_1m); per "
    "order l the interface gives B_lm = -beta_l a^(2l+1) A_lm, beta_l = l (lam_l' - lam_m) / (l lam_l' "
    "+ (l+1) lam_m), lam_l' = lam_i (perfect interface) or lam_i / (1 + l lam_i/(h a)) (Kapitza). "
    "Unknowns: odd l <= L, m = 0 mod 4 (field along a fourfold axis), a dense linear solve; "
    "lambda_e/lambda_m = 1 - 3 f sqrt(3/(4 pi)) B_10 / G (a = 1)."
)
ERROR_STATEMENT = (
    "L is raised in steps of 2 until three successive changes are below 1e-10 relative (or L reaches "
    "the cap: 31, then 61, then 81); estimated error = max(the last three changes, d_L r/(1-r)), d_L = "
    "|lambda(L) - lambda(L-2)|, r = the largest ratio of successive changes over the last four steps (a geometric "
    "tail). Convergence in L is geometric for every case: near touching the change shrinks by about "
    "0.5 per step on average (SC 0.5: 0.48 steadily; BCC 0.65 and FCC 0.7: ratios oscillating between "
    "0.3 and 0.85), so L reaches 45-61 there, 9-27 elsewhere. The lattice sums agree between two "
    "Ewald splittings to ~1e-14 and with direct sums; the translation theorem is checked to ~1e-11. "
    "Beyond truncation the values are limited by double precision (~1e-13 relative); the "
    "12-decimal values are therefore good to ~1e-9 or better (worst_estimated_rel_error). "
    "Independent checks ('checks'): the exact dilute expansion to O(f^(10/3)) (with the lattice "
    "constants K), the Hasselman-Johnson / Maxwell values at L = 1, the h -> infinity and h -> 0 "
    "limits, the Hashin-Shtrikman bounds, and a finite-volume brute force on the simple cubic cell "
    "(32^3 to 128^3, extrapolated), which agrees within its own uncertainty (a few 1e-4) at f = 0.3, "
    "0.4, 0.45 and with an interface (h a/lambda_m = 0.1 and 10, f = 0.3). At f = 0.5 its grids put "
    "two cells or fewer across the gap (0.031 a) and its ladder is not asymptotic: +2.8e-4 from the "
    "multipole at 128^3 and rising slowly at contrast 10 (a doubt of ~3e-4 it cannot settle), "
    "+0.95 % and falling at contrast 50, +0.96 % and falling with h a/lambda_m = 0.1, -0.12 % at "
    "112^3 and extrapolating onto it (5e-6) with h a/lambda_m = 10; there the evidence is the "
    "multipole's own geometric convergence."
)


def hs_check(rows):
    """Every perfect-interface value must lie between the Hashin-Shtrikman bounds (Maxwell with the
    roles of the phases swapped is the other bound)."""
    bad, margin = [], float("inf")
    for r in rows:
        c, f = float(r["contrast"]), r["f"]
        m1 = maxwell(f, c)  # spheres in matrix
        # matrix (fraction 1-f, conductivity 1) as inclusions in the sphere phase (conductivity c)
        b = (1.0 - c) / (1.0 + 2.0 * c)
        m2 = c * (1.0 + 2.0 * (1 - f) * b) / (1.0 - (1 - f) * b)
        lo, hi = min(m1, m2), max(m1, m2)
        v = r["lambda_e_over_lambda_m"]
        if not lo <= v <= hi:
            bad.append({k: r[k] for k in ("lattice", "f", "contrast")})
        margin = min(margin, (v - lo) / v, (hi - v) / v)
    return {"what": "every perfect-interface value (rows and contrast-0 limit rows) lies between the "
                    "Hashin-Shtrikman bounds", "cases": len(rows), "violations": bad,
            "smallest_relative_margin": float(f"{margin:.3e}")}


def table_checks(fv_files):
    """The checks embedded in the table's header (fast ones recomputed; finite-volume ladders read
    from the JSON files written by the `fd` command)."""
    c = {}
    c["lattice_sum_S4_sc_unit_cell"] = {
        "value": round(float((lattice_sums("sc", 1.0, 4)[(4, 0)] / math.sqrt(9 / (4 * math.pi))).real), 7),
        "what": "sum' P_4(cos theta)/r^5 over the unit simple cubic lattice (McPhedran & McKenzie 1978 "
                "quote 3.10823: from memory, not re-read)"}
    c["f10_3_coefficient"] = {
        "formula": "lambda_e/lambda_m = 1 + 3 f b1 / (1 - f b1 - K b1 b3 f^(10/3) + O(f^(14/3))), "
                   "b1 = (c-1)/(c+2), b3 = 3(c-1)/(3c+4), c = lambda_i/lambda_m",
        "K_from_our_lattice_sums": {lat: round(rayleigh_k(lat), 5) for lat in LATTICES},
        "K_literature": "SC 1.305 (Rayleigh 1892, as quoted in the brief); 1.3047 SC, 0.1293 BCC, 0.0753 FCC "
                        "(McKenzie, McPhedran & Derrick 1978 / Sangani & Acrivos 1983) quoted from memory: "
                        "the papers' tables were not reachable from here",
    }
    dil = []
    for lat in LATTICES:
        K = rayleigh_k(lat)
        for con in (10.0, 0.1):
            b = betas(3, con)
            for f in (0.01, 0.05):
                v = converge(lat, f, con, lmax=15)["lambda_e_over_lambda_m"]
                r3 = 1 + 3 * f * b[1] / (1 - f * b[1] - K * b[1] * b[3] * f ** (10 / 3))
                dil.append({"lattice": lat, "contrast": con, "f": f, "multipole": round(v, 12),
                            "maxwell": round(maxwell(f, con), 12), "with_f10_3_term": round(r3, 12),
                            "multipole_minus_f10_3_formula": float(f"{v - r3:.2e}"),
                            "f^(14/3)": float(f"{f ** (14 / 3):.1e}")})
    c["dilute_limit"] = {"what": "the multipole value minus the O(f^(10/3)) formula is O(f^(14/3)) or smaller",
                         "cases": dil}
    hj = []
    for lat in ("sc", "fcc"):
        for h in INTERFACE_H:
            v = Array(lat, 0.2, 1).solve(10.0, h, 1)[0]
            hj.append({"lattice": lat, "f": 0.2, "contrast": 10.0, "h_a_over_lambda_m": h,
                       "L1": round(v, 14), "hasselman_johnson": round(hasselman_johnson(0.2, 10.0, h), 14)})
    c["interface_dipole_limit"] = {"what": "at L = 1 the solution is Hasselman-Johnson's formula (analytic.md section 8)",
                                   "cases": hj}
    lim = []
    for lat, f in (("sc", 0.4), ("fcc", 0.6)):
        arr = Array(lat, f, 21)
        lim.append({"lattice": lat, "f": f, "perfect_interface": round(arr.solve(10.0)[0], 10),
                    "h=1e9": round(arr.solve(10.0, 1e9)[0], 10),
                    "insulating": round(arr.solve(0.0)[0], 10), "h=1e-9": round(arr.solve(10.0, 1e-9)[0], 10)})
    c["interface_limits"] = {"what": "contrast 10, L = 21: h -> infinity gives the perfect interface, h -> 0 the insulating sphere",
                             "cases": lim}
    c["finite_volume_brute_force"] = {
        "what": "fv_solve: two-point-flux finite volumes on n^3 grids of the SC cell, face conductance = "
                "parallel mean over 4x4 lines of each line's exact series resistance; an interface h on "
                "the faces whose two centres lie on opposite sides of the surface, in series, "
                "1/(h |n.e|) per unit area, and (being a staircase) averaged over 8 random sub-cell "
                "shifts of the sphere per grid; PCG with an FFT preconditioner; extrapolated to zero "
                "grid step by least squares (models h, h+h^2, h+h^1.5 on the finest 3 and 4 grids); the "
                "spread of the extrapolations is its own uncertainty. At f = 0.5 the gap (0.031 a) has "
                "two cells across it at 128^3: a rough check only",
        "cases": [json.load(open(p)) for p in (fv_files or [])],
    }
    return c


def main():
    ap = argparse.ArgumentParser(
        description="Effective conductivity of periodic SC/BCC/FCC sphere arrays by the multipole "
        "method (see the module docstring).")
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("case")
    p.add_argument("lattice", choices=list(LATTICES))
    p.add_argument("f", type=float)
    p.add_argument("contrast", type=float, help="lam_i/lam_m (inf: perfectly conducting)")
    p.add_argument("--h", type=float, default=None, help="interface conductance h a / lam_m")
    p.add_argument("--shifts", type=int, default=0, help="average over this many random shifts")
    p.add_argument("--lmax", type=int, default=61)
    p = sub.add_parser("check")
    p.add_argument("what", choices=["all", "translation", "sums"])
    p = sub.add_parser("fd")
    p.add_argument("lattice", choices=["sc"])
    p.add_argument("f", type=float)
    p.add_argument("contrast", type=float)
    p.add_argument("n", type=int, nargs="+")
    p.add_argument("-o", "--out", default=None, help="write the ladder as JSON")
    p.add_argument("--h", type=float, default=None, help="interface conductance h a / lam_m")
    p.add_argument("--shifts", type=int, default=0, help="average over this many random shifts")
    p = sub.add_parser("table")
    p.add_argument("-o", "--out", default=None)
    p.add_argument("--lmax", type=int, default=61)
    p.add_argument("--fv", nargs="*", default=[], help="JSON files written by `fd -o`")
    a = ap.parse_args()
    if a.cmd == "case":
        r = converge(a.lattice, a.f, a.contrast, a.h, lmax=a.lmax)
        for L, v in r["ladder"].items():
            print(f"  L={L:3d}  {v:.12f}")
        print(json.dumps({k: v for k, v in r.items() if k != "ladder"}, indent=1))
    elif a.cmd == "check":
        {"all": check_all, "translation": check_translation, "sums": check_sums}[a.what]()
    elif a.cmd == "fd":
        fd_check(a.lattice, a.f, a.contrast, a.n, a.out, h=a.h, shifts=a.shifts)
    elif a.cmd == "table":
        table = build_table(a.lmax, a.fv)
        text = json.dumps(table, indent=1)
        if a.out:
            with open(a.out, "w") as fh:
                fh.write(text + "\n")
        else:
            print(text)


if __name__ == "__main__":
    main()
