#!/usr/bin/env python3
"""Time to accuracy: demcon's periodic homogenisation against a voxel FFT solver (issue 32).

On this machine and on the identical microstructure, the effective conductivity of

  (a) a simple-cubic array of spheres, one sphere per periodic cell, volume fraction f = 0.3,
      contrast 10 (lambda_m = 1, lambda_i = 10 W/(m K));
  (b) one random periodic composite of the multi-inclusion case: f = 0.3, realisation 0 of
      `validation/data/multi-inclusion-fft-realisations.json` (124 silica spheres, 1.5 W/(m K),
      in epoxy, 0.195 W/(m K); the exact centres, with their periodic images),

is computed by

  * muSpectre (voxel FFT, Moulinec-Suquet type Green operator + CG; LGPL-3, run from a scratch
    venv outside the project, never vendored) on odd grids N^3; plain voxels (a voxel is the
    sphere's material when its centre is inside a sphere or one of its periodic images); the
    set-up (voxel mask, material assignment, solver construction and FFT plans) is timed apart
    from the solve (three load cases: the full tensor, as demcon gives it);
  * demcon (`demcon run`, `thermal.solver: Homogenize`, Laguerre cells, periodic box) at several
    particle counts, with `phase_rule: Conforming` (cells following the spheres' surfaces) and
    `Centre` (a particle takes the phase of its centre), the spheres given as a `Spheres` phase;
    three packing seeds per count (`--extra-counts`, default 5e5: the first seed only).

Quantity compared (the same for both tools): (a) the mean of the tensor's diagonal (the exact
tensor is isotropic); (b) lambda_yy, the only entry the reference extrapolates.

References and their own errors
-------------------------------
  (a) `validation/data/sphere-arrays-multipole.json`, row sc / f = 0.3 / contrast 10:
      lambda_e/lambda_m = 1.887740057635, a multipole (Rayleigh) solution; its estimated relative
      truncation error is 3e-11 (the row's `estimated_rel_error`; method and checks in
      validation/notes/sphere-arrays.md). Exact for this comparison.
  (b) `validation/data/multi-inclusion-fft-realisations.json`, f = 0.3, realisation 0:
      `extrapolated_y` = 0.35819 W/(m K), an FFT solution with laminate composite voxels at 64^3
      and 128^3, Richardson-extrapolated; the file's `method` text gives its error as "about
      1e-4 to 1e-3 relative (largest at phi = 0.5)". Errors below ~0.1 % in (b) are therefore not
      resolved by the reference. (Its 128^3 laminate value is +0.19 % from the extrapolation.)

Timings: wall-clock seconds on this machine (`nproc`, CPU model, date and load average are written
to the JSON; run it on a quiet machine, the figures move with the load). demcon runs on all cores
unless `--threads`; muSpectre's solve is single-threaded here (its CPU time, recorded beside the
wall time, equals it). For each tool the time is for the full tensor (three load cases). FFT
time = set-up (voxel mask, material assignment, solver construction and FFT plans) + solve.
demcon's time is split into the packing (the Lubachevsky-Stillinger packing, `demcon pack`) and
the rest (phases, conforming seeds, Laguerre tessellation, network, homogenisation, outputs: the
non-packing `stages` of summary.json); the chart plots the rest, and the packing added as a
second, open marker. A packing does not depend on the inclusions, so it is made once per (count,
seed) and reused, read from its file, by the four runs (two microstructures x two phase rules);
the script checks at the first count and seed that a run from the file gives bit for bit the
tensor of a run that packs itself (`Generate`, same seed), and records both packing times.
A user studying several microstructures (or phase rules) pays the packing once.

FFT grid sizes: odd (muSpectre's requirement) and with small prime factors only, as an FFT user
would pick them: measured here (one load case, SC), the cost per voxel and CG iteration is
3.2x higher at 97^3 (prime) and 1.8x at 129^3 (3 x 43) than at 99^3 or 125^3. The default ladder
15, 25, 35, 45, 63, 81, 105, 125, 147, 175 is 7-smooth.

muSpectre prints a harmless unit-mismatch warning (std::cout) per material and solver; the script
diverts it from stdout and records the distinct messages in the JSON (`fft_messages`).

Outputs: `validation/data/time-to-accuracy.json` (raw results: every FFT grid and demcon run,
the per-count summaries, the time to each target), `docs/img/time-to-accuracy.png` (|error| vs
wall time, log-log, one panel per microstructure), and a markdown table on stdout (progress on
stderr); a demcon run that fails is recorded with its error and the ladder goes on. Run by
hand, not in CI; about 15 minutes on 2 cores with the defaults (FFT grids 15-175, demcon 5e3-2e5
particles on three packings and 5e5 on one):

    python3 -m venv /work/scratch-fft/venv
    /work/scratch-fft/venv/bin/pip install muspectre numpy matplotlib
    cd /work/main && /work/scratch-fft/venv/bin/python scripts/fft_time_to_accuracy.py \\
        --demcon /work/helper-bin/demcon            # a release build of demcon

Options shorten or extend the ladders (`--resolutions 17,33,65 --counts 5000,20000 --seeds 1
--extra-counts ''`) and redirect the outputs (`--json`, `--png`); `--replot` redraws the chart and
the table from an existing JSON without running anything.

`--reuse-fft` reruns demcon only (about 7 minutes of the 15), e.g. for a new demcon binary: the
muSpectre rows are taken from the existing `--json` (rescored against the current references;
`--resolutions` is ignored) and the JSON records where each set of rows comes from: `machine` is
this run's (the demcon rows': binary path, mtime and SHA-256, date, load average at start and end),
`fft_origin` the run that made the muSpectre rows (its machine, date, load averages and muSpectre
version, carried over unchanged when that JSON had itself reused them) and the demcon binary whose
rows were replaced (`demcon_rows_replaced`). In a full run `fft_origin` is "this run". The chart's
title and the table name the date of reused muSpectre rows.
"""

import argparse
import contextlib
import datetime
import hashlib
import json
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MULTIPOLE = ROOT / "validation/data/sphere-arrays-multipole.json"
REALISATIONS = ROOT / "validation/data/multi-inclusion-fft-realisations.json"

CELL = 0.01  # edge of the periodic cell in demcon's scenes (m); the FFT cell is the unit cube
PACK_PHI = 0.6  # the packings of the sphere-arrays case (validation/src/cases/sphere_arrays.rs)
PACK_COV = 0.3
TARGETS = {"sc": 0.001, "random": 0.003}  # the accuracy targets (relative)
LABELS = {
    "sc": "(a) simple-cubic array, f = 0.3, contrast 10",
    "random": "(b) random composite, f = 0.3, realisation 0 (124 spheres)",
}


# --------------------------------------------------------------------------------------------
# The two microstructures and their references
# --------------------------------------------------------------------------------------------


def microstructures():
    """The two microstructures in unit-cell coordinates, with their references."""
    mp = json.loads(MULTIPOLE.read_text())
    row = next(
        r
        for r in mp["rows"]
        if r["lattice"] == "sc" and r["f"] == 0.3 and r["contrast"] == 10.0 and r["h_a_over_lambda_m"] is None
    )
    fr = json.loads(REALISATIONS.read_text())
    real = fr["by_volume_fraction"]["0.3"]["realisations"][0]
    assert real["realisation"] == 0
    lam_m, lam_i = fr["lambda_matrix_W_per_mK"], fr["lambda_spheres_W_per_mK"]
    return {
        "sc": {
            "centres": np.array([[0.5, 0.5, 0.5]]),
            "radius": 1.0 / row["cell_side_over_radius"],
            "lambda_m": 1.0,
            "lambda_i": 10.0,
            "component": "mean of the diagonal",
            "reference": 1.0 * row["lambda_e_over_lambda_m"],
            "reference_source": "validation/data/sphere-arrays-multipole.json (sc, f = 0.3, contrast 10)",
            "reference_error": f"multipole, estimated relative truncation error {row['estimated_rel_error']:.1e}",
        },
        "random": {
            "centres": np.array(real["centres"], dtype=float),
            "radius": 0.5 * real["D"],
            "lambda_m": lam_m,
            "lambda_i": lam_i,
            "component": "yy",
            "reference": real["extrapolated_y"],
            "reference_source": "validation/data/multi-inclusion-fft-realisations.json (f = 0.3, realisation 0, extrapolated_y)",
            "reference_error": "the file's method: " + fr["method"][fr["method"].index("its error") :].strip().rstrip("."),
            "reference_method": fr["method"],
            "fft_laminate_64": real["fft_laminate_64"],
            "fft_laminate_128": real["fft_laminate_128"],
        },
    }


def component(tensor, micro):
    """The compared scalar of a 3x3 tensor."""
    t = np.asarray(tensor, dtype=float)
    return float(np.trace(t) / 3.0) if micro == "sc" else float(t[1, 1])


def score(row, micro, m):
    """Sets a row's compared value and its signed relative error against the reference."""
    row["value"] = component(row["tensor"], micro)
    row["error"] = row["value"] / m["reference"] - 1.0


# --------------------------------------------------------------------------------------------
# muSpectre
# --------------------------------------------------------------------------------------------


def voxel_mask(n, centres, radius):
    """Voxels (centres at (i + 1/2)/n) inside any sphere or periodic image; unit cell; [i, j, k]."""
    mask = np.zeros((n, n, n), dtype=bool)
    h = 1.0 / n
    r2 = radius * radius
    for c in centres:
        # the voxel indices within the sphere's bounding box, wrapped (periodic images)
        lo = np.floor((c - radius) / h - 0.5).astype(int)
        hi = np.ceil((c + radius) / h - 0.5).astype(int)
        axes = [np.arange(lo[d], hi[d] + 1) for d in range(3)]
        dx = [((a + 0.5) * h - c[d]) ** 2 for d, a in enumerate(axes)]
        ball = dx[0][:, None, None] + dx[1][None, :, None] + dx[2][None, None, :] < r2
        ix = np.ix_(*(a % n for a in axes))
        mask[ix] |= ball
    return mask


@contextlib.contextmanager
def captured_fd1(sink):
    """Sends file descriptor 1 (muSpectre's C++ std::cout: a unit-mismatch warning per material
    and solver) to `sink` (a list of lines), so that stdout carries only the table."""
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+") as f:
        os.dup2(f.fileno(), 1)
        try:
            yield
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
            f.seek(0)
            sink.extend(ln.rstrip() for ln in f if ln.strip())


def run_fft(n, m, msp):
    """One muSpectre homogenisation: the full tensor (three load cases) on an n^3 grid."""
    t0, c0 = time.perf_counter(), time.process_time()
    inside = voxel_mask(n, m["centres"], m["radius"])
    t_mask = time.perf_counter()
    rve = msp.cell.CellData.make([n] * 3, [1.0] * 3)
    rve.nb_quad_pts = 1
    matrix = msp.material.MaterialLinearDiffusion_3d.make(rve, "matrix", m["lambda_m"])
    incl = msp.material.MaterialLinearDiffusion_3d.make(rve, "inclusions", m["lambda_i"])
    # muSpectre's pixel index is column-major (k = i + n j + n^2 k, checked on its pixel
    # iterator); it has no bulk assignment, so add_pixel is mapped over the index arrays (no
    # Python loop over the grid's coordinates).
    flat = inside.ravel(order="F")
    for mat, idx in ((incl, np.flatnonzero(flat)), (matrix, np.flatnonzero(~flat))):
        list(map(mat.add_pixel, idx.tolist()))
    t_assign = time.perf_counter()
    krylov = msp.solvers.KrylovSolverCG(1e-8, 1000, verbose=msp.Verbosity.Silent)
    solver = msp.solvers.SolverNewtonCG(rve, krylov, msp.Verbosity.Silent, 1e-5, 0, 1000)
    solver.initialise_cell()
    t_setup, c_setup = time.perf_counter(), time.process_time()
    tensor = np.zeros((3, 3))
    per_load, fev, done = [], [], 0
    for d in range(3):
        ts = time.perf_counter()
        g = np.zeros((3, 1))
        g[d] = 1.0  # the mean gradient itself (not an increment: checked, consecutive loads don't add)
        res = solver.solve_load_increment(g)
        if not res.success:
            raise RuntimeError(f"muSpectre {n}^3 load {d}: {res.message}")
        # column d of the effective tensor: the mean flux under a unit mean gradient along d
        tensor[:, d] = res.stress.reshape(3, -1, order="F").mean(axis=1)
        per_load.append(time.perf_counter() - ts)
        fev.append(int(res.nb_fev) - done)  # nb_fev counts over the solver's life
        done = int(res.nb_fev)
    t_end, c_end = time.perf_counter(), time.process_time()
    return {
        "n": n,
        "voxel_fraction": float(inside.mean()),
        "mask_s": t_mask - t0,
        "assign_s": t_assign - t_mask,
        "setup_s": t_setup - t0,
        "solve_s": t_end - t_setup,
        "solve_per_load_s": per_load,
        "setup_cpu_s": c_setup - c0,
        "solve_cpu_s": c_end - c_setup,
        "operator_evaluations_per_load": fev,
        "tensor": tensor.tolist(),
    }


# --------------------------------------------------------------------------------------------
# demcon
# --------------------------------------------------------------------------------------------


def scene_ron(name, packing_file, m, rule):
    """A periodic homogenisation scene on an imported packing, the spheres as a Spheres phase."""
    centres = ", ".join("({!r}, {!r}, {!r})".format(*(float(v * CELL) for v in c)) for c in m["centres"])
    return f"""(
    name: "{name}",
    seed: 1,
    packing: File(path: "{packing_file}", container: Some(Periodic(size: ({CELL}, {CELL}, {CELL})))),
    surface: Laguerre,
    materials: [
        (name: "matrix", conductivity: {float(m["lambda_m"])!r}, density: 1000.0, specific_heat: 1000.0,
         resistivity: None, resistivity_temp_coeff: 0.0, resistivity_ref_temp: 20.0),
        (name: "spheres", conductivity: {float(m["lambda_i"])!r}, density: 1000.0, specific_heat: 1000.0,
         resistivity: None, resistivity_temp_coeff: 0.0, resistivity_ref_temp: 20.0),
    ],
    phases: [Spheres(material: "spheres", radius: {float(m["radius"] * CELL)!r}, centres: [{centres}])],
    phase_rule: {rule},
    thermal: Some((initial_temperature: 0.0, bcs: [], sources: [], solver: Homogenize)),
    outputs: (vtk: false),
)
"""


def generate_variant(ron, count, seed):
    """The same scene packing itself (Generate) with the packing's parameters and seed."""
    gen = (
        f"packing: Generate(container: Periodic(size: ({CELL}, {CELL}, {CELL})), count: {count}, "
        f"phi: {PACK_PHI}, radius_cov: {PACK_COV}, radius_range: None, allow_short: false),"
    )
    ron = re.sub(r"packing: File\(.*\),\n", gen + "\n", ron)
    return re.sub(r"seed: 1,", f"seed: {seed},", ron)


class RunFailed(RuntimeError):
    """A demcon command that exited with an error."""


def save(result, path):
    """The raw results so far (the summaries are added at the end)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(result, indent=1) + "\n")


def timed(cmd):
    """Runs a command; its wall and CPU time (children's user + system)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        msg = [ln for ln in p.stderr.splitlines() if ln.startswith("error")] or p.stderr.splitlines()[-1:]
        raise RunFailed(f"{Path(cmd[2]).name if len(cmd) > 2 else cmd} (exit {p.returncode}): {' '.join(msg)}")
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return p, wall, cpu


def pack(demcon, count, seed, path):
    """`demcon pack` of the periodic cell; its report."""
    report = path.with_suffix(".json")
    _, wall, cpu = timed(
        [demcon, "pack", "--container", "periodic", "--size", f"{CELL},{CELL},{CELL}", "--count", str(count),
         "--phi", str(PACK_PHI), "--radius-cov", str(PACK_COV), "--seed", str(seed), "--out", str(path),
         "--quiet", "--report-json", str(report)]
    )  # fmt: skip
    rep = json.loads(report.read_text())
    return {"pack_s": rep["wall_s"], "process_wall_s": wall, "cpu_s": cpu, "stop": rep["stop"], "phi": rep["phi"]}


def run_demcon(demcon, ron, workdir, tag, threads):
    """`demcon run` of one scene; the tensor, the stages and the times. The phase rule that ran
    (summary.json's build.phase_rule; older binaries don't write it) must be the scene's."""
    scene = workdir / f"{tag}.ron"
    scene.write_text(ron)
    out = workdir / f"out-{tag}"
    cmd = [demcon, "run", str(scene), "--out", str(out), "--quiet"]
    if threads:
        cmd += ["--threads", str(threads)]
    p, wall, cpu = timed(cmd)
    s = json.loads((out / "summary.json").read_text())
    stages = {st["stage"]: st["wall_s"] for st in s["stages"]}
    h = s["homogenization"]["thermal"]
    ran = s["build"].get("phase_rule")
    asked = re.search(r"phase_rule: (\w+)", ron)
    if ran is not None and asked is not None and ran != asked.group(1):
        raise RuntimeError(f"{tag}: the scene asks for phase_rule {asked.group(1)}, summary.json says {ran}")
    return {
        "n_particles": s["model"]["n_particles"],
        "phase_rule": ran,
        "tensor": s["etc_tensor"],
        "stages_s": stages,
        "summary_wall_s": s["wall_s"],
        # everything but the packing (which is here the reading of the packing file)
        "rest_s": s["wall_s"] - stages.get("packing", 0.0),
        "process_wall_s": wall,
        "cpu_s": cpu,
        "solver": h["method"],
        "iterations": h["iterations"],
        "conform": s["build"].get("conform"),
        "phase_fractions": s["build"]["phase_fractions"],
        "diagnostics": s["diagnostics"],
        "stderr_warnings": [ln for ln in p.stderr.splitlines() if "warn" in ln.lower()],
    }


# --------------------------------------------------------------------------------------------
# Summaries, chart, table
# --------------------------------------------------------------------------------------------


def time_to_target(points, target):
    """The first point (in increasing cost) from which every costlier point is within the target,
    and the first point within it at all; points: (cost key, time s, |error|) sorted by cost."""
    steady = None
    for i in range(len(points)):
        if all(e <= target for _, _, e in points[i:]):
            steady = points[i]
            break
    first = next((p for p in points if p[2] <= target), None)
    fmt = lambda p: None if p is None else {"at": p[0], "time_s": p[1], "abs_error": p[2]}  # noqa: E731
    return {"target": target, "from_here_on": fmt(steady), "first_hit": fmt(first)}


def aggregate_demcon(rows, micro, rule):
    """Per particle count: mean times, mean and max |error| over the seeds."""
    out = []
    for count in sorted({r["count"] for r in rows}):
        mine = [r for r in rows if r["count"] == count and r["micro"] == micro and r["rule"] == rule]
        failed = [{"seed": r["seed"], "failed": r["failed"]} for r in mine if "failed" in r]
        rs = [r for r in mine if "failed" not in r]
        if not rs:
            if failed:
                out.append({"count": count, "seeds": [], "failed_runs": failed})
            continue
        err = np.array([r["error"] for r in rs])
        out.append({
            "count": count,
            "seeds": [r["seed"] for r in rs],
            "n_particles_mean": float(np.mean([r["n_particles"] for r in rs])),
            "rest_s_mean": float(np.mean([r["rest_s"] for r in rs])),
            "pack_s_mean": float(np.mean([r["pack_s"] for r in rs])),
            "mean_error": float(err.mean()),
            "mean_abs_error": float(np.abs(err).mean()),
            "max_abs_error": float(np.abs(err).max()),
            "failed_runs": failed,
        })  # fmt: skip
    return out


def seeds_label(result, rule):
    """How many packings each count had (over both microstructures, failed runs included)."""
    per = {}
    for r in result["demcon"]:
        if r["rule"] == rule:
            per.setdefault(r["count"], set()).add(r["seed"])
    most = max(len(v) for v in per.values())
    fewer = [f"{c:,}: {len(v)}" for c, v in sorted(per.items()) if len(v) != most]
    return ", ".join([f"{most} packings per count"] + fewer)


def chart(result, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5.8), sharey=True)
    for ax, micro in zip(axes, ("sc", "random")):
        fft = [r for r in result["fft"] if r["micro"] == micro]
        t = [r["setup_s"] + r["solve_s"] for r in fft]
        e = [100 * abs(r["error"]) for r in fft]
        ax.plot(t, e, "o-", color="tab:blue", label="muSpectre voxel FFT (set-up + solve)")
        for r, x, y in zip(fft, t, e):
            ax.annotate(f"{r['n']}³", (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7,
                        color="tab:blue")  # fmt: skip
        styles = {"Conforming": ("tab:red", "s"), "Centre": ("tab:gray", "^")}
        for rule, (col, mk) in styles.items():
            agg = [a for a in result["demcon_summary"][micro][rule] if a["seeds"]]  # failed counts left out
            if not agg:
                continue
            x = np.array([a["rest_s_mean"] for a in agg])
            y = np.array([100 * a["mean_abs_error"] for a in agg])
            ymax = np.array([100 * a["max_abs_error"] for a in agg])
            nseeds = seeds_label(result, rule)
            ax.errorbar(x, y, yerr=[np.zeros_like(y), ymax - y], fmt=mk + "-", color=col, capsize=2,
                        label=f"demcon {rule} (build + homogenise; mean |err|, bar to max; {nseeds})")  # fmt: skip
            if rule == "Conforming":
                xp = x + np.array([a["pack_s_mean"] for a in agg])
                ax.plot(xp, y, mk + ":", color=col, mfc="none", alpha=0.7,
                        label="demcon Conforming incl. packing (made once, reusable for any inclusions)")  # fmt: skip
                for a, xx, yy in zip(agg, x, y):
                    ax.annotate(f"{a['count'] / 1000:g}k", (xx, yy), textcoords="offset points", xytext=(4, -10),
                                fontsize=7, color=col)  # fmt: skip
            failed = [a for a in result["demcon_summary"][micro][rule] if a["failed_runs"]]
            if failed:
                what = ", ".join(f"{a['count'] / 1000:g}k seed {f['seed']}" for a in failed for f in a["failed_runs"])
                ax.text(0.98, 0.97 if rule == "Conforming" else 0.92, f"demcon {rule} failed at {what} (see JSON)",
                        transform=ax.transAxes, ha="right", va="top", fontsize=7, color=col)  # fmt: skip
        target = 100 * TARGETS[micro]
        ax.axhline(target, color="k", lw=0.8, ls="--")
        ax.text(0.02, target, f" target {target:g} %", transform=ax.get_yaxis_transform(),
                va="bottom", fontsize=8)  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time (s)")
        ax.set_title(LABELS[micro] + f"\n[{result['microstructures'][micro]['component']}]", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    # (b)'s reference is itself uncertain to 1e-4 .. 1e-3 relative: shade what it cannot resolve
    lo, hi = axes[1].get_ylim()
    axes[1].axhspan(lo, 0.1, color="0.92", zorder=0)
    axes[1].text(0.02, 0.1 * 0.8, " within the reference's own error (up to 0.1 %)", transform=axes[1].get_yaxis_transform(),
                 fontsize=7, va="top", color="0.4")  # fmt: skip
    axes[1].set_ylim(lo, hi)
    axes[0].set_ylabel("|λ/λ_ref − 1| (%)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=7, frameon=False)
    m = result["machine"]
    fig.suptitle(f"Time to accuracy, periodic homogenisation: {m['nproc']} cores, {m['cpu_model']}, {m['date']}"
                 + provenance(result), fontsize=10)  # fmt: skip
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130)


def provenance(result):
    """'' when both tools ran together, else the date of the reused muSpectre rows."""
    o = result.get("fft_origin")
    return f" (muSpectre rows of {o['machine']['date']}, reused)" if isinstance(o, dict) else ""


def table(result):
    m = result["machine"]
    lines = [f"demcon: {m['demcon_binary']} ({m['date']}, load {m['load_average_at_start']:.2f} at start)"
             + provenance(result), ""]  # fmt: skip
    for micro in ("sc", "random"):
        ms = result["microstructures"][micro]
        lines += [
            f"### {LABELS[micro]}",
            "",
            f"Reference {ms['reference']:.6f} W/(m·K) ({ms['component']}); {ms['reference_error']}.",
            "",
            "| tool | grid / particles | set-up (FFT) or packing (demcon), s | solve (FFT) or build + solve "
            "(demcon), s | error: signed (FFT); mean abs / max abs over packings (demcon) |",
            "| --- | --- | --- | --- | --- |",
        ]
        for r in (r for r in result["fft"] if r["micro"] == micro):
            lines.append(
                f"| muSpectre FFT | {r['n']}³ | {r['setup_s']:.2f} | {r['solve_s']:.2f} | {100 * r['error']:+.3f} % |"
            )
        for rule in ("Conforming", "Centre"):
            for a in result["demcon_summary"][micro][rule]:
                fails = "; ".join(f"seed {f['seed']} failed: {f['failed']}" for f in a["failed_runs"])
                if not a["seeds"]:
                    lines.append(f"| demcon {rule} | {a['count']:,} | | | {fails} |")
                    continue
                lines.append(
                    f"| demcon {rule} | {a['count']:,} ({a['n_particles_mean']:,.0f} cells; {len(a['seeds'])} "
                    f"packing{'s' if len(a['seeds']) > 1 else ''}) | {a['pack_s_mean']:.2f} | {a['rest_s_mean']:.2f} | "
                    f"{100 * a['mean_abs_error']:.3f} % / "
                    f"{100 * a['max_abs_error']:.3f} % (mean signed {100 * a['mean_error']:+.3f} %)"
                    + (f"; {fails}" if fails else "")
                    + " |"
                )
        lines.append("")
        tt = result["time_to_target"][micro]
        lines.append(f"Time to {100 * TARGETS[micro]:g} % (from this point on every finer run is within it):")
        for tool, v in tt.items():
            s = v["from_here_on"]
            f = v["first_hit"]
            txt = "not reached" if s is None else f"{s['time_s']:.2f} s at {s['at']}"
            if f is not None and (s is None or f["at"] != s["at"]):
                txt += f" (first hit {f['time_s']:.2f} s at {f['at']})"
            lines.append(f"- {tool}: {txt}")
        lines.append("")
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------


def machine(demcon):
    """This run's machine, date, load and demcon binary (which made the demcon rows)."""
    cpu = "unknown"
    for ln in Path("/proc/cpuinfo").read_text().splitlines():
        if ln.startswith("model name"):
            cpu = ln.split(":", 1)[1].strip()
            break
    nproc = subprocess.run(["nproc"], capture_output=True, text=True).stdout.strip()
    ver = subprocess.run([demcon, "--version"], capture_output=True, text=True).stdout.strip()
    return {
        "nproc": int(nproc),
        "cpu_model": cpu,
        "date": datetime.date.today().isoformat(),
        "load_average_at_start": os.getloadavg()[0],
        "python": platform.python_version(),
        "numpy": np.__version__,
        "demcon": ver,
        "demcon_binary": str(demcon),
        "demcon_binary_mtime": datetime.datetime.fromtimestamp(os.stat(demcon).st_mtime, datetime.timezone.utc)
        .isoformat(timespec="seconds"),
        "demcon_binary_sha256": hashlib.sha256(Path(demcon).read_bytes()).hexdigest(),
    }


def muspectre_version():
    try:
        from importlib.metadata import version

        return version("muspectre")
    except Exception:  # pragma: no cover
        return "unknown"


def run_fft_ladder(result, micros, resolutions, json_path):
    """muSpectre on every grid of both microstructures: result["fft"] and result["fft_messages"]."""
    import muSpectre as msp  # the scratch venv's

    result["machine"]["muspectre"] = muspectre_version()
    result["fft_origin"] = "this run (see 'machine')"
    print(f"muSpectre {result['machine']['muspectre']}: grids {resolutions}", file=sys.stderr)
    fft_messages = []
    for micro, m in micros.items():
        for n in resolutions:
            with captured_fd1(fft_messages):
                r = run_fft(n, m, msp)
            r["micro"] = micro
            score(r, micro, m)
            result["fft"].append(r)
            save(result, json_path)
            print(f"  fft {micro:6s} {n:4d}^3 set-up {r['setup_s']:7.2f} s solve {r['solve_s']:7.2f} s "
                  f"error {100 * r['error']:+.4f} %", file=sys.stderr)  # fmt: skip
    result["fft_messages"] = sorted(set(fft_messages))
    print(f"  muSpectre printed {len(fft_messages)} lines, distinct: {result['fft_messages']}", file=sys.stderr)


def reuse_fft(result, micros, old, json_path):
    """The muSpectre rows of an earlier JSON (`old`), rescored against the current references;
    result["fft_origin"]: the run that made them (the earlier run's machine, date and load, or its
    own 'fft_origin' when it had itself reused them) and the demcon binary of the rows replaced."""
    if not old.get("fft"):
        raise SystemExit(f"--reuse-fft: {json_path} has no muSpectre rows")
    for r in old["fft"]:
        score(r, r["micro"], micros[r["micro"]])
    result["fft"] = old["fft"]
    result["fft_messages"] = old["fft_messages"]
    origin = old.get("fft_origin")
    if not isinstance(origin, dict):  # the earlier run made them itself
        path = json_path.resolve()
        origin = {
            "reused_from": str(path.relative_to(ROOT)) if path.is_relative_to(ROOT) else str(path),
            "machine": {k: v for k, v in old["machine"].items() if not k.startswith("demcon")},
        }
    origin["demcon_rows_replaced"] = {k: v for k, v in old["machine"].items() if k.startswith("demcon") or k == "date"}
    result["fft_origin"] = origin
    grids = sorted({r["n"] for r in old["fft"]})
    print(f"muSpectre rows reused from {json_path} ({origin['machine']['date']}; grids {grids})", file=sys.stderr)


def ints(s):
    return [int(x) for x in s.split(",") if x]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--demcon", default="/work/helper-bin/demcon", help="the demcon binary (release build)")
    ap.add_argument("--resolutions", type=ints, default=ints("15,25,35,45,63,81,105,125,147,175"))
    ap.add_argument("--counts", type=ints, default=ints("5000,10000,20000,50000,100000,200000"))
    ap.add_argument("--seeds", type=ints, default=ints("1,2,3"))
    ap.add_argument("--extra-counts", type=ints, default=ints("500000"), help="counts run on the first seed only")
    ap.add_argument("--threads", type=int, default=None, help="demcon --threads (default: all cores)")
    ap.add_argument("--json", type=Path, default=ROOT / "validation/data/time-to-accuracy.json")
    ap.add_argument("--png", type=Path, default=ROOT / "docs/img/time-to-accuracy.png")
    ap.add_argument("--replot", action="store_true", help="redraw the chart and table from --json, run nothing")
    ap.add_argument("--reuse-fft", action="store_true",
                    help="keep the muSpectre rows of --json (their machine, date and load recorded in 'fft_origin') "
                    "and rerun demcon only; --resolutions is then ignored")  # fmt: skip
    ap.add_argument("--workdir", type=Path, default=None, help="keep packings and runs here (default: a temp dir)")
    args = ap.parse_args()
    if args.replot:
        result = json.loads(args.json.read_text())
        chart(result, args.png)
        print(table(result))
        return
    demcon = str(Path(args.demcon).resolve())
    old = json.loads(args.json.read_text()) if args.reuse_fft else None  # read before it is overwritten

    micros = microstructures()
    result = {
        "what": "Time to accuracy of the periodic effective conductivity: demcon (Laguerre cells, "
        "Homogenize; Conforming and Centre phase rules) against muSpectre (voxel FFT, plain voxels) on "
        "the same microstructures, on one machine (issue 32). Written by scripts/fft_time_to_accuracy.py; "
        "see its docstring for the method.",
        "machine": machine(demcon),
        "fft_origin": None,  # set with the muSpectre rows: this run, or the earlier run they are reused from
        "settings": {
            "fft": "muSpectre MaterialLinearDiffusion_3d, SolverNewtonCG (1 Newton step, linear) with "
            "KrylovSolverCG rel. tol 1e-8; three load cases (unit mean gradient along x, y, z); voxel "
            "centres at (i + 1/2)/N, a voxel is the spheres' material when its centre is inside a sphere "
            "or a periodic image; time = set-up (mask, material assignment, solver and FFT plans) + solve",
            "demcon": f"periodic cell of side {CELL} m, demcon pack phi = {PACK_PHI}, radius CoV = "
            f"{PACK_COV} (Lubachevsky-Stillinger), packing read from its file by each run; surface: "
            "Laguerre, thermal.solver: Homogenize, outputs: (vtk: false); rest_s = summary.json wall_s "
            "minus its 'packing' stage (the file read); pack_s = demcon pack's own wall_s",
            "errors": "relative, signed: value/reference - 1 (value: the compared component)",
        },
        "microstructures": {
            k: {kk: (vv.tolist() if isinstance(vv, np.ndarray) else vv) for kk, vv in v.items()}
            for k, v in micros.items()
        },
        "fft": [],
        "demcon": [],
    }
    for k in result["microstructures"].values():
        k.pop("centres")  # the realisation's centres are in its own file

    # ---- muSpectre ----
    if old is None:
        run_fft_ladder(result, micros, args.resolutions, args.json)
    else:
        reuse_fft(result, micros, old, args.json)

    # ---- demcon ----
    tmp = None
    if args.workdir is None:
        tmp = tempfile.TemporaryDirectory(prefix="tta-")
        work = Path(tmp.name)
    else:
        work = args.workdir
        work.mkdir(parents=True, exist_ok=True)
    # the first seed's packing of the smallest count is also checked against a run that packs itself
    ladder = [(c, s) for c in args.counts for s in args.seeds] + [(c, args.seeds[0]) for c in args.extra_counts]
    for count, seed in ladder:
        packing = work / f"pack-{count}-{seed}.xyzr"
        pk = pack(demcon, count, seed, packing)
        for micro, m in micros.items():
            for rule in ("Conforming", "Centre"):
                tag = f"{micro}-{rule}-{count}-{seed}"
                ron = scene_ron(f"tta-{tag}", packing, m, rule)
                try:
                    r = run_demcon(demcon, ron, work, tag, args.threads)
                except RunFailed as e:
                    # recorded and reported, not hidden: the ladder goes on
                    result["demcon"].append(dict(micro=micro, rule=rule, count=count, seed=seed, pack=pk, failed=str(e)))
                    print(f"  demcon {micro:6s} {rule:10s} {count:7d} seed {seed}: FAILED: {e}", file=sys.stderr)
                    save(result, args.json)
                    continue
                r.update(micro=micro, rule=rule, count=count, seed=seed, pack=pk, pack_s=pk["pack_s"])
                score(r, micro, m)
                result["demcon"].append(r)
                save(result, args.json)
                print(f"  demcon {micro:6s} {rule:10s} {count:7d} seed {seed}: pack {pk['pack_s']:6.2f} s "
                      f"rest {r['rest_s']:6.2f} s error {100 * r['error']:+.4f} %", file=sys.stderr)  # fmt: skip
                if "reuse_check" not in result:
                    g = run_demcon(demcon, generate_variant(ron, count, seed), work, tag + "-generate", args.threads)
                    result["reuse_check"] = {
                        "scene": tag,
                        "tensor_identical": g["tensor"] == r["tensor"],
                        "generate_packing_stage_s": g["stages_s"]["packing"],
                        "demcon_pack_s": pk["pack_s"],
                    }
                    if g["tensor"] != r["tensor"]:
                        print("  WARNING: the run from the packing file differs from Generate", file=sys.stderr)
    if tmp is not None:
        tmp.cleanup()

    # ---- summaries ----
    result["demcon_summary"] = {
        micro: {rule: aggregate_demcon(result["demcon"], micro, rule) for rule in ("Conforming", "Centre")}
        for micro in micros
    }
    result["time_to_target"] = {}
    for micro in micros:
        fft = sorted((r for r in result["fft"] if r["micro"] == micro), key=lambda r: r["n"])
        tt = {
            "muSpectre (set-up + solve)": time_to_target(
                [(f"{r['n']}^3", r["setup_s"] + r["solve_s"], abs(r["error"])) for r in fft], TARGETS[micro]
            )
        }
        for rule in ("Conforming", "Centre"):
            agg = [a for a in result["demcon_summary"][micro][rule] if a["seeds"]]  # failed counts left out
            tt[f"demcon {rule} (solve, max over packings)"] = time_to_target(
                [(f"{a['count']} particles", a["rest_s_mean"], a["max_abs_error"]) for a in agg], TARGETS[micro]
            )
            tt[f"demcon {rule} (solve + packing, max over packings)"] = time_to_target(
                [(f"{a['count']} particles", a["rest_s_mean"] + a["pack_s_mean"], a["max_abs_error"]) for a in agg],
                TARGETS[micro],
            )
        result["time_to_target"][micro] = tt

    result["machine"]["load_average_at_end"] = os.getloadavg()[0]
    save(result, args.json)
    chart(result, args.png)
    print(table(result))
    print(f"\nwritten: {args.json}, {args.png}", file=sys.stderr)


if __name__ == "__main__":
    main()
