"""Scenes as dicts: the RON schema's shape, equal to the RON file to the last digit; errors name
the field path."""

import numpy as np
import pytest

import demcon

# homogeneous.ron written as a dict by hand (the schema of docs/python.md "Scenes as dicts")
HOMOGENEOUS = {
    "name": "homogeneous",
    "seed": 3,
    "packing": {
        "Generate": {
            "container": {"Box": {"size": (0.1, 0.1, 0.1)}},
            "count": 2000,
            "phi": 0.6,
            "radius_cov": 0.3,
        }
    },
    "surface": "Laguerre",
    "materials": [{"name": "steel", "conductivity": 33.0, "density": 7800.0, "specific_heat": 500.0}],
    "thermal": {
        "initial_temperature": 25.0,
        "bcs": [
            {"WallTemperature": {"face": "YMin", "value": 25.0}},
            {"WallTemperature": {"face": "YMax", "value": np.float64(35.0)}},
        ],
        "solver": "Steady",
    },
    "outputs": {"etc_axis": "Y", "flux": True, "vtk": False},
}


def test_a_dict_scene_equals_its_ron_file_to_the_last_digit(homogeneous):
    from_file = demcon.Scene.from_file(homogeneous).run(threads=1)
    from_dict = demcon.Scene(HOMOGENEOUS).run(threads=1)
    assert from_dict.etc == from_file.etc
    for name in ["centres", "radii", "temperature", "heat_flux", "volume"]:
        assert np.array_equal(getattr(from_dict, name), getattr(from_file, name)), name


def test_to_dict_round_trips(homogeneous):
    scene = demcon.Scene.from_file(homogeneous)
    d = scene.to_dict()
    assert d["materials"][0]["conductivity"] == 33.0
    assert d["thermal"]["bcs"][1] == {"WallTemperature": {"face": "YMax", "value": 35.0}}
    assert demcon.Scene(d).to_dict() == d


def _with(path, value):
    """HOMOGENEOUS with the entry at `path` (keys and indices) set to `value`."""
    import copy

    d = copy.deepcopy(HOMOGENEOUS)
    node = d
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return d


@pytest.mark.parametrize(
    "path, value, field, says",
    [
        (["thermal", "sollver"], "Steady", "thermal.sollver", "unknown field `sollver`"),
        (["thermal", "bcs", 0, "WallTemperature", "value"], "hot", "thermal.bcs[0].WallTemperature.value",
         "a number or a time table"),
        (["packing", "Generate", "count"], 2.5, "packing.Generate.count", "expected usize"),
        (["seed"], float("nan"), "seed", "finite"),
        (["thermal", "solver"], "Stedy", "thermal.solver", "unknown variant `Stedy`"),
        (["materials", 0, "conductivity"], -1.0, "materials[steel].conductivity", "-1"),
        (["thermal", "bcs", 0, "WallTemperature", "face"], "Top", "thermal.bcs[0].WallTemperature.face",
         "unknown variant `Top`"),
    ],
)
def test_errors_name_the_field_path(path, value, field, says):
    with pytest.raises(demcon.SceneError) as e:
        demcon.Scene(_with(path, value))
    assert field in str(e.value)
    assert says in str(e.value)


def test_values_without_a_place_in_a_scene_are_refused():
    with pytest.raises(TypeError, match=r"seed.*object"):
        demcon.Scene(_with(["seed"], object()))
    with pytest.raises(TypeError, match="a dict in the scene schema"):
        demcon.Scene("(packing: ...)")
    with pytest.raises(demcon.SceneError, match="not a string"):
        demcon.Scene({1: 2})
    with pytest.raises(demcon.SceneError, match="missing field `packing`"):
        demcon.Scene({k: v for k, v in HOMOGENEOUS.items() if k != "packing"})


def test_a_scene_file_cannot_claim_given_particles():
    d = _with(["packing"], {"Given": {"count": 10, "container": {"Box": {"size": (1.0, 1.0, 1.0)}}}})
    with pytest.raises(demcon.SceneError, match="handed over in memory"):
        demcon.Scene(d)
