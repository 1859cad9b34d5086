"""Runs through Python: homogeneous exactness, arrays (shapes, dtypes, units), text = file."""

import json

import numpy as np
import pytest

import demcon


@pytest.fixture(scope="module")
def result():
    from conftest import DATA

    return demcon.Scene.from_file(DATA / "homogeneous.ron").run()


def test_homogeneous_etc_is_the_material_conductivity(result):
    # Laguerre cells solve a linear field exactly: λ_e = λ = 33 W/(m·K) to the solver's residual.
    assert result.etc == pytest.approx(33.0, rel=1e-8)
    assert result.summary["etc"]["lambda_e"] == result.etc


def test_arrays_have_shapes_dtypes_and_units(result):
    n = result.summary["model"]["n_particles"]
    assert n > 1000
    for name in ["radii", "volume", "temperature"]:
        a = getattr(result, name)
        assert a.shape == (n,) and a.dtype == np.float64, name
    for name in ["centres", "heat_flux"]:
        a = getattr(result, name)
        assert a.shape == (n, 3) and a.dtype == np.float64, name
    assert result.phase.shape == (n,) and result.phase.dtype == np.uint16
    # metres: the cube is 0.1 m; temperatures between the held faces (°C as in the scene)
    assert np.all((result.centres >= 0.0) & (result.centres <= 0.1))
    assert np.all((result.radii > 0.0) & (result.radii < 0.01))
    assert result.temperature.min() >= 25.0 - 1e-9 and result.temperature.max() <= 35.0 + 1e-9
    # Σ volumes = the box's (Laguerre cells fill it), in m³
    assert result.volume.sum() == pytest.approx(1e-3, rel=1e-6)
    # heat flows from YMax to YMin: q_y = -λ ΔT/L = -3300 W/m² on average
    q = (result.heat_flux[:, 1] * result.volume).sum() / result.volume.sum()
    assert q == pytest.approx(-33.0 * 10.0 / 0.1, rel=1e-6)
    # no electric physics, no periodic homogenisation
    assert result.potential is None and result.current_density is None
    assert result.joule_power is None and result.etc_tensor is None


def test_summary_is_summary_json(result):
    assert isinstance(result.summary, dict)
    assert json.loads(json.dumps(result.summary)) == result.summary


def test_from_str_equals_from_file_to_the_last_digit(homogeneous, result):
    other = demcon.Scene.from_str(homogeneous.read_text()).run(threads=1)
    assert other.etc == result.etc
    for name in ["centres", "radii", "temperature", "heat_flux", "volume"]:
        assert np.array_equal(getattr(other, name), getattr(result, name)), name


def test_out_writes_the_cli_outputs(homogeneous, tmp_path):
    out = tmp_path / "run"
    r = demcon.Scene.from_file(homogeneous).run(out=out)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["etc"]["lambda_e"] == r.etc
