#!/usr/bin/env python3
"""Periodic voxel FFT homogenisation of steady scalar conduction: a reference for demcon.

Independent of any DEM code and of other FFT codes (written from the equations below, numpy +
scipy only). It gives the effective conductivity tensor of a periodic box that holds shaped
inclusions (spheroids, flat or round-ended cylinders) in a matrix, on a sequence of voxel grids,
and an extrapolation to zero voxel size with an error estimate.

Problem and units
-----------------
Periodic box [0, Lx) x [0, Ly) x [0, Lz) (metres; any consistent length unit works, only ratios
matter). Conductivities lambda in W/(m K) (any unit: the output is in the input's unit). Heat
flux q = -lambda grad T. Temperature T(x) = E . x + T~(x), E the imposed mean gradient, T~
periodic. The effective tensor is defined by  <q> = -lambda_e E, i.e. column j of lambda_e is
<lambda (E + grad T~)> for E = e_j (unit gradient, K/m). It is symmetric positive definite and
reported with a positive sign.

Method (Fourier-Galerkin, Zeman et al. 2010; Vondrejc, Zeman & Marek 2014)
--------------------------------------------------------------------------
Unknown: the gradient field e = E + e~ with e~ a compatible (curl-free, zero-mean, periodic)
field. Trial space: trigonometric polynomials on the voxel grid (n1 x n2 x n3 Fourier modes),
coefficients evaluated at the voxel centres (midpoint quadrature of lambda per voxel). With the
projection onto compatible fields of the identity reference medium,

    G = F^-1 Gamma^ F,   Gamma^(xi) = xi xi^T / |xi|^2 (xi != 0),  Gamma^(0) = 0,

(an orthogonal projection; F the discrete Fourier transform) the Galerkin equation is

    G[ lambda e~ ] = -G[ lambda E ],

whose operator G lambda G is symmetric positive definite on the range of G, so it is solved by
scipy.sparse.linalg.cg on a LinearOperator (3 forward + 3 inverse real FFTs per iteration), from
e~ = 0, to a relative residual ||G lambda e - 0|| / ||G lambda E|| <= tol (default 1e-8).
Frequencies: plain Fourier (spectral) frequencies xi_k = 2 pi m_k / L_k, m_k = -(n_k-1)/2 ...
(n_k-1)/2, NOT finite-difference-consistent ones. Grid sizes are odd by default, so there is no
Nyquist mode; if an even size is forced (--sizes exact), the modes with a Nyquist component are
dropped from the trial space (Gamma^ = 0 there), which keeps the fields real and the scheme
conforming, except the pure-axis ones (N,0,0), (0,N,0), (0,0,N), kept with Gamma^ = e_k e_k^T
(so that laminates stay exact). Odd grids are the tested, recommended setting.
The conductivity may be a full symmetric 3x3 tensor per voxel (used by the composite voxels).

Voxel images
------------
plain      a voxel takes lambda_i when its centre lies inside a shape (or a periodic image of
           one), else lambda_m. First-order "staircase" error in h, with oscillations because
           the image's volume fraction jumps with the resolution.
composite  "laminate" composite voxels (Gelebart & Ouaki 2015; Kabel, Merkert & Schneider 2015):
           each voxel that the interface may cross is sub-sampled on s^3 points to get its
           inclusion fraction phi (default s = 8; s = 4 leaves image volume-fraction errors up
           to 1e-3 on coarse grids, which makes the convergence visibly non-monotone); with the
           local interface normal n its tensor is the rank-one laminate
               lambda_vox = lambda_R n n^T + lambda_V (I - n n^T),
               lambda_V = phi lambda_i + (1-phi) lambda_m   (Voigt, along the interface)
               1/lambda_R = phi/lambda_i + (1-phi)/lambda_m (Reuss, across it).
           Normal, "--normal gradient" (default): the gradient of the shape's level function at
           the voxel centre (central differences), except for a voxel that two shapes' surfaces
           cross, which uses the centroid rule; "--normal centroid": always the direction from
           the centroid of the voxel's inside sub-points to the voxel centre. A voxel whose
           normal cannot be defined (inside sub-points centred on the voxel centre, rare) gets
           the scalar (lambda_V + lambda_R)/2 (counted as scalar_fallback_voxels).
Which voxels are sampled: every shape has a level function F (F <= 0 inside) with a known
Lipschitz constant K (exact signed distance, K = 1, for the cylinders; sqrt((z/a)^2+(rho/b)^2)-1,
K = 1/min(a,b), for the spheroid); a voxel with |F(centre)| <= K r_v (r_v the half-diagonal of
the voxel) may be cut, F < -K r_v is entirely inside, F > K r_v entirely outside.
Periodic images: each voxel centre / sub-point is taken at its minimum image relative to the
shape centre; this is exact when every box side exceeds twice the shape's circumradius, which is
asserted (spheroid max(a,b); flat cylinder sqrt(r^2 + (L/2)^2); round cylinder L/2).

Grid sizes
----------
"resolutions" are voxel counts along the longest side; the other sides get n L_k / L_max. Each
target is then rounded (--sizes): "odd" (default) to the nearest odd integer; "odd-fast" to the
nearest odd integer whose prime factors are <= 13 (FFT speed: 97 -> 99, 129 -> 125); "exact"
to the nearest integer (even sizes allowed, see above). The grid actually used and the voxel
sizes are reported; h = (hx hy hz)^(1/3) is the step used by the extrapolation.

Discretisation error and how it is estimated
--------------------------------------------
* Algebraic: CG to relative residual tol (1e-8): relative error of lambda_e of the same order
  (the residual reached is reported for every load case).
* Discretisation (voxel image + Fourier Galerkin with discontinuous lambda): lambda_e(h) =
  lambda_0 + c h^p + ..., p about 1 for plain voxels (staircase of the interface, plus an
  oscillating part from the voxel image's volume fraction), p about 1 to 2 for composite voxels
  with a much smaller c (measured: see scripts/voxel_fft/README.md). It is estimated from the
  sequence of resolutions (function `extrapolate`):
    - lambda_0, p: least-squares fit of lambda(h) = lambda_0 + c h^p, p common to all components
      and fitted on the mean of the diagonal, p in [0.5, 4] (>= 3 resolutions); Richardson with
      p = 1 for two resolutions. "fit_reliable" is false when p sits at a bound or the
      diagonal mean is not monotone in h. With exactly 3 resolutions the fit always passes
      through the points, so p is only as good as the data's smoothness.
    - lambda_0_p1: the same fit with p = 1 (the known first-order voxel error).
    - difference_two_finest (also "error_bound"): |lambda(finest) - lambda(second finest)|;
      error_estimate_finest = difference * r/(1-r), r = h_finest/h_second (first-order
      Richardson estimate of the finest run's own error; the plain difference understates it
      when the two finest grids are close, e.g. 65 and 81).
    - recommended (+- recommended_error = max(difference_two_finest, |recommended - finest|)):
      composite voxels: lambda_0 if the fit is reliable, else lambda_0_p1; plain voxels:
      always lambda_0_p1 (their oscillating error makes a fitted p meaningless).
  Use resolutions spaced by a factor ~1.4-2 (e.g. 33, 49, 65, 99 or 65, 99, 125).

Input (JSON)
------------
{"period": [Lx, Ly, Lz], "lambda_matrix": float, "lambda_inclusion": float,
 "resolutions": [n1, n2, ...],
 "shapes": [
   {"kind": "spheroid", "centre": [x,y,z], "axis": [ux,uy,uz], "a": semi-axis along axis,
    "b": semi-axis across},
   {"kind": "cylinder", "centre": [...], "axis": [...], "radius": r,
    "length": tip-to-tip length incl. caps, "ends": "flat" | "round"} ]}
Optional keys (overridden by the command line): "variants", "subsample", "tol", "sizes",
"load_cases", "normal".

Usage
-----
    python voxel_fft.py input.json [--out result.json] [--variants plain,composite]
        [--subsample 8] [--tol 1e-8] [--sizes odd|odd-fast|exact] [--load-cases xyz]
        [--normal gradient|centroid] [--maxiter 2000] [--quiet]
    python voxel_fft.py --image labels.npy --labels 0:1,1:10 [--period 1,1,1] [--out r.json]
        [--tol 1e-8] [--load-cases xyz] [--maxiter 2000] [--quiet]
the latter: the effective tensor of a given integer label image (axes x, y, z), plain voxels,
one conductivity per label, on exactly the image's grid (even sizes allowed); --period defaults
to the grid size (cubic voxels; the tensor does not depend on the box's scale).
Progress goes to stderr, the result (JSON) to stdout or --out. One thread is used (the BLAS /
OpenMP thread counts are set to 1 unless already set; scipy.fft runs with workers=1).

Python API: `Conductivity`, `effective_tensor(cond, period, ...)`, `voxelize(...)`,
`image_effective_tensor(labels, period, {label: lambda})`, `image_conductivity`,
`make_shape(dict)`, `extrapolate(hs, tensors)`, `run(config)`.
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy.fft as sfft  # noqa: E402
from scipy.optimize import minimize_scalar  # noqa: E402
from scipy.sparse.linalg import LinearOperator, cg  # noqa: E402

WORKERS = 1


# --------------------------------------------------------------------------------------------
# Grid
# --------------------------------------------------------------------------------------------
def _smooth(n, primes=(2, 3, 5, 7, 11, 13)):
    for p in primes:
        while n % p == 0:
            n //= p
    return n == 1


def grid_size(target, mode="odd"):
    """Voxel count for a (real) target count along one side."""
    if mode == "exact":
        return max(1, int(round(target)))
    odd = max(1, 2 * int(math.floor((target - 1.0) / 2.0 + 0.5)) + 1)  # ties go up
    if mode == "odd":
        return odd
    if mode == "odd-fast":
        cands = [c for c in range(max(1, odd - 400), odd + 401) if c % 2 == 1 and _smooth(c)]
        return min(cands, key=lambda c: (abs(c - target), -c))  # ties go up
    raise ValueError(f"unknown size mode {mode!r}")


def grid_shape(period, n_longest, mode="odd"):
    lmax = max(period)
    return tuple(grid_size(n_longest * L / lmax, mode) for L in period)


# --------------------------------------------------------------------------------------------
# Conductivity field (scalar per voxel, optionally a full symmetric tensor on a subset)
# --------------------------------------------------------------------------------------------
class Conductivity:
    """lambda per voxel: `scalar` (nx, ny, nz); voxels listed in `idx` (flat C-order indices)
    use instead the symmetric tensors `tensors` (m, 3, 3)."""

    def __init__(self, scalar, idx=None, tensors=None):
        self.scalar = np.ascontiguousarray(scalar, dtype=float)
        self.shape = self.scalar.shape
        if idx is None or len(idx) == 0:
            self.idx, self.tensors = None, None
        else:
            self.idx = np.asarray(idx, dtype=np.int64)
            self.tensors = np.ascontiguousarray(tensors, dtype=float)
            assert self.tensors.shape == (len(self.idx), 3, 3)
            assert np.allclose(self.tensors, self.tensors.transpose(0, 2, 1)), "tensors not symmetric"

    @classmethod
    def from_tensor_field(cls, T):
        """T of shape (nx, ny, nz, 3, 3): a full tensor in every voxel."""
        T = np.asarray(T, dtype=float)
        shape = T.shape[:3]
        return cls(np.zeros(shape), np.arange(int(np.prod(shape))), T.reshape(-1, 3, 3))

    def apply(self, e):
        """lambda e for a field e of shape (3, nx, ny, nz)."""
        y = e * self.scalar[None]
        if self.idx is not None:
            e2 = e.reshape(3, -1)
            y2 = y.reshape(3, -1)
            y2[:, self.idx] = np.einsum("mij,jm->im", self.tensors, e2[:, self.idx])
        return y

    def eig_range(self):
        lo, hi = float(self.scalar.min()), float(self.scalar.max())
        if self.idx is not None:
            w = np.linalg.eigvalsh(self.tensors)
            if len(self.idx) == self.scalar.size:
                lo, hi = float(w.min()), float(w.max())
            else:
                lo, hi = min(lo, float(w.min())), max(hi, float(w.max()))
        return lo, hi


# --------------------------------------------------------------------------------------------
# Fourier-Galerkin solver
# --------------------------------------------------------------------------------------------
class Projection:
    """G = F^-1 xi xi^T/|xi|^2 F on real fields of shape (3, n1, n2, n3), periodic box `period`."""

    def __init__(self, period, shape):
        self.shape = tuple(int(n) for n in shape)
        freqs = []
        for k, (L, n) in enumerate(zip(period, self.shape)):
            if k < 2:
                m = np.fft.fftfreq(n) * n
            else:
                m = np.fft.rfftfreq(n) * n
            xi = 2.0 * np.pi * m / L
            if n % 2 == 0:
                xi[np.isclose(np.abs(m), n / 2)] = np.nan  # Nyquist: dropped
            freqs.append(xi)
        X = freqs[0][:, None, None]
        Y = freqs[1][None, :, None]
        Z = freqs[2][None, None, :]
        norm2 = X * X + Y * Y + Z * Z
        with np.errstate(invalid="ignore", divide="ignore"):
            inv = 1.0 / np.sqrt(norm2)
        bad = ~np.isfinite(inv) | (norm2 == 0)
        inv[bad] = 0.0
        Xs, Ys, Zs = (np.nan_to_num(v) for v in (X, Y, Z))
        # unit frequency direction zeta (0 at xi = 0 and on dropped Nyquist modes)
        self.zeta = np.stack([np.broadcast_to(Xs, inv.shape) * inv,
                              np.broadcast_to(Ys, inv.shape) * inv,
                              np.broadcast_to(Zs, inv.shape) * inv])
        # even sizes: a Nyquist mode along one axis only, (N,0,0) etc., is unambiguous
        # (Gamma^ = e_k e_k^T, the sampled gradient of sin(pi n x_k / L_k)); keep it, so that
        # laminates stay exact. Every other mode with a Nyquist component is dropped.
        for k, n in enumerate(self.shape):
            if n % 2 == 0:
                at = [0, 0, 0]
                at[k] = n // 2 if k < 2 else -1
                self.zeta[(k,) + tuple(at)] = 1.0

    def __call__(self, f):
        F = sfft.rfftn(f, axes=(1, 2, 3), workers=WORKERS)
        s = self.zeta[0] * F[0]
        s += self.zeta[1] * F[1]
        s += self.zeta[2] * F[2]
        np.multiply(self.zeta, s[None], out=F)
        return sfft.irfftn(F, s=self.shape, axes=(1, 2, 3), workers=WORKERS)


def effective_tensor(cond, period, tol=1e-8, maxiter=2000, load_cases=(0, 1, 2), proj=None,
                     log=None):
    """Effective tensor of the voxel conductivity `cond` in the periodic box `period`.

    Returns dict: lambda_eff (3x3 list; columns not computed are NaN), iterations, residual
    (true relative residual after CG), time_s per load case, info codes."""
    shape = cond.shape
    N = int(np.prod(shape))
    if proj is None:
        proj = Projection(period, shape)

    def matvec(x):
        return proj(cond.apply(x.reshape((3,) + shape))).ravel()

    A = LinearOperator((3 * N, 3 * N), matvec=matvec, dtype=float)
    lam = np.full((3, 3), np.nan)
    its, res, times, infos = [], [], [], []
    for j in load_cases:
        t0 = time.perf_counter()
        E = np.zeros(3)
        E[j] = 1.0
        lamE = cond.apply(np.broadcast_to(E[:, None, None, None], (3,) + shape).copy())
        b = -proj(lamE).ravel()
        bnorm = np.linalg.norm(b)
        count = [0]
        if bnorm == 0.0 or bnorm <= 1e-14 * np.linalg.norm(lamE.ravel()):
            x, info, r = np.zeros(3 * N), 0, 0.0
        else:
            def cb(_xk):
                count[0] += 1
            x, info = cg(A, b, rtol=tol, atol=0.0, maxiter=maxiter, callback=cb)
            r = float(np.linalg.norm(A.matvec(x) - b) / bnorm)
        e = x.reshape((3,) + shape)
        e[j] += 1.0
        lam[:, j] = cond.apply(e).reshape(3, -1).mean(axis=1)
        dt = time.perf_counter() - t0
        its.append(count[0])
        res.append(r)
        times.append(dt)
        infos.append(int(info))
        if log:
            log(f"    load {'xyz'[j]}: {count[0]} CG iterations, residual {r:.2e}, {dt:.2f} s")
        if info != 0:
            print(f"WARNING: CG did not converge (info={info}) for load case {'xyz'[j]}",
                  file=sys.stderr)
    return {"lambda_eff": lam, "iterations": its, "relative_residual": res, "time_s": times,
            "cg_info": infos}


# --------------------------------------------------------------------------------------------
# Shapes: level function F (<= 0 inside) of a displacement d = x - centre, Lipschitz constant
# --------------------------------------------------------------------------------------------
class Shape:
    kind = "?"

    def __init__(self, centre, axis):
        self.centre = np.asarray(centre, dtype=float)
        u = np.asarray(axis, dtype=float)
        nu = np.linalg.norm(u)
        assert nu > 0, "axis of zero length"
        self.u = u / nu

    def _zr2(self, dx, dy, dz):
        z = self.u[0] * dx + self.u[1] * dy + self.u[2] * dz
        r2 = np.maximum(dx * dx + dy * dy + dz * dz - z * z, 0.0)
        return z, r2


class Spheroid(Shape):
    kind = "spheroid"

    def __init__(self, centre, axis, a, b):
        super().__init__(centre, axis)
        self.a, self.b = float(a), float(b)
        assert self.a > 0 and self.b > 0
        self.volume = 4.0 / 3.0 * math.pi * self.a * self.b ** 2
        self.circumradius = max(self.a, self.b)
        self.lipschitz = 1.0 / min(self.a, self.b)

    def level(self, dx, dy, dz):
        z, r2 = self._zr2(dx, dy, dz)
        return np.sqrt(z * z / self.a ** 2 + r2 / self.b ** 2) - 1.0


class Cylinder(Shape):
    kind = "cylinder"

    def __init__(self, centre, axis, radius, length, ends="flat"):
        super().__init__(centre, axis)
        self.r, self.L, self.ends = float(radius), float(length), ends
        assert self.r > 0 and self.L > 0
        if ends == "flat":
            self.volume = math.pi * self.r ** 2 * self.L
            self.circumradius = math.hypot(self.r, self.L / 2)
        elif ends == "round":
            assert self.L >= 2 * self.r, "round cylinder shorter than its two caps"
            self.volume = math.pi * self.r ** 2 * (self.L - 2 * self.r) + 4.0 / 3.0 * math.pi * self.r ** 3
            self.circumradius = self.L / 2
        else:
            raise ValueError(f"unknown ends {ends!r}")
        self.lipschitz = 1.0  # exact signed distance

    def level(self, dx, dy, dz):
        z, r2 = self._zr2(dx, dy, dz)
        rho = np.sqrt(r2)
        if self.ends == "flat":
            q0 = rho - self.r
            q1 = np.abs(z) - self.L / 2
            out = np.sqrt(np.maximum(q0, 0.0) ** 2 + np.maximum(q1, 0.0) ** 2)
            return out + np.minimum(np.maximum(q0, q1), 0.0)
        hl = self.L / 2 - self.r
        zc = np.clip(z, -hl, hl)
        return np.sqrt(r2 + (z - zc) ** 2) - self.r


def make_shape(s):
    kind = s["kind"]
    if kind == "spheroid":
        return Spheroid(s["centre"], s["axis"], s["a"], s["b"])
    if kind == "cylinder":
        return Cylinder(s["centre"], s["axis"], s["radius"], s["length"], s.get("ends", "flat"))
    raise ValueError(f"unknown shape kind {kind!r}")


# --------------------------------------------------------------------------------------------
# Voxelisation
# --------------------------------------------------------------------------------------------
def _min_image(d, L):
    return d - L * np.round(d / L)


def _local_indices(c, margin, h, n, L):
    """Grid indices (mod n, unique) along one axis whose voxel centres lie within `margin` of c
    (periodically), and their minimum-image displacement from c."""
    i0 = int(math.ceil((c - margin) / h - 0.5))
    i1 = int(math.floor((c + margin) / h - 0.5))
    if i1 - i0 + 1 >= n:
        i = np.arange(n)
    else:
        i = np.arange(i0, i1 + 1) % n
    d = _min_image((i + 0.5) * h - c, L)
    return i, d


def voxelize(shapes, period, shape, composite=True, subsample=8, normal="gradient"):
    """Voxel images of the shapes' union. Returns dict with
    'plain' (bool array: voxel centre inside), 'overlap_voxels' (centres inside >= 2 shapes),
    and if composite: 'phi' (float array, inclusion fraction per voxel), 'mixed_idx' (flat
    indices of voxels with 0 < phi < 1), 'mixed_phi', 'mixed_normal' (m, 3; NaN row = none)."""
    period = np.asarray(period, dtype=float)
    n = np.asarray(shape)
    h = period / n
    rv = 0.5 * float(np.linalg.norm(h))
    for sh in shapes:
        for k in range(3):
            assert period[k] > 2 * sh.circumradius, (
                f"box side {period[k]} not larger than twice the circumradius "
                f"{sh.circumradius} of a {sh.kind}: minimum image not valid")
    count = np.zeros(shape, dtype=np.int16)
    full = np.zeros(shape, dtype=bool) if composite else None
    b_idx, b_bits, b_shape, b_grad = [], [], [], []
    s = int(subsample)
    off1 = ((np.arange(s) + 0.5) / s - 0.5)
    offs = np.stack(np.meshgrid(off1 * h[0], off1 * h[1], off1 * h[2], indexing="ij"),
                    axis=-1).reshape(-1, 3)  # (s^3, 3), centred on the voxel centre
    for si, sh in enumerate(shapes):
        margin = sh.circumradius + rv
        (ix, dx), (iy, dy), (iz, dz) = (
            _local_indices(sh.centre[k], margin, h[k], n[k], period[k]) for k in range(3))
        F = sh.level(dx[:, None, None], dy[None, :, None], dz[None, None, :])
        sub = np.ix_(ix, iy, iz)
        count[sub] += (F <= 0.0)
        if not composite:
            continue
        band = sh.lipschitz * rv
        full[sub] |= F < -band
        cut = np.nonzero(np.abs(F) <= band)
        if len(cut[0]) == 0:
            continue
        gi = (ix[cut[0]] * n[1] + iy[cut[1]]) * n[2] + iz[cut[2]]
        dc = np.stack([dx[cut[0]], dy[cut[1]], dz[cut[2]]], axis=1)  # (m, 3)
        bits = np.empty((len(gi), s ** 3), dtype=bool)
        chunk = max(1, 2_000_000 // s ** 3)
        for a in range(0, len(gi), chunk):
            p = dc[a:a + chunk, None, :] + offs[None, :, :]
            p = _min_image(p, period[None, None, :])
            bits[a:a + chunk] = sh.level(p[..., 0], p[..., 1], p[..., 2]) <= 0.0
        # gradient of the level function at the voxel centre (central differences)
        eps = 1e-4 * float(h.min())
        g = np.empty_like(dc)
        for k in range(3):
            dp = dc.copy()
            dm = dc.copy()
            dp[:, k] += eps
            dm[:, k] -= eps
            g[:, k] = (sh.level(dp[:, 0], dp[:, 1], dp[:, 2])
                       - sh.level(dm[:, 0], dm[:, 1], dm[:, 2])) / (2 * eps)
        b_idx.append(gi)
        b_bits.append(bits)
        b_shape.append(np.full(len(gi), si))
        b_grad.append(g)
    out = {"plain": count > 0, "overlap_voxels": int(np.count_nonzero(count > 1)), "h": h}
    if not composite:
        return out
    phi = full.astype(float)
    if b_idx:
        gi = np.concatenate(b_idx)
        bits = np.concatenate(b_bits)
        grad = np.concatenate(b_grad)
        order = np.argsort(gi, kind="stable")
        gi, bits, grad = gi[order], bits[order], grad[order]
        uniq, start, nsh = np.unique(gi, return_index=True, return_counts=True)
        bits_u = np.logical_or.reduceat(bits, start, axis=0)
        grad_u = grad[start]
        keep = ~full.ravel()[uniq]
        uniq, bits_u, grad_u, nsh = uniq[keep], bits_u[keep], grad_u[keep], nsh[keep]
        ph = bits_u.mean(axis=1)
        phi.ravel()[uniq] = ph
        mixed = (ph > 0.0) & (ph < 1.0)
        m_idx, m_bits, m_grad, m_nsh = uniq[mixed], bits_u[mixed], grad_u[mixed], nsh[mixed]
        m_phi = ph[mixed]
        # centroid normal: from the centroid of the inside sub-points toward the voxel centre
        cin = (m_bits.astype(float) @ offs) / m_bits.sum(axis=1)[:, None]
        cen_n = -cin
        if normal == "gradient":
            nrm = np.where((m_nsh == 1)[:, None], m_grad, cen_n)
        elif normal == "centroid":
            nrm = cen_n
        else:
            raise ValueError(f"unknown normal mode {normal!r}")
        ln = np.linalg.norm(nrm, axis=1)
        okn = ln > 1e-9 * float(h.min())
        nrm = np.where(okn[:, None], nrm / np.where(okn, ln, 1.0)[:, None], np.nan)
    else:
        m_idx = np.zeros(0, dtype=np.int64)
        m_phi = np.zeros(0)
        nrm = np.zeros((0, 3))
    out.update(phi=phi, mixed_idx=m_idx, mixed_phi=m_phi, mixed_normal=nrm)
    return out


def plain_conductivity(img, lam_m, lam_i):
    return Conductivity(np.where(img["plain"], lam_i, lam_m))


def composite_conductivity(img, lam_m, lam_i):
    """Laminate composite voxels from voxelize(..., composite=True). Returns (cond, n_scalar
    fallbacks)."""
    phi = img["phi"]
    scalar = np.where(phi >= 1.0, lam_i, lam_m).astype(float)
    idx = img["mixed_idx"]
    ph = img["mixed_phi"]
    nrm = img["mixed_normal"]
    lv = ph * lam_i + (1 - ph) * lam_m
    lr = 1.0 / (ph / lam_i + (1 - ph) / lam_m)
    bad = ~np.all(np.isfinite(nrm), axis=1)
    n_ok = np.where(bad[:, None], 0.0, nrm)
    T = (lr - lv)[:, None, None] * np.einsum("mi,mj->mij", n_ok, n_ok) \
        + lv[:, None, None] * np.eye(3)[None]
    if np.any(bad):
        T[bad] = (0.5 * (lv[bad] + lr[bad]))[:, None, None] * np.eye(3)[None]
    scalar.ravel()[idx] = 0.0
    return Conductivity(scalar, idx, T), int(np.count_nonzero(bad))


# --------------------------------------------------------------------------------------------
# Given label images
# --------------------------------------------------------------------------------------------
def image_conductivity(labels, lam_of_label):
    """Plain-voxel Conductivity of an integer label image (axes x, y, z): every voxel takes
    lam_of_label[its label]. Every label present must be mapped (ValueError otherwise)."""
    labels = np.asarray(labels)
    if labels.ndim != 3:
        raise ValueError(f"label image must be 3-D (axes x, y, z), got shape {labels.shape}")
    if not (np.issubdtype(labels.dtype, np.integer) or labels.dtype == bool):
        raise ValueError(f"label image must hold integers, got dtype {labels.dtype}")
    present = [int(v) for v in np.unique(labels)]
    missing = [v for v in present if v not in lam_of_label]
    if missing:
        raise ValueError(f"labels {missing} have no conductivity")
    lam = np.empty(labels.shape, dtype=float)
    for lab in present:
        v = float(lam_of_label[lab])
        if not (v > 0.0 and math.isfinite(v)):
            raise ValueError(f"conductivity of label {lab} must be positive, got {v}")
        lam[labels == lab] = v
    return Conductivity(lam)


def image_effective_tensor(labels, period, lam_of_label, tol=1e-8, maxiter=2000,
                           load_cases=(0, 1, 2), log=None):
    """Effective tensor of a given integer label image (numpy array, axes x, y, z; voxel
    (i, j, k) covers [i, i+1) hx x [j, j+1) hy x [k, k+1) hz, h = period / shape) with the
    label -> conductivity map `lam_of_label` (dict), periodic box `period`: plain voxels, the
    same solver as `run` (`effective_tensor`; even sizes allowed, Nyquist handling as in the
    docstring). Returns effective_tensor's dict plus grid, period, volume_fractions (per label)
    and setup_time_s (conductivity + projection)."""
    t0 = time.perf_counter()
    labels = np.asarray(labels)
    cond = image_conductivity(labels, lam_of_label)
    period = [float(v) for v in period]
    if len(period) != 3 or min(period) <= 0:
        raise ValueError(f"period must be 3 positive lengths, got {period}")
    proj = Projection(period, labels.shape)
    setup = time.perf_counter() - t0
    r = effective_tensor(cond, period, tol=tol, maxiter=maxiter, load_cases=load_cases,
                         proj=proj, log=log)
    vals, counts = np.unique(labels, return_counts=True)
    r.update(grid=list(labels.shape), period=period,
             volume_fractions={int(v): float(c) / labels.size for v, c in zip(vals, counts)},
             setup_time_s=setup)
    return r


def parse_labels(text):
    """'0:1,1:10' -> {0: 1.0, 1: 10.0}."""
    out = {}
    for item in text.split(","):
        if not item.strip():
            continue
        k, v = item.split(":")
        out[int(k)] = float(v)
    return out


# --------------------------------------------------------------------------------------------
# Extrapolation to h -> 0
# --------------------------------------------------------------------------------------------
def _fit_fixed_p(h, Y, p):
    """Least squares Y[i] = l0 + c h_i^p for every column of Y (nres, ncomp)."""
    A = np.stack([np.ones_like(h), h ** p], axis=1)
    coef, *_ = np.linalg.lstsq(A, Y, rcond=None)
    r = Y - A @ coef
    return coef[0], coef[1], r


def extrapolate(hs, tensors, p_range=(0.5, 4.0), prefer_p1=False):
    """Extrapolate tensors(h) (list of 3x3, any order of h) to h = 0.

    Keys of the result (tensors as 3x3 lists, per component):
      lambda_0                 fit lambda(h) = lambda_0 + c h^p (p common, fitted on the mean
                               of the diagonal; >= 3 resolutions) or Richardson p = 1 (two)
      p, fit_rms_residual, fit_reliable (False when p sits at a bound of p_range, or the
                               sequence of the diagonal mean is not monotone)
      lambda_0_p1              least-squares fit with p = 1 fixed (the first-order voxel error)
      difference_two_finest    |lambda(finest) - lambda(second finest)|  ("error_bound" in the
                               brief's sense; it only bounds the finest run's error when the two
                               finest h differ by a factor of about 2 or more)
      error_estimate_finest    difference_two_finest * r/(1-r), r = h_finest/h_second: the
                               Richardson estimate of the finest run's error if the error is
                               first order (conservative when the true p >= 1)
      recommended, recommended_error
                               lambda_0 and max(difference_two_finest, |lambda_0 - finest|) when
                               the fit is reliable, else lambda_0_p1 and max(difference_two_finest,
                               |lambda_0_p1 - finest|); with prefer_p1 (used for plain voxels,
                               whose oscillating error makes a 3-point p meaningless) always
                               lambda_0_p1
    """
    hs = np.asarray(hs, dtype=float)
    T = np.asarray(tensors, dtype=float).reshape(len(hs), 9)
    order = np.argsort(-hs)  # coarse -> fine
    hs, T = hs[order], T[order]
    if len(hs) < 2:
        return {"lambda_0": T[-1].reshape(3, 3).tolist(), "p": None,
                "difference_two_finest": None, "error_estimate_finest": None,
                "method": "single resolution: no extrapolation", "fit_reliable": False,
                "recommended": T[-1].reshape(3, 3).tolist(), "recommended_error": None}
    out = {}
    diag = T[:, [0, 4, 8]]
    solved = np.all(np.isfinite(diag), axis=0)
    s = diag[:, solved].mean(axis=1)
    diff = np.abs(T[-1] - T[-2])
    r = hs[-1] / hs[-2]
    l0p1 = _fit_fixed_p(hs, T, 1.0)[0]
    if len(hs) == 2:
        p, l0, reliable = 1.0, l0p1, True
        out.update(method="Richardson, p = 1 (two resolutions)", fit_rms_residual=0.0)
    else:
        def ssr(p):
            _, _, res = _fit_fixed_p(hs, s[:, None], p)
            return float(np.sum(res ** 2))
        grid = np.linspace(p_range[0], p_range[1], 351)
        vals = np.array([ssr(q) for q in grid])
        k = int(np.argmin(vals))
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        p = float(minimize_scalar(ssr, bounds=(lo, hi), method="bounded",
                                  options={"xatol": 1e-10}).x)
        l0, _, res = _fit_fixed_p(hs, T, p)
        ds = np.diff(s)
        monotone = bool(np.all(ds > 0) or np.all(ds < 0))
        at_bound = p < p_range[0] + 0.01 or p > p_range[1] - 0.01
        reliable = bool(monotone and not at_bound)
        out.update(method="least squares lambda(h) = lambda_0 + c h^p, p common, fitted on the"
                          " mean of the diagonal", p_range=list(p_range),
                   fit_rms_residual=float(np.sqrt(np.mean(res[:, [0, 4, 8]][:, solved] ** 2))),
                   monotone=monotone, p_at_bound=bool(at_bound))
    use_fit = reliable and not prefer_p1
    rec = l0 if use_fit else l0p1
    out.update(p=p, fit_reliable=reliable,
               lambda_0=l0.reshape(3, 3).tolist(),
               lambda_0_p1=l0p1.reshape(3, 3).tolist(),
               difference_two_finest=diff.reshape(3, 3).tolist(),
               error_bound=diff.reshape(3, 3).tolist(),
               error_estimate_finest=(diff * r / (1 - r)).reshape(3, 3).tolist(),
               lambda_0_minus_finest=(l0 - T[-1]).reshape(3, 3).tolist(),
               recommended=rec.reshape(3, 3).tolist(),
               recommended_from="lambda_0" if use_fit else "lambda_0_p1",
               recommended_error=np.maximum(diff, np.abs(rec - T[-1])).reshape(3, 3).tolist(),
               h=hs.tolist())
    return out


# --------------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------------
def _nan_to_none(x):
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, list):
        return [_nan_to_none(v) for v in x]
    if isinstance(x, dict):
        return {k: _nan_to_none(v) for k, v in x.items()}
    return x


def run(cfg, variants=("plain", "composite"), subsample=8, tol=1e-8, sizes="odd",
        load_cases=(0, 1, 2), normal="gradient", maxiter=2000, log=None):
    period = [float(v) for v in cfg["period"]]
    lam_m, lam_i = float(cfg["lambda_matrix"]), float(cfg["lambda_inclusion"])
    shapes = [make_shape(s) for s in cfg["shapes"]]
    vol = float(np.prod(period))
    f_exact = sum(s.volume for s in shapes) / vol
    res = {"period": period, "lambda_matrix": lam_m, "lambda_inclusion": lam_i,
           "n_shapes": len(shapes), "volume_fraction_exact": f_exact,
           "options": {"variants": list(variants), "subsample": subsample, "tol": tol,
                       "sizes": sizes, "load_cases": "".join("xyz"[j] for j in load_cases),
                       "normal": normal, "frequencies": "plain Fourier (spectral)",
                       "threads": 1},
           "variants": {v: {"runs": []} for v in variants}}
    for nres in cfg["resolutions"]:
        gshape = grid_shape(period, nres, sizes)
        if log:
            log(f"resolution {nres}: grid {gshape}")
        t0 = time.perf_counter()
        img = voxelize(shapes, period, gshape, composite="composite" in variants,
                       subsample=subsample, normal=normal)
        t_vox = time.perf_counter() - t0
        t0 = time.perf_counter()
        proj = Projection(period, gshape)
        t_proj = time.perf_counter() - t0
        h = img["h"]
        heff = float(np.prod(h) ** (1.0 / 3.0))
        for v in variants:
            t0 = time.perf_counter()
            extra = {}
            if v == "plain":
                cond = plain_conductivity(img, lam_m, lam_i)
                fimg = float(np.mean(img["plain"]))
            elif v == "composite":
                cond, nfb = composite_conductivity(img, lam_m, lam_i)
                fimg = float(np.mean(img["phi"]))
                extra = {"mixed_voxels": int(len(img["mixed_idx"])), "scalar_fallback_voxels": nfb}
            else:
                raise ValueError(f"unknown variant {v!r}")
            t_cond = time.perf_counter() - t0
            if log:
                log(f"  {v}: image fraction {fimg:.6f} (exact {f_exact:.6f})")
            r = effective_tensor(cond, period, tol=tol, maxiter=maxiter, load_cases=load_cases,
                                 proj=proj, log=log)
            res["variants"][v]["runs"].append({
                "resolution": nres, "grid": list(gshape), "h": h.tolist(), "h_eff": heff,
                "volume_fraction_image": fimg, "volume_fraction_exact": f_exact,
                "overlap_voxels": img["overlap_voxels"], **extra,
                "lambda_eff": r["lambda_eff"].tolist(),
                "iterations": r["iterations"], "relative_residual": r["relative_residual"],
                "cg_info": r["cg_info"],
                "wall_time_s": {"per_load_case": r["time_s"], "solve_total": float(sum(r["time_s"])),
                                "voxelize_shared": t_vox, "operator_setup_shared": t_proj,
                                "conductivity_setup": t_cond}})
    for v in variants:
        runs = res["variants"][v]["runs"]
        res["variants"][v]["extrapolation"] = extrapolate([r["h_eff"] for r in runs],
                                                          [r["lambda_eff"] for r in runs],
                                                          prefer_p1=(v == "plain"))
    return _nan_to_none(res)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input", nargs="?", help="shapes case (JSON); omit with --image")
    ap.add_argument("--image", help="a label image (.npy, integer, axes x, y, z) instead of shapes")
    ap.add_argument("--labels", help="with --image: label:conductivity pairs, e.g. 0:1,1:10")
    ap.add_argument("--period", help="with --image: box lengths Lx,Ly,Lz (default: the grid "
                                     "size, i.e. cubic voxels of side 1)")
    ap.add_argument("--out")
    ap.add_argument("--variants")
    ap.add_argument("--subsample", type=int)
    ap.add_argument("--tol", type=float)
    ap.add_argument("--sizes", choices=["odd", "odd-fast", "exact"])
    ap.add_argument("--load-cases")
    ap.add_argument("--normal", choices=["gradient", "centroid"])
    ap.add_argument("--maxiter", type=int, default=2000)
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args(argv)
    log = None if a.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    if a.image is not None:
        if a.input is not None or a.labels is None:
            ap.error("--image takes no shapes input and needs --labels")
        labels = np.load(a.image)
        period = ([float(v) for v in a.period.split(",")] if a.period
                  else [float(n) for n in labels.shape])
        lc = a.load_cases or "xyz"
        t0 = time.perf_counter()
        r = image_effective_tensor(labels, period, parse_labels(a.labels),
                                   tol=a.tol if a.tol is not None else 1e-8, maxiter=a.maxiter,
                                   load_cases=tuple("xyz".index(c) for c in lc), log=log)
        res = {"image": a.image, "labels": {str(k): v for k, v in parse_labels(a.labels).items()},
               "grid": r["grid"], "period": r["period"],
               "volume_fractions": {str(k): v for k, v in r["volume_fractions"].items()},
               "lambda_eff": r["lambda_eff"].tolist(), "iterations": r["iterations"],
               "relative_residual": r["relative_residual"], "cg_info": r["cg_info"],
               "wall_time_s": {"per_load_case": r["time_s"], "solve_total": float(sum(r["time_s"])),
                               "setup": r["setup_time_s"]},
               "options": {"tol": a.tol if a.tol is not None else 1e-8, "load_cases": lc,
                           "voxels": "plain (one conductivity per label)",
                           "frequencies": "plain Fourier (spectral)", "threads": 1},
               "wall_time_total_s": time.perf_counter() - t0}
        txt = json.dumps(_nan_to_none(res), indent=1)
        if a.out:
            with open(a.out, "w") as fh:
                fh.write(txt + "\n")
        else:
            print(txt)
        return
    if a.input is None:
        ap.error("a shapes input (JSON) or --image is required")
    with open(a.input) as fh:
        cfg = json.load(fh)

    def pick(cli, key, default):
        return cli if cli is not None else cfg.get(key, default)

    variants = pick(a.variants, "variants", "plain,composite")
    if isinstance(variants, str):
        variants = [v.strip() for v in variants.split(",") if v.strip()]
    lc = pick(a.load_cases, "load_cases", "xyz")
    load_cases = tuple("xyz".index(c) for c in lc)
    t0 = time.perf_counter()
    res = run(cfg, variants=tuple(variants), subsample=int(pick(a.subsample, "subsample", 8)),
              tol=float(pick(a.tol, "tol", 1e-8)), sizes=pick(a.sizes, "sizes", "odd"),
              load_cases=load_cases, normal=pick(a.normal, "normal", "gradient"),
              maxiter=a.maxiter, log=log)
    res["wall_time_total_s"] = time.perf_counter() - t0
    txt = json.dumps(res, indent=1)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(txt + "\n")
    else:
        print(txt)


if __name__ == "__main__":
    main()
