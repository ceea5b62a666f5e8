"""Radiance fields from Python: a tiny dataset rendered from a phantom, read back, a few training
iterations exported as an RGBA volume, evaluation; datasets built from numpy arrays."""

import numpy as np
import pytest

import pliant


@pytest.fixture(scope="module")
def dataset_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("nerf") / "ds"
    phantom = pliant.shepp_logan((16, 16, 16))
    tf = pliant.preset_transfer_function("mri-brain", phantom)
    result = pliant.render_dataset(phantom, out, tf, views=12, size=(16, 16), test_every=4)
    assert (result["train"], result["test"]) == (9, 3)
    return out


def test_dataset_reads_back_with_image_views(dataset_dir):
    train = pliant.read_nerf_dataset(dataset_dir / "transforms_train.json")
    assert len(train) == 9 and train.intrinsics.width == 16
    image = train.image(0)
    assert image.shape == (16, 16, 3) and image.dtype == np.float32
    assert np.shares_memory(image, train.image(0))  # the dataset's own pixels
    assert 0.0 <= image.min() and image.max() <= 1.0 and image.max() > 0.0
    pose = train.pose(0)
    assert pose.shape == (3, 4)
    np.testing.assert_allclose(pose[:, :3].T @ pose[:, :3], np.eye(3), atol=1e-9)
    assert train.box == ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    assert train.camera(0).width == 16


def test_a_few_training_iterations_export_a_volume(dataset_dir):
    train = pliant.read_nerf_dataset(dataset_dir / "transforms_train.json")
    progress = []
    volume, stats = pliant.train_volume(
        train, iterations=20, resolution=8, batch_rays=256, export_resolution=12,
        progress=lambda p: progress.append(p.iteration))
    assert progress == list(range(1, 21))
    assert stats["iterations"] == 20 and stats["interrupted"] is False
    assert volume.type == "rgba8" and volume.dims == (12, 12, 12)
    test = pliant.read_nerf_dataset(dataset_dir / "transforms_test.json")
    scores = pliant.evaluate_volume(test, volume)
    assert len(scores["views"]) == 3 and np.isfinite(scores["psnr"])


def test_a_dataset_built_from_arrays_trains_like_the_file(dataset_dir):
    read = pliant.read_nerf_dataset(dataset_dir / "transforms_train.json")
    poses = np.stack([read.pose(i) for i in range(len(read))])
    images = np.stack([read.image(i) for i in range(len(read))])
    built = pliant.Dataset(read.intrinsics, poses, images, box=read.box)
    assert len(built) == 9 and built.name(0) == "view_0"
    np.testing.assert_array_equal(built.image(3), read.image(3))
    options = dict(iterations=5, resolution=8, batch_rays=128, export_resolution=8)
    a, _ = pliant.train_volume(read, **options)
    b, _ = pliant.train_volume(built, **options)
    np.testing.assert_array_equal(a.array, b.array)
    with pytest.raises(pliant.InvalidInput, match="images"):
        pliant.Dataset(read.intrinsics, poses, images[:, :8])
    assert pliant.psnr(images[0], images[0]) == float("inf")
