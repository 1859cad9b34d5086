"""The same scenes through the CLI (`demcon run`) and through Python (`Scene.run(out=...)`):
identical outputs, wall times side by side, and what handing the arrays to Python costs.

Usage: python python/benches/cli_vs_python.py --demcon target/release/demcon [--repeat 3]
       [scene.ron ...]
Prints a Markdown table (docs/python.md). "identical" compares every file the two runs wrote
byte for byte, except summary.json, whose values are compared with the machine's figures
(wall times, event rates, the process's memory, wall times quoted in diagnostics) left out.
"""

import argparse
import filecmp
import json
import re
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import demcon

ROOT = Path(__file__).resolve().parents[2]
SCENES = [
    ROOT / "python/tests/data/homogeneous.ron",
    ROOT / "scenes/fibre-composite.ron",
    ROOT / "scenes/joule-transient.ron",
    ROOT / "python/benches/million.ron",
]


def measured(key: str) -> bool:
    """A figure of the machine, not of the result: times, rates, memory of the process."""
    return key.endswith("_s") or "rss" in key or key == "peak_bytes_per_particle"


def strip_times(v):
    """summary.json without the machine's figures (wall times, event rates, memory)."""
    if isinstance(v, dict):
        return {k: strip_times(x) for k, x in v.items() if not measured(k)}
    if isinstance(v, list):
        return [strip_times(x) for x in v]
    if isinstance(v, str):  # a diagnostic that quotes a wall time ("…, 0.967 s")
        return re.sub(r"\d+\.\d+ s\b", "<time> s", v)
    return v


def same_outputs(a: Path, b: Path) -> bool:
    names = sorted(p.name for p in a.iterdir())
    if names != sorted(p.name for p in b.iterdir()):
        return False
    for name in names:
        if name == "summary.json":
            sa = json.loads((a / name).read_text())
            sb = json.loads((b / name).read_text())
            if strip_times(sa) != strip_times(sb):
                return False
        elif (a / name).is_file() and not filecmp.cmp(a / name, b / name, shallow=False):
            return False
    return True


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--demcon", required=True, help="the CLI binary (target/release/demcon)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("scenes", nargs="*", type=Path, default=SCENES)
    args = ap.parse_args()
    print("| scene | particles | CLI (s) | Python (s) | Python / CLI | arrays to Python (ms) | outputs |")
    print("|---|---|---|---|---|---|---|")
    for scene in args.scenes:
        cli, py, handover = [], [], []
        same = True
        n = 0
        for k in range(args.repeat):
            with tempfile.TemporaryDirectory() as tmp:
                a, b = Path(tmp) / "cli", Path(tmp) / "py"
                t0 = time.perf_counter()
                subprocess.run(
                    [args.demcon, "run", str(scene), "--out", str(a), "--quiet"],
                    check=True,
                    stdout=subprocess.DEVNULL,
                )
                cli.append(time.perf_counter() - t0)
                t0 = time.perf_counter()
                r = demcon.Scene.from_file(scene).run(out=b, progress=False)
                py.append(time.perf_counter() - t0)
                # the run itself (wall_s) excluded: the worker thread, summary dict and arrays
                t1 = time.perf_counter()
                r2 = demcon.Scene.from_file(scene).run(progress=False)
                handover.append(time.perf_counter() - t1 - r2.wall_s)
                n = r.radii.shape[0]
                same = same and same_outputs(a, b)
        c, p = statistics.median(cli), statistics.median(py)
        print(
            f"| {scene.name} | {n} | {c:.2f} | {p:.2f} | {p / c:.3f} | {1e3 * statistics.median(handover):.0f} | "
            f"{'identical' if same else 'DIFFER'} |"
        )


if __name__ == "__main__":
    main()
