"""The error hierarchy: library errors become pliant.Error subclasses that are also the matching
built-in exceptions, with the library's message."""

import pytest

import pliant


def test_hierarchy():
    assert issubclass(pliant.InvalidInput, pliant.Error)
    assert issubclass(pliant.InvalidInput, ValueError)
    assert issubclass(pliant.IoError, OSError)
    assert issubclass(pliant.Unsupported, NotImplementedError)
    assert issubclass(pliant.InternalError, RuntimeError)
    assert issubclass(pliant.Interrupted, KeyboardInterrupt)


def test_messages_pass_through():
    with pytest.raises(pliant.InvalidInput, match="width"):
        pliant.Camera.perspective((0, 0, 1), (0, 0, 0), (0, 1, 0), 40.0, 0, 10)
    with pytest.raises(pliant.Unsupported, match="inv3"):
        pliant.write_volume("x.inv3", pliant.Volume.zeros((2, 2, 2)))
    with pytest.raises(pliant.IoError, match="nope.nrrd"):
        pliant.read_volume("nope.nrrd")


def test_log_handler_receives_library_messages():
    messages = []
    pliant.set_log_handler(lambda level, text: messages.append((level, text)))
    try:
        # Two sheets crossing: the start intersects itself, which the library reports.
        scene = {
            "cloth": {
                "grid": {"size": [0.2, 0.2], "quads": [4, 4]},
                "instances": [{"translate": [0, 0, 0.5]},
                              {"rotate_degrees": [30, 0, 0], "translate": [0, 0, 0.5]}],
            },
            "frames": 1,
            "substeps": 2,
        }
        pliant.ClothSimulation(pliant.parse_cloth_scene(scene), "crossing")
    finally:
        pliant.set_log_handler(None)
    assert any("crossing" in text for _, text in messages), messages
