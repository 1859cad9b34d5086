"""Bad input raises a Python exception naming the field or argument."""

import pytest

import demcon


def test_scene_error_is_a_value_error_with_the_field_path(homogeneous):
    text = homogeneous.read_text().replace("conductivity: 33.0", "conductivity: -1.0")
    with pytest.raises(demcon.SceneError) as e:
        demcon.Scene.from_str(text)
    assert isinstance(e.value, ValueError)
    assert "materials[steel].conductivity" in str(e.value)
    assert "-1" in str(e.value)


def test_parse_error_names_line_and_column():
    with pytest.raises(demcon.SceneError, match=r"<string>:\d+:\d+"):
        demcon.Scene.from_str("(packing: ")


def test_missing_file_names_the_path(tmp_path):
    path = tmp_path / "nope.ron"
    with pytest.raises(FileNotFoundError, match="nope.ron"):
        demcon.Scene.from_file(path)


def test_bad_run_arguments(homogeneous):
    scene = demcon.Scene.from_file(homogeneous)
    with pytest.raises(ValueError, match="threads = 0"):
        scene.run(threads=0)
    with pytest.raises(ValueError, match="progress = 'yes'"):
        scene.run(progress="yes")
    with pytest.raises(TypeError):
        scene.run(threads="two")
