"""``RunResult.to_pyvista()``: the particles as a PyVista point cloud with their fields."""


def to_pyvista(result):
    """The particle centres as a ``pyvista.PolyData``, with ``radius``, ``phase``, ``volume``
    and every field the run computed (temperature, heat_flux, halo_flux, potential,
    current_density, joule_power) as point data. Glyph the points with spheres scaled by
    ``radius`` to see the particles (``mesh.glyph(scale="radius", geom=pyvista.Sphere(radius=1))``)."""
    try:
        import pyvista
    except ImportError as e:
        raise ImportError(
            "RunResult.to_pyvista needs PyVista: pip install pyvista "
            "(or open the run's particles.vtu, written with outputs vtk: true, in ParaView)"
        ) from e
    mesh = pyvista.PolyData(result.centres)
    fields = {
        "radius": result.radii,
        "phase": result.phase,
        "volume": result.volume,
        "temperature": result.temperature,
        "heat_flux": result.heat_flux,
        "halo_flux": result.halo_flux,
        "potential": result.potential,
        "current_density": result.current_density,
        "joule_power": result.joule_power,
    }
    for name, values in fields.items():
        if values is not None:
            mesh.point_data[name] = values
    return mesh
