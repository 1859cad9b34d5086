#!/usr/bin/env python3
"""The same random sphere microstructure as a sphere list and as labelled voxel images.

Writes into FOLDER: `spheres{32,64,128,256}.npy` (axes x, y, z; label 1 inside any of 60
spheres of radius 0.08 at random centres in the periodic unit cell, minimum image), `list.ron`
(the spheres as a `Spheres` phase) and `img{N}.ron` (the images as `Image` phases), all at
COUNT particles, contrast 10, Segment rule, periodic homogenisation. Run each with
`demcon run FOLDER/<scene>.ron` and compare `etc_tensor` in the summaries: the images converge
to the list as the voxel shrinks (docs/performance.md, "Images").

Usage: python3 scripts/image_vs_list.py FOLDER [COUNT]   (numpy needed)
"""
import sys

import numpy as np

folder = sys.argv[1]
count = int(sys.argv[2]) if len(sys.argv) > 2 else 60000
rng = np.random.default_rng(1)
centres = rng.random((60, 3))
for n in (32, 64, 128, 256):
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
    np.save(f"{folder}/spheres{n}.npy", lab)


def scene(phase, name):
    return f"""(
    name: "{name}",
    seed: 1,
    packing: Generate(container: Periodic(size: (1.0, 1.0, 1.0)), count: {count}, phi: 0.6, radius_cov: 0.3),
    surface: Laguerre,
    materials: [
        (name: "m", conductivity: 1.0, density: 1000.0, specific_heat: 500.0),
        (name: "s", conductivity: 10.0, density: 1000.0, specific_heat: 500.0),
    ],
    phases: [{phase}],
    phase_rule: Some(Segment),
    thermal: (bcs: [], solver: Homogenize),
    outputs: (vtk: false),
)
"""


listed = ", ".join(f"({float(c[0])!r}, {float(c[1])!r}, {float(c[2])!r})" for c in centres)
with open(f"{folder}/list.ron", "w") as f:
    f.write(scene(f'Spheres(material: "s", radius: 0.08, centres: [{listed}])', "list"))
for n in (32, 64, 128, 256):
    with open(f"{folder}/img{n}.ron", "w") as f:
        f.write(scene(f'Image(path: "spheres{n}.npy", voxel: {1.0 / n!r}, labels: [(0, "m"), (1, "s")])', f"img{n}"))
