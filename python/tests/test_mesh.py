"""Meshes in and out: OBJ and PLY round trips, zero-copy views, input validation."""

import gc

import numpy as np
import pytest

import pliant


@pytest.mark.parametrize("extension", [".obj", ".ply"])
def test_mesh_round_trip(tmp_path, extension):
    mesh = pliant.grid_sheet(5, 3, 2.0, 1.0)
    mesh.positions[:, 2] = np.linspace(0.0, 1.0, mesh.num_vertices) ** 2  # not just a plane
    path = tmp_path / f"sheet{extension}"
    pliant.write_mesh(path, mesh)
    back = pliant.read_mesh(str(path))
    assert (back.num_vertices, back.num_triangles) == (24, 30)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_allclose(back.positions, mesh.positions, rtol=0, atol=1e-6)


def test_mesh_arrays_are_views_that_keep_the_mesh_alive():
    mesh = pliant.TriangleMesh(np.zeros((3, 3)), [[0, 1, 2]])
    positions = mesh.positions
    assert positions.shape == (3, 3) and positions.dtype == np.float64
    assert mesh.triangles.dtype == np.int32
    assert np.shares_memory(positions, mesh.positions)  # the mesh's own memory, no copy
    positions[1] = (1.0, 0.0, 0.0)
    assert mesh.positions[1].tolist() == [1.0, 0.0, 0.0]
    del mesh
    gc.collect()
    positions[2] = (0.0, 1.0, 0.0)  # the view keeps the mesh alive
    assert positions.tolist() == [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


def test_mesh_input_is_validated():
    with pytest.raises(pliant.InvalidInput, match="positions: expected an array of shape"):
        pliant.TriangleMesh(np.zeros((3, 2)), [[0, 1, 2]])
    with pytest.raises(ValueError, match="triangles"):  # InvalidInput is a ValueError
        pliant.TriangleMesh(np.zeros((3, 3)), [[0, 1, 3]])
    with pytest.raises(pliant.IoError):
        pliant.read_mesh("no/such/file.obj")
    with pytest.raises(OSError, match="unsupported mesh file extension"):
        pliant.read_mesh("mesh.stl")
