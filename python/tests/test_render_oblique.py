"""The ray caster on an oblique volume from Python, as tests/render/raycast_oblique_test.cpp: a
grid turned in the world renders as it lies (no resampling), against the analytic image of an
off-centre sphere, against its exact resampling for a quarter turn, and through a NIfTI file read
with orientation='keep'."""

import math

import numpy as np
import pytest

import pliant


def rotation(axis, degrees):
    """The rotation by `degrees` about `axis` (Rodrigues) as a direction: its three columns."""
    x, y, z = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    a = math.radians(degrees)
    c, s, t = math.cos(a), math.sin(a), 1.0 - math.cos(a)
    r = np.array(
        [
            [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
            [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
            [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
        ]
    )
    return tuple(tuple(r[:, col]) for col in range(3))


def test_direction_and_world_bounds():
    v = pliant.Volume.zeros((8, 6, 4))
    assert v.is_axis_aligned
    assert v.direction == ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    assert v.world_bounds == v.bounds
    v.direction = rotation((0, 0, 1), 30.0)
    assert not v.is_axis_aligned
    lo, hi = v.world_bounds
    # The 8 x 6 box turned 30 deg about z: x from -6 sin 30 to 8 cos 30.
    assert lo[0] == pytest.approx(-6.0 * 0.5)
    assert hi[0] == pytest.approx(8.0 * math.cos(math.radians(30.0)))
    with pytest.raises(pliant.InvalidInput):
        v.direction = ((1.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))


def test_off_centre_sphere_in_a_turned_grid_matches_the_analytic_image():
    radius, rgba, unit = 14.0, (0.8, 0.6, 0.4, 0.5), 40.0
    centre_grid = np.array([40.0, 22.0, 30.0])
    ball = pliant.uniform_sphere(
        (64, 64, 64), radius, rgba, center=tuple(centre_grid), supersample=4
    )
    ball.direction = rotation((1, 2, 3), 20.0)
    ball.origin = (3.0, -5.0, 7.0)
    d = np.array(ball.direction).T  # columns: the grid's axes in the world
    centre = np.array(ball.origin) + d @ centre_grid
    box = (tuple(centre - (24.0, 24.0, 40.0)), tuple(centre + (24.0, 24.0, 40.0)))
    camera = pliant.Camera.along_axis(box, "+z", 48, 48)  # right = -x, up = +y
    got = pliant.raycast(ball, camera, opacity_unit=unit, early_termination=1.0) / 255.0
    x = 24.0 - (np.arange(48) + 0.5)
    r = np.sqrt(x[None, :] ** 2 + x[:, None] ** 2)
    chord = np.where(r < radius, 2.0 * np.sqrt(np.maximum(radius**2 - r**2, 0.0)), 0.0)
    a = 1.0 - (1.0 - rgba[3]) ** (chord / unit)
    expected = np.stack([c * a for c in rgba[:3]], axis=-1)
    away = np.abs(r - radius) >= 1.5  # the silhouette is voxelization, not the transform
    assert np.abs(got - expected)[away].max() <= 1.2e-2


def test_quarter_turn_renders_as_its_exact_resampling():
    v = pliant.rgba_test_object((33, 29, 31), "rgba8")
    v.direction = ((0.0, 1.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    sx, sy, sz = v.spacing
    reference = pliant.resample_to_axis_aligned(v, spacing=(sy, sx, sz))
    assert reference.is_axis_aligned and reference.dims == (29, 33, 31)
    camera = pliant.Camera.framing(v.world_bounds, 30.0, 20.0, 64, 56)
    a = pliant.raycast(v, camera).astype(int)
    b = pliant.raycast(reference, camera).astype(int)
    assert np.abs(a - b).max() <= 1


def test_tilted_nifti_read_with_its_direction(tmp_path):
    v = pliant.shepp_logan((32, 28, 24))
    v.direction = rotation((0, 1, 0), 5.0)
    path = tmp_path / "tilted.nii.gz"
    pliant.write_volume(path, v)
    kept = pliant.read_volume(path, orientation="keep")
    assert not kept.is_axis_aligned
    assert np.allclose(np.array(kept.direction), np.array(v.direction), atol=1e-6)
    resampled = pliant.read_volume(path)  # the default: resampled onto an axis-aligned grid
    assert resampled.is_axis_aligned
    tf = pliant.preset_transfer_function("mri-brain", kept)
    camera = pliant.Camera.orbit(kept.world_bounds, 30.0, 20.0, 90.0, 64, 56)
    native = pliant.raycast(kept, camera, tf).astype(float)
    blurred = pliant.raycast(resampled, camera, tf).astype(float)
    mse = np.mean((native - blurred) ** 2)
    assert 10.0 * math.log10(255.0**2 / mse) >= 30.0
    with pytest.raises(pliant.InvalidInput):
        pliant.read_volume(path, orientation="sideways")
