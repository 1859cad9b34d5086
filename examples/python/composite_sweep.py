"""ETC of an epoxy/silica composite against the silica volume fraction, for three seeds.

Usage: python examples/python/composite_sweep.py [--count N] [--plot out.png]
The scene is a dict of the RON schema (docs/python.md) run in memory; the table goes to stdout,
the figure to --plot when matplotlib is installed. Default 4 000 particles per run (seconds).
"""

import argparse

import demcon

EPOXY, SILICA = 0.195, 1.5  # W/(m·K)


def scene(seed: int, count: int, fraction: float) -> dict:
    """The scene as a dict (the RON schema's shape: docs/python.md "Scenes as dicts")."""
    return {
        "name": "composite-sweep",
        "seed": seed,
        "packing": {
            "Generate": {
                "container": {"Box": {"size": (0.1, 0.1, 0.1)}},
                "count": count,
                "phi": 0.58,
                "radius_cov": 0.3,
            }
        },
        "surface": "Laguerre",
        "materials": [
            {"name": "epoxy", "conductivity": EPOXY, "density": 1200.0, "specific_heat": 1000.0},
            {"name": "silica", "conductivity": SILICA, "density": 2200.0, "specific_heat": 740.0},
        ],
        "phases": [{"Inclusions": {"material": "silica", "fraction": fraction, "size_ratio": 3.0}}],
        "thermal": {
            "initial_temperature": 25.0,
            "bcs": [
                {"WallTemperature": {"face": "YMin", "value": 25.0}},
                {"WallTemperature": {"face": "YMax", "value": 35.0}},
            ],
            "solver": "Steady",
        },
        "outputs": {"etc_axis": "Y", "vtk": False},
    }


def maxwell_garnett(f: float) -> float:
    """Maxwell Garnett (the Hashin–Shtrikman lower bound) for dilute spheres (W/(m·K))."""
    d = SILICA - EPOXY
    return EPOXY * (SILICA + 2 * EPOXY + 2 * f * d) / (SILICA + 2 * EPOXY - f * d)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=4000, help="particles per run")
    ap.add_argument("--fractions", type=float, nargs="+", default=[0.05, 0.1, 0.2, 0.3])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--plot", help="write the figure here (needs matplotlib)")
    args = ap.parse_args()

    rows = []
    print("fraction  seed  ETC (W/(m·K))  Maxwell Garnett")
    for f in args.fractions:
        for seed in args.seeds:
            r = demcon.Scene(scene(seed, args.count, f)).run()
            rows.append((f, seed, r.etc))
            print(f"{f:8.3f}  {seed:4d}  {r.etc:13.5f}  {maxwell_garnett(f):.5f}")

    if args.plot:
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
        except ImportError:
            print("matplotlib is not installed: no figure")
            return
        fig, ax = plt.subplots()
        for seed in args.seeds:
            pts = [(f, e) for f, s, e in rows if s == seed]
            ax.plot(*zip(*pts), "o-", label=f"seed {seed}")
        ax.set_xlabel("silica volume fraction")
        ax.set_ylabel("effective conductivity (W/(m·K))")
        ax.legend()
        fig.savefig(args.plot, dpi=120)
        print(f"figure in {args.plot}")


if __name__ == "__main__":
    main()
