#!/usr/bin/env python3
"""Voxel-FFT reference for the "images" validation case: one random sphere microstructure given
as a sphere list and as labelled voxel images.

Three microstructures (numpy default_rng(seed), seeds 1, 2, 3; 60 centres rng.random((60, 3)),
radius 0.08, periodic unit cube, overlaps allowed: the union is the inclusion phase; matrix
lambda = 1), two contrasts (lambda_inclusion = 10 and 0.1). For each:

* the label images at n = 32, 64, 128, 256, built exactly by the rule of
  scripts/image_vs_list.py, in float64 and in this order: x_i = (i + 0.5)/n; d = x - c;
  d -= np.round(d); d2 = dx*dx + dy*dy + dz*dz (accumulated x, then y, then z); label 1 where
  d2 <= r*r for any centre. The count of label-1 voxels is recorded (and a SHA-256 of the image's
  bytes, uint8, C order, axes x, y, z) so that another code can check that it rebuilt the same
  image. The image builder here is checked bit for bit against a literal transcription of
  image_vs_list.py's loop.
* the effective tensor of each image with plain voxels (voxel_fft.image_effective_tensor:
  Fourier-Galerkin CG, plain Fourier frequencies, on exactly the n^3 grid; even n: the modes
  with a Nyquist component are dropped except the pure-axis ones), CG relative residual 1e-8,
  all three load cases; iterations and solve wall time (sum over the load cases, excluding the
  image building and the operator setup).
* the continuum value of the sphere list: voxel_fft.run with the spheres as spheroids
  a = b = 0.08, laminate composite voxels (s = 8, gradient normals), resolutions 65, 99, 125
  (sizes "odd"), extrapolated to zero voxel size: `recommended` +- `recommended_error`.
  voxelize takes the union of overlapping shapes (a voxel centre / sub-point is inside when it
  is inside any shape), which is what is wanted here; run()'s volume_fraction_exact (the sum of
  the sphere volumes) is NOT the union's, so the union's fraction is computed here
  (inclusion-exclusion: exact pairwise lens volumes, triple intersections by a 2-D quadrature of
  the exact chord overlap; no four spheres share a point) and compared with the composite
  image's mean phi at 125^3.

Usage: python scripts/images_fft_reference.py [--out validation/data/images-fft.json]
           [--seeds 1,2,3] [--sizes 32,64,128,256] [--n256-seeds 1,2,3] [--cache FILE]
Results are cached per item in --cache (default /tmp/images_fft_cache.json), so an interrupted
run resumes. One thread (numpy + scipy, scipy.fft workers = 1).
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import hashlib  # noqa: E402
import itertools  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "voxel_fft"))
import voxel_fft as vf  # noqa: E402

RADIUS = 0.08
N_CENTRES = 60
LAMBDA_MATRIX = 1.0
CONTRASTS = (10.0, 0.1)
PERIOD = [1.0, 1.0, 1.0]
TOL = 1e-8
CONT_RES = [65, 99, 125]


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def centres_of(seed):
    rng = np.random.default_rng(seed)
    return rng.random((N_CENTRES, 3))


# ---------------------------------------------------------------------------------- images
def label_image(centres, n, r=RADIUS):
    """The image rule of image_vs_list.py, with 1-D displacement arrays broadcast (the same
    float64 operations on the same operands, element by element). Also returns the smallest
    |d2 - r*r| over all (voxel, centre) pairs and whether any |d| was exactly 0.5 (where
    round-half-to-even and round-half-away-from-zero differ)."""
    x = (np.arange(n) + 0.5) / n
    r2 = r * r
    lab = np.zeros((n, n, n), dtype=np.uint8)
    margin = math.inf
    half = False
    for c in centres:
        ds = []
        for k in range(3):
            d = x - c[k]
            half |= bool(np.any(np.abs(d) == 0.5))
            d -= np.round(d)
            ds.append(d * d)
        d2 = ds[0][:, None, None] + ds[1][None, :, None]
        d2 = d2 + ds[2][None, None, :]
        margin = min(margin, float(np.min(np.abs(d2 - r2))))
        lab[d2 <= r2] = 1
    return lab, margin, half


def label_image_literal(centres, n):
    """Literal transcription of scripts/image_vs_list.py (for the bit-for-bit check)."""
    x = (np.arange(n) + 0.5) / n
    grid = np.meshgrid(x, x, x, indexing="ij")
    lab = np.zeros((n, n, n), dtype=np.uint8)
    for c in centres:
        d2 = np.zeros_like(grid[0])
        for k in range(3):
            d = grid[k] - c[k]
            d -= np.round(d)
            d2 += d * d
        lab[d2 <= 0.08**2] = 1
    return lab


# -------------------------------------------------------------------------- union fraction
def _min_image_dist(a, b):
    d = a - b
    d -= np.round(d)
    return float(np.linalg.norm(d))


def _unwrap(centres, idx):
    """Centres idx at their minimum image around the first one."""
    c0 = centres[idx[0]]
    pts = [c0]
    for q in idx[1:]:
        d = centres[q] - c0
        pts.append(c0 + d - np.round(d))
    return np.array(pts)


def triple_volume(p, r, m=2000):
    """Volume of the intersection of three balls of radius r at p (3, 3): 2-D midpoint
    quadrature over (x, y) of the exact length of the common z-interval of the three chords."""
    lo = np.max(p[:, :2] - r, axis=0)
    hi = np.min(p[:, :2] + r, axis=0)
    if np.any(hi <= lo):
        return 0.0
    hx, hy = (hi - lo) / m
    x = lo[0] + (np.arange(m) + 0.5) * hx
    y = lo[1] + (np.arange(m) + 0.5) * hy
    zlo = np.full((m, m), -np.inf)
    zhi = np.full((m, m), np.inf)
    for c in p:
        rho2 = (x[:, None] - c[0]) ** 2 + (y[None, :] - c[1]) ** 2
        h = np.sqrt(np.maximum(r * r - rho2, 0.0))
        h[rho2 >= r * r] = -np.inf
        zlo = np.maximum(zlo, c[2] - h)
        zhi = np.minimum(zhi, c[2] + h)
    return float(np.sum(np.maximum(zhi - zlo, 0.0)) * hx * hy)


def union_fraction(centres, r=RADIUS):
    """Volume fraction of the union of the spheres (unit periodic cube, 2r < 1/2 so a ball
    meets at most one image of another): inclusion-exclusion, sum of volumes - pairwise lens
    volumes pi (4r + d)(2r - d)^2 / 12 (exact) + triple-intersection volumes (2-D quadrature
    of the exact chord overlap, at 2000^2 and 1000^2 points: the difference is the quadrature
    error estimate). Checked: no four spheres share a point (then the series ends there)."""
    m = len(centres)
    pairs = {}
    for i, j in itertools.combinations(range(m), 2):
        d = _min_image_dist(centres[i], centres[j])
        if d < 2 * r:
            pairs[(i, j)] = d
    triples = []
    n_pairwise3 = 0
    for i, j, k in itertools.combinations(range(m), 3):
        if (i, j) in pairs and (i, k) in pairs and (j, k) in pairs:
            n_pairwise3 += 1
            pts = _unwrap(centres, (i, j, k))
            if _min_enclosing_radius3(pts) <= r:
                triples.append((i, j, k))
    tset = set(triples)
    quads = 0
    for i, j, k, l in itertools.combinations(range(m), 4):
        if all(t in tset for t in ((i, j, k), (i, j, l), (i, k, l), (j, k, l))):
            quads += 1  # a 4-clique of triples: might share a point (not handled, flagged)
    v1 = 4.0 / 3.0 * math.pi * r ** 3
    lens = sum(math.pi * (4 * r + d) * (2 * r - d) ** 2 / 12.0 for d in pairs.values())
    v3 = [triple_volume(_unwrap(centres, t), r) for t in triples]
    v3c = [triple_volume(_unwrap(centres, t), r, m=1000) for t in triples]
    f_sum = m * v1
    union = f_sum - lens + sum(v3)
    return {"union": union, "union_error": abs(sum(v3) - sum(v3c)),
            "sum_of_sphere_volumes": f_sum, "overlapping_pairs": len(pairs),
            "pairwise_lens_volume": lens, "triples_with_common_point": len(triples),
            "triple_intersection_volume": float(sum(v3)),
            "quadruples_possibly_sharing_a_point": quads,
            "method": ("inclusion-exclusion: 60 (4/3) pi r^3 - sum of pairwise lens volumes "
                       "(exact) + sum of triple-intersection volumes (2-D quadrature of the "
                       "exact chord overlap, 2000^2 points; union_error = change from 1000^2); "
                       "no four spheres share a point")}


def _min_enclosing_radius3(p):
    """Radius of the smallest ball enclosing 3 points."""
    best = math.inf
    for a, b in itertools.combinations(range(3), 2):  # ball on a diameter
        c = 0.5 * (p[a] + p[b])
        R = max(np.linalg.norm(p - c, axis=1))
        best = min(best, R)
    # circumcircle (only smallest when the triangle is acute; the diameter balls cover the rest)
    a, b, c = p
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = float(n @ n)
    if nn > 0:
        cc = a + (np.cross(n, ab) * (ac @ ac) + np.cross(ac, n) * (ab @ ab)) / (2 * nn)
        R = max(np.linalg.norm(p - cc, axis=1))
        if R < best and np.allclose(np.linalg.norm(p - cc, axis=1), R):
            best = R
    return float(best)


# ------------------------------------------------------------------------------ the runs
def continuum(centres, lam_i):
    cfg = {"period": PERIOD, "lambda_matrix": LAMBDA_MATRIX, "lambda_inclusion": lam_i,
           "resolutions": CONT_RES,
           "shapes": [{"kind": "spheroid", "centre": [float(v) for v in c], "axis": [0, 0, 1],
                       "a": RADIUS, "b": RADIUS} for c in centres]}
    t0 = time.perf_counter()
    res = vf.run(cfg, variants=("composite",), subsample=8, tol=TOL, sizes="odd",
                 load_cases=(0, 1, 2), normal="gradient", log=log)
    wall = time.perf_counter() - t0
    v = res["variants"]["composite"]
    ex = v["extrapolation"]
    rec = np.array(ex["recommended"])
    err = np.array(ex["recommended_error"])
    runs = [{"grid": r["grid"], "tensor": r["lambda_eff"],
             "diag": [r["lambda_eff"][k][k] for k in range(3)],
             "iterations": r["iterations"], "relative_residual": r["relative_residual"],
             "volume_fraction_image": r["volume_fraction_image"],
             "overlap_voxels": r["overlap_voxels"], "mixed_voxels": r["mixed_voxels"],
             "scalar_fallback_voxels": r["scalar_fallback_voxels"],
             "solve_s": r["wall_time_s"]["solve_total"],
             "voxelize_s": r["wall_time_s"]["voxelize_shared"]} for r in v["runs"]]
    return {"diag": np.diag(rec).tolist(), "tensor": rec.tolist(),
            "error_diag": np.diag(err).tolist(), "error_tensor": err.tolist(),
            "resolutions": CONT_RES,
            "method": ("voxel_fft.run: Fourier-Galerkin CG (tol 1e-8, 3 load cases), laminate "
                       "composite voxels (sub-sampling s = 8, gradient normals; overlapping "
                       "spheres merged as a union), odd grids 65^3, 99^3, 125^3, extrapolated "
                       "to h -> 0: `recommended` (" + ex["recommended_from"] + ") +- "
                       "`recommended_error` = max(|finest - second finest|, "
                       "|recommended - finest|), per component"),
            "recommended_from": ex["recommended_from"], "p": ex["p"],
            "fit_reliable": ex["fit_reliable"], "lambda_0": ex["lambda_0"],
            "lambda_0_p1": ex["lambda_0_p1"], "runs": runs, "wall_s": wall}


def image_run(lab, lam_i):
    r = vf.image_effective_tensor(lab, PERIOD, {0: LAMBDA_MATRIX, 1: lam_i}, tol=TOL,
                                  load_cases=(0, 1, 2), log=log)
    L = r["lambda_eff"]
    return {"tensor": L.tolist(), "diag": np.diag(L).tolist(), "iterations": r["iterations"],
            "relative_residual": r["relative_residual"], "cg_info": r["cg_info"],
            "solve_s": float(sum(r["time_s"])), "solve_s_per_load_case": r["time_s"],
            "setup_s": r["setup_time_s"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=os.path.join(HERE, "..", "validation", "data",
                                                  "images-fft.json"))
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--sizes", default="32,64,128,256")
    ap.add_argument("--n256-seeds", default="1,2,3",
                    help="seeds for which the 256^3 image is solved")
    ap.add_argument("--cache", default="/tmp/images_fft_cache.json")
    ap.add_argument("--no-literal-check", action="store_true")
    ap.add_argument("--only", help="compute only this item kind: images or continuum")
    a = ap.parse_args()
    seeds = [int(s) for s in a.seeds.split(",")]
    sizes = [int(s) for s in a.sizes.split(",")]
    n256 = {int(s) for s in a.n256_seeds.split(",") if s}
    cache = {}
    if os.path.exists(a.cache):
        with open(a.cache) as fh:
            cache = json.load(fh)

    def save():
        tmp = a.cache + ".tmp"
        with open(tmp, "w") as fh:
            json.dump(cache, fh)
        os.replace(tmp, a.cache)

    micro = []
    for seed in seeds:
        centres = centres_of(seed)
        uf = union_fraction(centres)
        log(f"seed {seed}: union fraction {uf['union']:.8f} (sum {uf['sum_of_sphere_volumes']:.6f},"
            f" {uf['overlapping_pairs']} overlapping pairs, triples with a common point "
            f"{uf['triples_with_common_point']} (volume {uf['triple_intersection_volume']:.3e},"
            f" quadrature error {uf['union_error']:.1e}), possible quadruples "
            f"{uf['quadruples_possibly_sharing_a_point']})")
        assert uf["quadruples_possibly_sharing_a_point"] == 0
        ms = {"seed": seed, "centres": [[float(v) for v in c] for c in centres],
              "volume_fraction": uf, "contrasts": []}
        imgs = {}
        for n in sizes:
            key = f"img/{seed}/{n}"
            if n == 256 and seed not in n256:
                continue
            t0 = time.perf_counter()
            lab, margin, half = label_image(centres, n)
            tb = time.perf_counter() - t0
            info = {"n": n, "label1_voxels": int(np.count_nonzero(lab)),
                    "volume_fraction": float(np.count_nonzero(lab)) / n ** 3,
                    "sha256_uint8_C_order": hashlib.sha256(lab.tobytes(order="C")).hexdigest(),
                    "min_abs_d2_minus_r2": margin, "any_abs_d_equal_half": half,
                    "build_s": tb}
            if key in cache:
                assert cache[key]["label1_voxels"] == info["label1_voxels"]
                assert cache[key]["sha256_uint8_C_order"] == info["sha256_uint8_C_order"]
                info["literal_check"] = cache[key].get("literal_check")
            if not a.no_literal_check and info.get("literal_check") is None:
                lit = label_image_literal(centres, n)
                info["literal_check"] = bool(np.array_equal(lit, lab))
                del lit
                assert info["literal_check"], f"image rule mismatch at seed {seed}, n {n}"
            cache[key] = info
            save()
            log(f"  image {n}^3: {info['label1_voxels']} label-1 voxels "
                f"(fraction {info['volume_fraction']:.6f}), min |d2 - r^2| {margin:.2e}, "
                f"built in {tb:.1f} s, literal check {info.get('literal_check')}")
            imgs[n] = (lab, info)
        for lam_i in CONTRASTS:
            entry = {"lambda_inclusion": lam_i}
            ckey = f"cont/{seed}/{lam_i}"
            if a.only in (None, "continuum") and ckey not in cache:
                log(f"seed {seed}, lambda_i {lam_i}: continuum (composite 65/99/125)")
                cache[ckey] = continuum(centres, lam_i)
                save()
            entry["continuum"] = cache.get(ckey)
            entry["images"] = []
            for n, (lab, info) in imgs.items():
                ikey = f"solve/{seed}/{lam_i}/{n}"
                if a.only in (None, "images") and ikey not in cache:
                    log(f"seed {seed}, lambda_i {lam_i}: image {n}^3 plain")
                    cache[ikey] = image_run(lab, lam_i)
                    save()
                if ikey in cache:
                    entry["images"].append({k: v for k, v in info.items()
                                            if k not in ("build_s",)} | cache[ikey])
            ms["contrasts"].append(entry)
        micro.append(ms)
        del imgs
    out = {
        "about": (
            "Voxel-FFT reference for the 'images' validation case: the same random sphere "
            "microstructure as a sphere list and as labelled voxel images. Three "
            "microstructures (numpy default_rng(seed), seeds 1, 2, 3; 60 centres "
            "rng.random((60, 3)); radius 0.08; periodic unit cube; overlaps allowed, the union "
            "is the inclusion phase; matrix lambda 1), contrasts lambda_inclusion = 10 and 0.1. "
            "images[]: label images built exactly as scripts/image_vs_list.py (float64: "
            "x = (i+0.5)/n; d = x - c; d -= np.round(d); d2 = dx*dx + dy*dy + dz*dz, x then y "
            "then z; label 1 where d2 <= r*r for any centre; axes x, y, z), label1_voxels and "
            "a SHA-256 of the uint8 C-order bytes to check a rebuild; their effective tensor "
            "with plain voxels on exactly the n^3 grid (scripts/voxel_fft/voxel_fft.py "
            "image_effective_tensor: Fourier-Galerkin CG, plain Fourier frequencies, relative "
            "residual 1e-8, three load cases; even n: Nyquist modes dropped except the "
            "pure-axis ones), CG iterations per load case and solve_s (wall time of the three "
            "solves, excluding image building and operator setup). continuum: the sphere list's "
            "value, voxel_fft.run with laminate composite voxels at 65^3, 99^3, 125^3, "
            "extrapolated to zero voxel size (recommended +- recommended_error). "
            "volume_fraction.union: the union's volume fraction (inclusion-exclusion: exact "
            "pairwise lenses, triple intersections by quadrature, +- union_error; no four "
            "spheres share a point); composite_image_125: mean phi of the 125^3 composite "
            "image, for comparison. Computed by "
            "scripts/images_fft_reference.py, 2026-11-28, on a 2-core host with 1 thread "
            "(another build running on the other core: timings carry some scatter)."),
        "date": "2026-11-28",
        "machine": "2-core host, 1 thread (numpy/scipy, scipy.fft workers=1)",
        "period": PERIOD, "radius": RADIUS, "lambda_matrix": LAMBDA_MATRIX,
        "n_centres": N_CENTRES, "tolerance": TOL,
        "microstructures": micro,
    }
    for ms in micro:  # union fraction cross-check against the composite image
        for e in ms["contrasts"]:
            c = e.get("continuum")
            if c:
                ms["volume_fraction"]["composite_image_125"] = c["runs"][-1]["volume_fraction_image"]
    with open(a.out, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")
    log(f"wrote {a.out}")


if __name__ == "__main__":
    main()
