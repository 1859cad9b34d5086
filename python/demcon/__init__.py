"""demcon from Python: heat and electric conduction in sphere packings.

Scenes are demcon's RON files (docs/scenes.md) or dicts of the same schema, read and checked by
the same code as the CLI ``demcon run``; packings are numpy arrays; runs release the GIL and
stop on Ctrl-C; results come back as numpy arrays in SI units. See docs/python.md.
"""

from __future__ import annotations

from typing import Any, Iterable, Mapping, Optional

from ._demcon import Packing, RunResult, Scene, SceneError, __version__, pack

__all__ = ["Packing", "RunResult", "Scene", "SceneError", "__version__", "homogenize", "pack"]


def homogenize(
    packing: Packing,
    materials: Iterable[Mapping[str, Any]],
    phases: Iterable[Any] = (),
    *,
    physics: str = "thermal",
    surface: Any = "Laguerre",
    threads: Optional[int] = None,
):
    """The effective conductivity tensor of a periodic packing, by periodic homogenisation.

    - ``packing``: a ``demcon.Packing`` in a ``Periodic`` container (``demcon.pack`` or
      ``Packing.from_arrays``); its ``phase`` array picks each sphere's material;
    - ``materials``: dicts as in a scene's ``materials`` (``{"name": "epoxy", "conductivity":
      0.2}``; W/(m·K), and ``resistivity`` in Ω·m for ``physics="electric"``); ``density``
      and ``specific_heat`` may be left out (a homogenisation is steady);
    - ``phases``: a scene's ``phases`` (inclusions, shapes, regions) laid over the spheres;
    - ``physics``: ``"thermal"`` (W/(m·K)) or ``"electric"`` (S/m);
    - ``surface``: the network's transmission surface (a scene's ``surface``).

    Returns the (3, 3) tensor as a numpy array. Raises ``demcon.SceneError`` naming the field
    (``materials[0].conductivity``) on a bad value.
    """
    if physics not in ("thermal", "electric"):
        raise ValueError(f"physics = {physics!r}: allowed are 'thermal' and 'electric'")
    # a homogenisation is steady: density and specific heat play no part (1.0 fills them in)
    materials = [{"density": 1.0, "specific_heat": 1.0, **m} for m in materials]
    spec: dict = {
        "name": "homogenize",
        "surface": surface,
        "materials": materials,
        "phases": list(phases),
    }
    if physics == "thermal":
        spec["thermal"] = {"bcs": [], "solver": "Homogenize"}
    else:
        spec["electric"] = {"electrodes": [], "homogenize": True}
    result = Scene(spec, packing=packing).run(threads=threads, progress=False)
    return result.etc_tensor if physics == "thermal" else result.electric_tensor
