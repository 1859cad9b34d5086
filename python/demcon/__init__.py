"""demcon from Python: heat and electric conduction in sphere packings.

Scenes are demcon's RON files (docs/scenes.md) or dicts of the same schema, read and checked by
the same code as the CLI ``demcon run``; packings are numpy arrays; runs release the GIL and
stop on Ctrl-C; results come back as numpy arrays in SI units. See docs/python.md.
"""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from ._demcon import Packing, RunResult, Scene, SceneError, __version__, pack

#: ``Scene.run``'s result (the same class as ``RunResult``).
Result = RunResult

__all__ = ["Packing", "Result", "RunResult", "Scene", "SceneError", "__version__", "homogenize", "pack"]

_Materials = Union[Mapping[str, Any], Iterable[Mapping[str, Any]]]


def _material_list(materials: _Materials) -> list:
    """Materials as a scene's list of dicts: a list of dicts as is; a dict ``{name: λ}`` or
    ``{name: {property: value}}`` by name, in its order."""
    if isinstance(materials, Mapping):
        out = []
        for name, value in materials.items():
            if isinstance(value, Mapping):
                out.append({"name": name, **value})
            elif isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
                out.append({"name": name, "conductivity": float(value)})
            else:
                raise TypeError(
                    f"materials[{name!r}] = {value!r}: a conductivity (W/(m·K)) or a dict of the "
                    "material's properties ({'conductivity': ..., 'resistivity': ...})"
                )
        return out
    out = list(materials)
    for k, m in enumerate(out):
        if not isinstance(m, Mapping):
            raise TypeError(
                f"materials[{k}] = {m!r}: a dict as in a scene ({{'name': 'epoxy', 'conductivity': 0.2}})"
            )
    return out


def homogenize(
    packing: Packing,
    materials: _Materials,
    phases: Union[Sequence[Any], np.ndarray, None] = None,
    *,
    physics: str = "thermal",
    surface: Any = "Laguerre",
    threads: Optional[int] = None,
) -> np.ndarray:
    """The effective conductivity tensor of a periodic packing, by periodic homogenisation.

    - ``packing``: a ``demcon.Packing`` in a ``Periodic`` container (``demcon.pack`` or
      ``Packing.from_arrays``);
    - ``materials``: a scene's material dicts (``[{"name": "epoxy", "conductivity": 0.2},
      ...]``), or a dict by name (``{"epoxy": 0.2, "silica": 1.5}``, or ``{"epoxy": {...}}``);
      W/(m·K), and ``resistivity`` in Ω·m for ``physics="electric"``; ``density`` and
      ``specific_heat`` may be left out (a homogenisation is steady). The first is phase 0;
    - ``phases``: each sphere's material, as an (N,) integer array (indices into
      ``materials``), or a scene's ``phases`` list (inclusions, shapes, regions) laid over the
      packing's own ``phase``; None keeps the packing's ``phase``;
    - ``physics``: ``"thermal"`` (W/(m·K)) or ``"electric"`` (S/m);
    - ``surface``: the network's transmission surface (a scene's ``surface``).

    Returns the (3, 3) tensor as a numpy array. Raises ``demcon.SceneError`` naming the field
    (``materials[0].conductivity``) on a bad value.
    """
    if physics not in ("thermal", "electric"):
        raise ValueError(f"physics = {physics!r}: allowed are 'thermal' and 'electric'")
    scene_phases: list = []
    if isinstance(phases, np.ndarray) or (
        isinstance(phases, Sequence) and len(phases) > 0 and all(isinstance(k, (int, np.integer, np.bool_)) for k in phases)
    ):
        # one material index per sphere
        packing = Packing.from_arrays(packing.centres, packing.radii, packing.container, phase=np.asarray(phases))
    elif phases is not None:
        scene_phases = list(phases)
    # a homogenisation is steady: density and specific heat play no part (1.0 fills them in)
    spec: dict = {
        "name": "homogenize",
        "surface": surface,
        "materials": [{"density": 1.0, "specific_heat": 1.0, **m} for m in _material_list(materials)],
        "phases": scene_phases,
    }
    if physics == "thermal":
        spec["thermal"] = {"bcs": [], "solver": "Homogenize"}
    else:
        spec["electric"] = {"electrodes": [], "homogenize": True}
    result = Scene(spec, packing=packing).run(threads=threads, progress=False)
    return result.etc_tensor if physics == "thermal" else result.electric_tensor
