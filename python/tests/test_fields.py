"""The run's other arrays: contacts (with heat flows that balance), probes, profiles, the Halo
flux; progress through tqdm; PyVista."""

import copy

import numpy as np
import pytest

import demcon
from test_dict import HOMOGENEOUS


@pytest.fixture(scope="module")
def result():
    spec = copy.deepcopy(HOMOGENEOUS)
    spec["outputs"].update(
        probes=[{"name": "middle", "point": (0.05, 0.05, 0.05)}],
        profiles=[{"name": "along_y", "from": (0.05, 0.0, 0.05), "to": (0.05, 0.1, 0.05), "points": 11}],
        halo=2.0,
    )
    return demcon.Scene(spec).run()


def test_contacts_carry_the_heat_that_crosses_the_body(result):
    c = result.contacts()
    m = c["pairs"].shape[0]
    assert c["pairs"].shape == (m, 2) and c["pairs"].dtype == np.uint32
    for name in ["distance", "thermal_conductance", "heat_flow"]:
        assert c[name].shape == (m,) and c[name].dtype == np.float64, name
    assert np.all(c["thermal_conductance"] > 0.0) and np.all(c["distance"] > 0.0)
    # every cut between the held faces carries Q = λ A ΔT / L = 33 · 0.01 · 10 / 0.1 = 33 W
    # downwards (from YMax at 35 °C to YMin at 25 °C), exactly for Laguerre cells
    y = result.centres[:, 1]
    p, q = c["pairs"][:, 0], c["pairs"][:, 1]
    for cut in [0.03, 0.05, 0.07]:
        up = (y[p] < cut) & (y[q] >= cut)
        down = (y[p] >= cut) & (y[q] < cut)
        q_up = c["heat_flow"][up].sum() - c["heat_flow"][down].sum()
        assert q_up == pytest.approx(-33.0, rel=1e-7), cut


def test_probes_and_profiles_are_arrays(result):
    probe = result.probes["middle"]
    assert probe["t"].shape == (1,) and probe["solved"].dtype == bool
    assert probe["temperature"].shape == (1,) and 25.0 < probe["temperature"][0] < 35.0
    assert probe["flux_magnitude"][0] == pytest.approx(3300.0, rel=1e-6)
    prof = result.profiles["along_y"]
    assert prof["distance"].shape == (11,) and prof["temperature"].shape == (1, 11)
    assert prof["solved"].shape == (1, 11) and prof["solved"].dtype == bool
    # the linear field T = 25 + 100 y, read at the nearest particle (within a particle size)
    assert np.allclose(prof["temperature"][0], 25.0 + 100.0 * prof["distance"], atol=1.0)


def test_halo_flux(result):
    n = result.radii.shape[0]
    assert result.halo_flux.shape == (n, 3) and result.halo_cut.shape == (n,)
    inner = ~result.halo_cut
    assert inner.sum() > 0
    # a uniform flux stays uniform under the Halo average: q_y = -3300 W/m²
    assert np.allclose(result.halo_flux[inner, 1], -3300.0, rtol=1e-6)


def test_progress_true_uses_tqdm_when_installed(homogeneous, capsys):
    pytest.importorskip("tqdm")
    demcon.Scene.from_file(homogeneous).run(progress=True)
    err = capsys.readouterr().err
    assert "demcon: packing" in err and "demcon: solve" in err


def test_to_pyvista(result):
    try:
        import pyvista
    except ImportError:
        with pytest.raises(ImportError, match="pip install pyvista"):
            result.to_pyvista()
        return
    mesh = result.to_pyvista()
    assert isinstance(mesh, pyvista.PolyData)
    assert mesh.n_points == result.radii.shape[0]
    assert np.array_equal(mesh.point_data["temperature"], result.temperature)
