"""Deformable volumes from Python: the soft body on a tet grid over a tiny volume, drivers,
resampling, the guard of reset_body, `pliant deform` as run_deform."""

import gc

import numpy as np
import pytest

import pliant


@pytest.fixture(scope="module")
def ball():
    # A 16^3 RGBA sphere: what a cleaned radiance field gives the rest of the pipeline.
    return pliant.uniform_sphere((16, 16, 16), 6.0, (1.0, 0.5, 0.2, 0.8), supersample=2)


def test_resampling_at_rest_reproduces_the_source(ball):
    dv = pliant.DeformableVolume(ball, cell_voxels=2)
    rest = dv.resample()
    assert rest.dims == ball.dims and rest.type == ball.type
    np.testing.assert_array_equal(rest.array, ball.array)
    # The one-off resampler over the same mesh gives the same voxels.
    grid = pliant.build_tet_grid(ball, cell_voxels=2)
    target = pliant.Volume.zeros(ball.dims, ball.type)
    stats = pliant.resample(ball, grid.mesh, grid.mesh.positions, target)
    assert stats.num_tets == grid.mesh.num_tets
    np.testing.assert_array_equal(target.array, ball.array)


def test_twist_deforms_and_keeps_volume(ball):
    dv = pliant.DeformableVolume(ball, cell_voxels=2, stiffness=0.8, substeps=5)
    body = dv.body
    rest = body.rest_positions.copy()
    assert rest.shape == (dv.rest.num_vertices, 3) and rest.dtype == np.float32
    body.add_driver(pliant.TwistDriver(axis="z", angle=60.0, ramp_time=0.1))
    for _ in range(4):
        body.step(1.0 / 24.0)
    assert body.time == pytest.approx(4 / 24)
    moved = np.linalg.norm(body.positions - rest, axis=1)
    assert moved.max() > 0.5  # voxels
    stats = body.stats()
    assert stats.volume_ratio == pytest.approx(1.0, abs=0.05)
    assert stats.inverted_tets == 0
    deformed, rs = dv.resample(return_stats=True)
    assert rs.num_voxels_written > 0
    assert not np.array_equal(deformed.array, ball.array)
    assert deformed.array[..., 3].max() > 0


def test_reset_body_refuses_while_the_body_is_referenced(ball):
    dv = pliant.DeformableVolume(ball, cell_voxels=4)
    body = dv.body
    body.add_driver(pliant.WaveDriver(amplitude=0.05))
    body.step(0.1)
    positions = body.positions
    del body
    with pytest.raises(pliant.InvalidInput, match="still alive"):
        dv.reset_body()  # `positions` still points into the body
    del positions
    gc.collect()
    dv.reset_body()
    assert dv.body.time == 0.0
    np.testing.assert_array_equal(dv.body.positions, dv.body.rest_positions)


def test_soft_body_on_its_own(ball):
    grid = pliant.build_tet_grid(ball, cell_voxels=4)
    body = pliant.SoftBody(grid, gravity=(0.0, 0.0, -9.81))
    bottom = np.nonzero(body.rest_positions[:, 2] <= body.rest_positions[:, 2].min())[0]
    body.pin(bottom)
    assert np.all(body.inv_masses[bottom] == 0)
    body.step(0.05)
    assert body.positions[bottom].tolist() == body.rest_positions[bottom].tolist()
    assert body.positions[:, 2].mean() < body.rest_positions[:, 2].mean()
    with pytest.raises(TypeError, match="unknown option"):
        pliant.SoftBody(grid, stifness=0.5)
    with pytest.raises(pliant.InvalidInput, match="stiffness"):
        pliant.SoftBody(grid, stiffness=2.0)


def test_run_deform(ball, tmp_path):
    result = pliant.run_deform(ball, tmp_path / "twisted.nrrd", driver=pliant.TwistDriver(),
                               frames=3, cell_voxels=4, still=tmp_path / "last.png",
                               size=(32, 32))
    assert result["frames"] == 3 and result["inverted_tets"] == 0
    assert result["thin_levels"] == 2
    assert pliant.read_volume(tmp_path / "twisted.nrrd").dims == ball.dims
    assert pliant.read_png(tmp_path / "last.png").shape == (32, 32, 3)
    fixed = pliant.run_deform(ball, tmp_path / "fixed.nrrd", driver=pliant.TwistDriver(),
                              frames=1, cell_voxels=4, thin_levels=0)
    assert fixed["thin_levels"] == 0
    with pytest.raises(pliant.InvalidInput, match="thin_levels"):
        pliant.run_deform(ball, tmp_path / "bad.nrrd", driver=pliant.TwistDriver(), frames=1,
                          thin_levels=3)
    assert not (tmp_path / "bad.nrrd").exists()
