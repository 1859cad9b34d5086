#!/usr/bin/env python3
"""Voxel-FFT references of the `shapes-aligned` case for a set of placed microstructures.

Input: a JSON file in the format of `validation/data/shapes-fft.json` without `references`
(`period`, `lambda_matrix`, `microstructures[]` with `id` and `shapes[]` of spheroids given by
`centre`, `axis`, `a`, `b`). For every microstructure and contrast (lambda_i / lambda_m) this
computes exactly what `voxel_fft.run` computes for the composite variant (laminate composite
voxels, s = 8, gradient normals, sizes "odd", three load cases, CG to tol) at the given
resolutions and extrapolates with `voxel_fft.extrapolate`. The voxel image of one
(microstructure, grid) does not depend on the contrast, so it is built once and shared.

Every solved (microstructure, contrast, grid) is cached as one JSON file in --cache, so an
interrupted run resumes where it stopped. --out writes the `references` entries (the keys of
`shapes-fft.json`: microstructure, contrast, diagonal, error, fit_p, fit_reliable, grids,
by_grid) plus, under `details`, the full extrapolation and the wall times per entry.

    PY=/work/scratch-fft/venv/bin/python
    $PY scripts/voxel_fft/shapes_fft_reference.py /tmp/gen/shapes2.json \
        --cache /tmp/shapes2_fft_cache --out /tmp/shapes2_fft_refs.json [--ids prolate5-1,...]
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import voxel_fft as vf  # noqa: E402


def log(msg):
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


def cache_path(cache, mid, contrast, n):
    return os.path.join(cache, f"{mid}_c{contrast:g}_n{n}.json")


def solve_grid(ms, period, lam_m, contrasts, n, cache, tol, subsample):
    """Solve every contrast of one (microstructure, resolution) not yet in the cache."""
    todo = [c for c in contrasts if not os.path.exists(cache_path(cache, ms["id"], c, n))]
    if not todo:
        return
    shapes = [vf.make_shape({"kind": "spheroid", **s}) for s in ms["shapes"]]
    f_exact = sum(s.volume for s in shapes) / float(np.prod(period))
    gshape = vf.grid_shape(period, n, "odd")
    log(f"{ms['id']} n={n}: grid {gshape}, voxelize ({len(shapes)} shapes)")
    t0 = time.perf_counter()
    img = vf.voxelize(shapes, period, gshape, composite=True, subsample=subsample,
                      normal="gradient")
    t_vox = time.perf_counter() - t0
    t0 = time.perf_counter()
    proj = vf.Projection(period, gshape)
    t_proj = time.perf_counter() - t0
    h = img["h"]
    heff = float(np.prod(h) ** (1.0 / 3.0))
    fimg = float(np.mean(img["phi"]))
    log(f"  voxelize {t_vox:.1f} s, mixed voxels {len(img['mixed_idx'])}, "
        f"image fraction {fimg:.6f} (exact {f_exact:.6f})")
    for c in todo:
        lam_i = c * lam_m
        t0 = time.perf_counter()
        cond, nfb = vf.composite_conductivity(img, lam_m, lam_i)
        t_cond = time.perf_counter() - t0
        r = vf.effective_tensor(cond, period, tol=tol, maxiter=2000, load_cases=(0, 1, 2),
                                proj=proj, log=lambda m: log(f"  contrast {c:g}:{m}"))
        rec = {"microstructure": ms["id"], "contrast": c, "lambda_inclusion": lam_i,
               "resolution": n, "grid": list(gshape), "h": h.tolist(), "h_eff": heff,
               "volume_fraction_image": fimg, "volume_fraction_exact": f_exact,
               "overlap_voxels": img["overlap_voxels"],
               "mixed_voxels": int(len(img["mixed_idx"])), "scalar_fallback_voxels": nfb,
               "lambda_eff": r["lambda_eff"].tolist(), "iterations": r["iterations"],
               "relative_residual": r["relative_residual"], "cg_info": r["cg_info"],
               "wall_time_s": {"per_load_case": r["time_s"],
                               "solve_total": float(sum(r["time_s"])),
                               "voxelize_shared": t_vox, "operator_setup_shared": t_proj,
                               "conductivity_setup": t_cond},
               "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}
        tmp = cache_path(cache, ms["id"], c, n) + ".tmp"
        with open(tmp, "w") as fh:
            json.dump(vf._nan_to_none(rec), fh, indent=1)
        os.replace(tmp, cache_path(cache, ms["id"], c, n))
        log(f"  contrast {c:g}: diag {np.diag(r['lambda_eff'])}, "
            f"solve {sum(r['time_s']):.1f} s, iterations {r['iterations']}")
        del cond
    del img, proj


def reference_entry(mid, contrast, resolutions, cache):
    runs = [json.load(open(cache_path(cache, mid, contrast, n))) for n in resolutions]
    ex = vf.extrapolate([r["h_eff"] for r in runs], [r["lambda_eff"] for r in runs])
    rec = np.asarray(ex["recommended"])
    err = np.asarray(ex["recommended_error"])
    entry = {"microstructure": mid, "contrast": contrast,
             "diagonal": [float(rec[i, i]) for i in range(3)],
             "error": [float(err[i, i]) for i in range(3)],
             "fit_p": ex["p"], "fit_reliable": ex["fit_reliable"],
             "grids": [r["grid"] for r in runs],
             "by_grid": [[float(r["lambda_eff"][i][i]) for i in range(3)] for r in runs]}
    # voxelisation is shared by the contrasts; charge each contrast the full voxelisation time
    # (the cost of computing this entry alone)
    t_solve = sum(r["wall_time_s"]["solve_total"] for r in runs)
    t_vox = sum(r["wall_time_s"]["voxelize_shared"] + r["wall_time_s"]["operator_setup_shared"]
                + r["wall_time_s"]["conductivity_setup"] for r in runs)
    details = {"microstructure": mid, "contrast": contrast, "extrapolation": ex,
               "runs": [{k: r[k] for k in ("grid", "h_eff", "volume_fraction_image",
                                           "volume_fraction_exact", "overlap_voxels",
                                           "mixed_voxels", "scalar_fallback_voxels",
                                           "iterations", "relative_residual", "cg_info",
                                           "wall_time_s", "peak_rss_mb")} for r in runs],
               "wall_time_s": {"solve": t_solve, "voxelize_and_setup": t_vox,
                               "total_alone": t_solve + t_vox}}
    return entry, details


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("input")
    ap.add_argument("--cache", required=True)
    ap.add_argument("--out")
    ap.add_argument("--ids", help="comma-separated microstructure ids (default: all)")
    ap.add_argument("--contrasts", default="10,0.1")
    ap.add_argument("--resolutions", default="65,99,125")
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--subsample", type=int, default=8)
    a = ap.parse_args(argv)
    data = json.load(open(a.input))
    period = [float(v) for v in data["period"]]
    lam_m = float(data["lambda_matrix"])
    contrasts = [float(c) for c in a.contrasts.split(",")]
    resolutions = [int(n) for n in a.resolutions.split(",")]
    ids = a.ids.split(",") if a.ids else [m["id"] for m in data["microstructures"]]
    by_id = {m["id"]: m for m in data["microstructures"]}
    os.makedirs(a.cache, exist_ok=True)
    for mid in ids:
        for n in resolutions:
            solve_grid(by_id[mid], period, lam_m, contrasts, n, a.cache, a.tol, a.subsample)
    refs, details = [], []
    for mid in ids:
        for c in sorted(contrasts):
            e, d = reference_entry(mid, c, resolutions, a.cache)
            refs.append(e)
            details.append(d)
            log(f"{mid} contrast {c:g}: diag {e['diagonal']} +- {e['error']}, p {e['fit_p']:.3f}"
                f" reliable {e['fit_reliable']}, {d['wall_time_s']['total_alone']:.0f} s")
    if a.out:
        with open(a.out, "w") as fh:
            json.dump({"references": refs, "details": details}, fh, indent=1)


if __name__ == "__main__":
    main()
