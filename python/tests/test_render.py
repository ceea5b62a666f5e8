"""The ray caster from Python: a uniform sphere against its analytic image (as
tests/render/raycast_test.cpp), images as numpy arrays, PNG files."""

import numpy as np
import pytest

import pliant

# The C++ test's scene: radius R in a 64^3 box (spacing 1), colour c, opacity a per unit U.
R, N, RGBA, U = 28.0, 64, (0.8, 0.6, 0.4, 0.5), 80.0


@pytest.fixture(scope="module")
def ball():
    return pliant.uniform_sphere((N, N, N), R, RGBA, supersample=1)


def analytic_image(width, height):
    """c (1 - (1 - a)^(L/U)) along the chord L of each pixel's ray (view along +z: right = -x,
    up = +y)."""
    i = np.arange(width) + 0.5
    j = np.arange(height) + 0.5
    x = N * (1.0 - i / width) - 0.5 * N
    y = N * (1.0 - j / height) - 0.5 * N
    r2 = x[None, :] ** 2 + y[:, None] ** 2
    chord = np.where(r2 < R * R, 2.0 * np.sqrt(np.maximum(R * R - r2, 0.0)), 0.0)
    a = 1.0 - (1.0 - RGBA[3]) ** (chord / U)
    return np.stack([c * a for c in RGBA[:3]], axis=-1)


def test_sphere_matches_the_analytic_image(ball):
    camera = pliant.Camera.along_axis(ball.bounds, "+z", N, N)
    image = pliant.raycast(ball, camera, opacity_unit=U, early_termination=1.0)
    assert image.shape == (N, N, 3) and image.dtype == np.uint8
    got = image / 255.0
    # The centre pixel sees the whole diameter.
    centre = RGBA[0] * (1.0 - (1.0 - RGBA[3]) ** (2.0 * R / U))
    assert got[N // 2, N // 2, 0] == pytest.approx(centre, abs=5e-3)
    assert np.abs(got - analytic_image(N, N)).max() <= 1e-2


def test_ray_caster_renders_again_with_stats(ball, tmp_path):
    caster = pliant.RayCaster(ball, opacity_unit=U, early_termination=1.0)
    camera = pliant.Camera.along_axis(ball.bounds, "+z", N, N)
    image, stats = caster.render(camera, return_stats=True)
    assert stats.samples > 0
    np.testing.assert_array_equal(
        image, pliant.raycast(ball, camera, opacity_unit=U, early_termination=1.0))
    no_skipping = pliant.raycast(ball, camera, opacity_unit=U, early_termination=1.0,
                                 empty_space_skipping=False)
    np.testing.assert_array_equal(image, no_skipping)

    pliant.write_png(tmp_path / "ball.png", image)
    np.testing.assert_array_equal(pliant.read_png(tmp_path / "ball.png"), image)

    orbit = caster.render(pliant.Camera.framing(ball.bounds, 30, 20, 48, 32))
    assert orbit.shape == (32, 48, 3) and orbit.max() > 0


def test_scalar_volumes_need_a_transfer_function():
    phantom = pliant.shepp_logan((16, 16, 16))
    camera = pliant.Camera.framing(phantom.bounds, 0, 0, 16, 16)
    with pytest.raises(pliant.InvalidInput):
        pliant.raycast(phantom, camera)
    tf = pliant.preset_transfer_function("mri-brain", phantom)
    assert pliant.raycast(phantom, camera, tf, mode="mip").max() > 0
    with pytest.raises(TypeError, match="unknown option 'stepp'"):
        pliant.raycast(phantom, camera, tf, stepp=0.1)
