"""ETC of an epoxy/silica composite against the silica volume fraction, for three seeds.

Usage: python examples/python/composite_sweep.py [--count N] [--plot out.png]
The scene is built as RON text (docs/scenes.md) and run in memory; the table goes to stdout,
the figure to --plot when matplotlib is installed. Default 4 000 particles per run (seconds).
"""

import argparse

import demcon

SCENE = """(
    name: "composite-sweep",
    seed: {seed},
    packing: Generate(container: Box(size: (0.1, 0.1, 0.1)), count: {count}, phi: 0.58, radius_cov: 0.3),
    surface: Laguerre,
    materials: [
        (name: "epoxy", conductivity: 0.195, density: 1200.0, specific_heat: 1000.0),
        (name: "silica", conductivity: 1.5, density: 2200.0, specific_heat: 740.0),
    ],
    phases: [Inclusions(material: "silica", fraction: {fraction}, size_ratio: 3.0)],
    thermal: (
        initial_temperature: 25.0,
        bcs: [WallTemperature(face: YMin, value: 25.0), WallTemperature(face: YMax, value: 35.0)],
        solver: Steady,
    ),
    outputs: (etc_axis: Y, vtk: false),
)"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=4000, help="particles per run")
    ap.add_argument("--fractions", type=float, nargs="+", default=[0.05, 0.1, 0.2, 0.3])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--plot", help="write the figure here (needs matplotlib)")
    args = ap.parse_args()

    rows = []
    print("fraction  seed  ETC (W/(m·K))")
    for f in args.fractions:
        for seed in args.seeds:
            text = SCENE.format(seed=seed, count=args.count, fraction=f)
            r = demcon.Scene.from_str(text).run()
            rows.append((f, seed, r.etc))
            print(f"{f:8.3f}  {seed:4d}  {r.etc:.5f}")

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
