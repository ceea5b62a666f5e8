"""Volumes from Python: the (nz, ny, nx[, 4]) array convention, zero-copy views, file round
trips, cleaning and transfer functions."""

import gc

import numpy as np
import pytest

import pliant


def test_array_is_z_y_x_so_that_array_k_j_i_is_voxel_i_j_k():
    dims = (10, 8, 6)
    centre = (3.0, 5.0, 2.5)
    v = pliant.uniform_sphere(dims, 2.2, 1.0, spacing=(1.0, 1.0, 1.0), center=centre)
    a = v.array
    assert v.dims == dims and a.shape == (6, 8, 10) and a.dtype == np.float32
    for k in range(dims[2]):
        for j in range(dims[1]):
            for i in range(dims[0]):
                c = np.array(v.voxel_center(i, j, k))
                inside = np.linalg.norm(c - centre) <= 2.2
                assert a[k, j, i] == (1.0 if inside else 0.0), (i, j, k)


def test_raw_bytes_are_x_fastest(tmp_path):
    a = np.arange(2 * 3 * 4, dtype=np.uint16).reshape(2, 3, 4)  # (nz, ny, nx)
    v = pliant.Volume.from_array(a, spacing=(0.5, 1.0, 2.0), origin=(1.0, 2.0, 3.0))
    assert v.dims == (4, 3, 2) and v.type == "u16"
    pliant.write_volume(tmp_path / "v.json", v)
    assert (tmp_path / "v.raw").read_bytes() == a.tobytes()


def test_views_share_the_volume_memory_and_keep_it_alive(tmp_path):
    v = pliant.Volume.zeros((4, 4, 4), "rgba8")
    a = v.array
    assert a.shape == (4, 4, 4, 4) and a.dtype == np.uint8
    a[1, 2, 3] = (10, 20, 30, 40)
    del v
    gc.collect()
    a[0, 0, 0, 3] = 255  # the view keeps the volume alive
    assert a[1, 2, 3].tolist() == [10, 20, 30, 40]


@pytest.mark.parametrize("name", ["v.nrrd", "v.nii.gz", "v.json"])
def test_generated_volumes_round_trip_through_files(tmp_path, name):
    phantom = pliant.shepp_logan((16, 12, 8))
    path = tmp_path / name
    pliant.write_volume(path, phantom)
    back = pliant.read_volume(path)
    assert back.dims == phantom.dims and back.type == "f32"
    assert back.spacing == pytest.approx(phantom.spacing)
    assert back.origin == pytest.approx(phantom.origin)
    np.testing.assert_array_equal(back.array, phantom.array)


def test_rgba_round_trip_and_cleaning(tmp_path):
    arrows = pliant.rgba_test_object((24, 24, 24), "rgba8")
    pliant.write_volume(tmp_path / "arrows.nrrd", arrows, gzip=True)
    back = pliant.read_volume(tmp_path / "arrows.nrrd")
    np.testing.assert_array_equal(back.array, arrows.array)

    alpha = back.array[..., 3]
    faint = np.count_nonzero((alpha > 0) & (alpha < 35))
    assert faint > 0  # the grey sphere (0.1 ~ 26)
    assert pliant.threshold_alpha(back, 35) == faint
    assert np.count_nonzero((back.array[..., 3] > 0) & (back.array[..., 3] < 35)) == 0
    pliant.normalize_alpha(back)
    assert back.array[..., 3].max() == 255


def test_from_array_copies_and_validates():
    a = np.ones((2, 3, 4), dtype=np.float32)
    v = pliant.Volume.from_array(a)
    a[:] = 7
    assert v.array.max() == 1.0  # a copy in
    with pytest.raises(pliant.InvalidInput, match="dtype float64"):
        pliant.Volume.from_array(np.ones((2, 2, 2)))
    with pytest.raises(ValueError, match="expected shape"):
        pliant.Volume.from_array(np.ones((2, 2), dtype=np.float32))


def test_transfer_functions():
    tf = pliant.TransferFunction(color=[(0, 0, 0, 0), (1, 1, 0.5, 0)], opacity=[(0, 0), (1, 0.8)])
    assert tf.evaluate(0.5) == pytest.approx((0.5, 0.25, 0.0, 0.4))
    assert set(pliant.transfer_function_presets()) >= {"ct-bone", "mri-brain"}
    phantom = pliant.shepp_logan((8, 8, 8))
    lo, hi = pliant.value_range(phantom)
    assert lo == 0.0 and hi > 1.0
    grayscale = pliant.preset_transfer_function("grayscale", phantom)
    rgba = pliant.apply_transfer_function(phantom, grayscale)
    assert rgba.type == "rgba32f" and rgba.array.shape == (8, 8, 8, 4)
    with pytest.raises(pliant.InvalidInput, match="opacity"):
        pliant.TransferFunction(color=[(0, 0, 0, 0)], opacity=[(0, 2.0)])
