"""Packings as numpy arrays: generated, handed over, saved and read; homogenize; bad arrays."""

import numpy as np
import pytest

import demcon

CELL = {"Periodic": {"size": (1e-3, 1e-3, 1e-3)}}


@pytest.fixture(scope="module")
def packing():
    return demcon.pack(CELL, count=1500, phi=0.6, radius_cov=0.3, seed=5)


def test_pack_gives_arrays_and_a_report(packing):
    assert len(packing) == 1500
    assert packing.centres.shape == (1500, 3) and packing.centres.dtype == np.float64
    assert packing.radii.shape == (1500,) and packing.phase.dtype == np.uint16
    assert packing.phi == pytest.approx(0.6, abs=1e-9)
    info = packing.info()
    assert info["stop"] == "TargetReached" and info["n"] == 1500
    assert packing.container == {"Periodic": {"size": [1e-3, 1e-3, 1e-3]}}
    # the same seed, the same packing
    again = demcon.pack(CELL, count=1500, phi=0.6, radius_cov=0.3, seed=5)
    assert np.array_equal(again.centres, packing.centres)


def test_homogenize_a_homogeneous_packing_is_exact(packing):
    # Laguerre cells carry a uniform gradient exactly: λ_eff = λ I to the solver's residual.
    t = demcon.homogenize(packing, [{"name": "steel", "conductivity": 33.0}])
    assert t.shape == (3, 3)
    assert np.allclose(t, 33.0 * np.eye(3), rtol=0, atol=33.0 * 1e-8)


def test_phases_from_arrays_bound_the_tensor(packing):
    # two slabs across x: between the harmonic (series) and arithmetic (parallel) bounds
    phase = (packing.centres[:, 0] > 5e-4).astype(np.int64)
    p = demcon.Packing.from_arrays(packing.centres, packing.radii, packing.container, phase=phase)
    t = demcon.homogenize(p, [{"name": "a", "conductivity": 1.0}, {"name": "b", "conductivity": 10.0}])
    series, parallel = 1.0 / (0.5 / 1.0 + 0.5 / 10.0), 5.5
    assert series * 0.97 < t[0, 0] < series * 1.1
    assert parallel * 0.9 < t[1, 1] < parallel * 1.001
    assert t[0, 0] < t[1, 1]


def test_a_scene_on_a_packing_equals_its_file(packing, tmp_path):
    path = tmp_path / "cell.xyzr"
    packing.save(path)
    loaded = demcon.Packing.load(path)
    assert np.array_equal(loaded.centres, packing.centres) and np.array_equal(loaded.radii, packing.radii)
    spec = {
        "materials": [{"name": "a", "conductivity": 2.0, "density": 1.0, "specific_heat": 1.0}],
        "thermal": {"bcs": [], "solver": "Homogenize"},
    }
    in_memory = demcon.Scene(spec, packing=packing).run(threads=1)
    from_file = demcon.Scene({**spec, "packing": {"File": {"path": str(path)}}}).run(threads=1)
    assert np.array_equal(in_memory.etc_tensor, from_file.etc_tensor)


def test_phases_survive_save_and_load(packing, tmp_path):
    phase = np.arange(len(packing)) % 2
    p = demcon.Packing.from_arrays(packing.centres, packing.radii, packing.container, phase=phase)
    p.save(tmp_path / "two.xyzr")
    assert np.array_equal(demcon.Packing.load(tmp_path / "two.xyzr").phase, phase)


def test_bad_arrays_name_the_argument(packing):
    c, r, box = packing.centres, packing.radii, packing.container
    with pytest.raises(ValueError, match=r"centres: shape \[1500, 2\]"):
        demcon.Packing.from_arrays(c[:, :2], r, box)
    with pytest.raises(TypeError, match="centres: dtype int64"):
        demcon.Packing.from_arrays(c.astype(np.int64), r, box)
    with pytest.raises(TypeError, match="radii: a \\(N,\\) numpy array"):
        demcon.Packing.from_arrays(c, list(r), box)
    with pytest.raises(ValueError, match="one radius per centre"):
        demcon.Packing.from_arrays(c, r[:-1], box)
    nan = c.copy()
    nan[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"centres\[3\].*must be finite"):
        demcon.Packing.from_arrays(nan, r, box)
    with pytest.raises(ValueError, match=r"radii\[0\].*> 0"):
        demcon.Packing.from_arrays(c, -r, box)
    with pytest.raises(ValueError, match="outside the box"):
        demcon.Packing.from_arrays(c, r, {"Box": {"size": (1e-4, 1e-4, 1e-4)}})
    with pytest.raises(ValueError, match="unknown variant `Boxx`"):
        demcon.Packing.from_arrays(c, r, {"Boxx": {"size": (1.0, 1.0, 1.0)}})
    with pytest.raises(ValueError, match=r"phase: shape \[3\]"):
        demcon.Packing.from_arrays(c, r, box, phase=np.zeros(3, dtype=int))
    with pytest.raises(demcon.SceneError, match=r"phase\[0\]` = 4.*materials"):
        bad = demcon.Packing.from_arrays(c, r, box, phase=np.full(len(r), 4))
        demcon.homogenize(bad, [{"name": "a", "conductivity": 1.0}])


def test_bad_pack_arguments():
    with pytest.raises(demcon.SceneError, match="invalid phi = 0.9"):
        demcon.pack(CELL, count=100, phi=0.9)
    with pytest.raises(ValueError, match="radius_cov = -0.1"):
        demcon.pack(CELL, count=100, phi=0.5, radius_cov=-0.1)
    with pytest.raises(FileNotFoundError, match="nope.xyzr"):
        demcon.Packing.load("nope.xyzr")
    with pytest.raises(ValueError, match="physics = 'heat'"):
        demcon.homogenize(demcon.pack(CELL, count=50, phi=0.5), [], physics="heat")


def test_homogenize_takes_phases_as_an_array_and_materials_by_name(packing):
    phase = (packing.centres[:, 0] > 5e-4).astype(np.int64)
    p = demcon.Packing.from_arrays(packing.centres, packing.radii, packing.container, phase=phase)
    as_lists = demcon.homogenize(p, [{"name": "a", "conductivity": 1.0}, {"name": "b", "conductivity": 10.0}])
    by_name = demcon.homogenize(packing, {"a": 1.0, "b": 10.0}, phase)
    assert np.array_equal(as_lists, by_name)
    by_mask = demcon.homogenize(packing, {"a": 1.0, "b": 10.0}, phase > 0)  # bools: 0 and 1
    assert np.array_equal(as_lists, by_mask)
    with pytest.raises(TypeError, match=r"materials\['a'\] = 'x'"):
        demcon.homogenize(packing, {"a": "x"})
    with pytest.raises(ValueError, match=r"phase: shape \[2\]"):
        demcon.homogenize(packing, {"a": 1.0}, np.array([0, 0]))


def test_electric_homogenization_of_a_homogeneous_packing_is_exact(packing):
    # σ = 1/ρ = 100 S/m in every direction
    t = demcon.homogenize(packing, [{"name": "carbon", "conductivity": 1.0, "resistivity": 0.01}], physics="electric")
    assert np.allclose(t, 100.0 * np.eye(3), rtol=0, atol=100.0 * 1e-8)
