"""The cloth pipeline from Python: a small scene loaded from JSON and stepped; positions as views
of the solver's memory; reset and its guard; `pliant cloth` as run_cloth."""

import gc
import json

import numpy as np
import pytest

import pliant

# A 0.5 m sheet of 12 x 12 quads falling onto a sphere: 169 vertices, 288 triangles.
SCENE = {
    "cloth": {"grid": {"size": [0.5, 0.5], "quads": [12, 12]}, "translate": [0.0, 0.0, 0.25]},
    "material": {"thickness": 0.004},
    "obstacles": [{"sphere": {"center": [0.0, 0.0, 0.0], "radius": 0.15}}],
    "fps": 24,
    "frames": 4,
    "substeps": 10,
}


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "small.json"
    path.write_text(json.dumps(SCENE))
    return path


def test_small_scene_steps_without_intersections(scene_file):
    sim = pliant.ClothSimulation.from_file(scene_file)
    assert sim.scene.frames == 4 and sim.scene.substeps == 10
    start = sim.positions.copy()
    assert start.shape == (169, 3) and start.dtype == np.float64
    assert sim.triangles.shape == (288, 3) and sim.triangles.dtype == np.int32
    for frame in range(1, sim.scene.frames + 1):
        stats = sim.step()
        assert stats.ms > 0.0
        assert sim.frame == frame
        assert sim.check().intersecting_pairs == 0
        assert sim.check().obstacle_intersections == 0
    assert sim.time == pytest.approx(4 / 24)
    assert np.all(sim.positions[:, 2] < start[:, 2])  # it fell
    distance = np.linalg.norm(sim.positions, axis=1)  # from the sphere's centre
    assert distance.min() > 0.15 and distance.min() < 0.16  # on the sphere, not through it


def test_positions_are_a_read_only_view_that_follows_the_simulation(scene_file):
    sim = pliant.ClothSimulation(pliant.read_cloth_scene(scene_file), "small")
    x = sim.positions
    assert not x.flags.writeable
    with pytest.raises(ValueError):
        x[0, 0] = 1.0
    before = x.copy()
    sim.step()
    assert not np.array_equal(x, before)  # the same memory, now the next frame
    np.testing.assert_array_equal(x, sim.positions)


def test_reset_refuses_while_views_are_alive_then_restarts(scene_file):
    sim = pliant.ClothSimulation.from_file(scene_file)
    start = sim.positions.copy()
    sim.step()
    sim.step()
    view = sim.positions[::2]  # a slice keeps the guard alive too
    with pytest.raises(pliant.InvalidInput, match="still alive"):
        sim.reset()
    del view
    gc.collect()
    sim.reset()
    assert sim.frame == 0
    np.testing.assert_array_equal(sim.positions, start)


def test_a_scene_built_from_a_dict_simulates_like_the_file(scene_file):
    from_file = pliant.ClothSimulation.from_file(scene_file)
    built = pliant.parse_cloth_scene(SCENE, name="built")
    built.frames = 2
    assert built.gravity == (0.0, 0.0, -9.81)
    from_dict = pliant.ClothSimulation(built, "built")
    for _ in range(2):
        from_file.step()
        from_dict.step()
    np.testing.assert_array_equal(from_file.positions, from_dict.positions)  # deterministic


def test_bad_scenes_raise_with_the_key_path():
    with pytest.raises(pliant.IoError, match="material.thickness"):
        pliant.parse_cloth_scene({"cloth": {"grid": {}}, "material": {"thickness": "thick"}})
    with pytest.raises(OSError):
        pliant.read_cloth_scene("no/such/scene.json")


def test_run_cloth_writes_frames_and_stats(scene_file, tmp_path):
    calls = []
    stats = pliant.run_cloth(pliant.read_cloth_scene(scene_file), tmp_path / "out", frames=2,
                             preview=False, progress=lambda done, total, ms: calls.append(done))
    assert calls == [1, 2]
    assert stats["max_intersecting_pairs"] == 0 and stats["interrupted"] is False
    assert json.loads((tmp_path / "out" / "stats.json").read_text()) == stats
    assert len(list((tmp_path / "out" / "frames").iterdir())) == 3  # frames 0, 1, 2
