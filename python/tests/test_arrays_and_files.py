"""Arrays handed to meso render exactly as the files they stand for."""

import json

import numpy as np
import pytest

import meso
from conftest import asymmetric_heights, plane_scene, run_program, write_png


def assert_same_image(a, b):
    assert np.array_equal(a.rgb, b.rgb)
    assert np.array_equal(a.coverage, b.coverage)
    assert np.array_equal(a.depth, b.depth)


@pytest.mark.parametrize("technique", ["relief", "parallax", "tessellation", "reference"])
def test_numpy_height_map_renders_as_its_16bit_png(tmp_path, cones, technique):
    write_png(tmp_path / "cones.png", cones)
    (tmp_path / "scene.json").write_text(json.dumps(plane_scene("cones.png", technique)))
    from_file = meso.Scene.load(tmp_path / "scene.json").render()
    from_array = meso.Scene.from_dict(plane_scene(meso.HeightField(cones), technique)).render()
    assert from_file.coverage.sum() > 1000  # the plane fills most of the frame
    assert_same_image(from_file, from_array)


def test_a_height_fields_wrap_reaches_the_scene(cones):
    clamped = meso.Scene.from_dict(plane_scene(meso.HeightField(cones, wrap="clamp")))
    assert clamped.objects[0].mesostructure["wrap"] == "clamp"
    assert np.array_equal(clamped.objects[0].height_field,
                          cones.astype(np.float32) * (np.float32(1) / np.float32(65535)))
    repeated = meso.Scene.from_dict(plane_scene(meso.HeightField(cones)))
    assert repeated.objects[0].mesostructure["wrap"] == "repeat"
    assert not np.array_equal(clamped.render("relief").rgb, repeated.render("relief").rgb)


def test_uint8_and_float_arrays_read_as_png_values(tmp_path):
    grey8 = (asymmetric_heights() >> 8).astype(np.uint8)
    write_png(tmp_path / "grey8.png", grey8)
    (tmp_path / "scene.json").write_text(json.dumps(plane_scene("grey8.png")))
    from_file = meso.Scene.load(tmp_path / "scene.json").render()
    values = meso.HeightField(grey8).values
    assert np.array_equal(values, meso.load_image(tmp_path / "grey8.png"))
    # the float values the uint8 samples load as, given as floats, give the same picture
    from_float = meso.Scene.from_dict(plane_scene(meso.HeightField(values))).render()
    assert_same_image(from_file, from_float)


def test_color_map_array_renders_as_its_png(tmp_path, cones):
    rng = np.random.default_rng(3)
    colours = rng.integers(0, 256, size=(16, 24, 3), dtype=np.uint8)
    write_png(tmp_path / "colours.png", colours)
    write_png(tmp_path / "cones.png", cones)
    scene = plane_scene("cones.png")
    scene["objects"][0]["material"]["color_map"] = "colours.png"
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    from_file = meso.Scene.load(tmp_path / "scene.json").render()
    scene["objects"][0]["material"]["color_map"] = meso.ColorMap(colours)
    scene["objects"][0]["mesostructure"]["height_map"] = cones  # a bare array: a HeightField
    from_arrays = meso.Scene.from_dict(scene, base_dir=tmp_path).render()
    assert_same_image(from_file, from_arrays)


def cube_tile():
    """A closed box inside one tile, 0.2..0.8 in x, y and 0.3..0.95 in z, outward faces."""
    lo, hi = (0.2, 0.2, 0.3), (0.8, 0.8, 0.95)
    vertices = np.array([[(lo, hi)[(k >> a) & 1][a] for a in range(3)] for k in range(8)],
                        dtype=np.float32)
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = [(a, b, c) for a, b, c, d in faces] + [(a, c, d) for a, b, c, d in faces]
    return vertices, np.array(triangles, dtype=np.int64)


def test_tile_mesh_arrays_render_as_their_obj(tmp_path):
    vertices, triangles = cube_tile()
    with open(tmp_path / "box.obj", "w") as f:
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in triangles)
    scene = plane_scene(None, "relief_layers")
    scene["objects"][0]["mesostructure"] = {"solid": "box.obj", "depth": 0.15}
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    from_file = meso.Scene.load(tmp_path / "scene.json").render()
    scene["objects"][0]["mesostructure"]["solid"] = meso.TileMesh(vertices, triangles)
    from_arrays = meso.Scene.from_dict(scene).render()
    assert from_file.coverage.sum() > 100
    assert_same_image(from_file, from_arrays)


def test_an_open_tile_mesh_is_refused_with_the_key():
    vertices, triangles = cube_tile()
    scene = plane_scene(None, "relief_layers")
    scene["objects"][0]["mesostructure"] = {
        "solid": meso.TileMesh(vertices, triangles[:-1], name="open-box"), "depth": 0.15}
    with pytest.raises(meso.Error, match="open-box") as error:
        meso.Scene.from_dict(scene)
    assert error.value.result == "malformed input" and error.value.bad_input


@pytest.mark.parametrize("array, reason", [
    (np.zeros((8, 8), np.int64), "dtype int64 is not float, uint8 or uint16"),
    (np.full((8, 8), np.nan, np.float32), "nan at row 0, column 0"),
    (np.zeros((0, 8), np.float32), "shape (0, 8) has no texels"),
    (np.zeros((8, 0), np.uint8), "shape (8, 0) has no texels"),
    (np.zeros((2, 8, 8), np.float32), "is not (height, width)"),
    (np.full((4, 4), 1.5), "1.5 at row 0, column 0 is outside [0, 1]"),
])
def test_a_bad_height_array_names_the_argument(array, reason):
    with pytest.raises(meso.Error) as error:
        meso.HeightField(array)
    assert str(error.value).startswith("HeightField: array: ")
    assert reason in str(error.value)


def test_bad_arguments_name_themselves():
    scene = meso.Scene.from_dict(plane_scene(asymmetric_heights()))
    with pytest.raises(meso.Error, match=r"^size: "):
        scene.render(size=(0, 5))
    with pytest.raises(meso.Error, match=r"^threads: "):
        scene.render(threads=-1)
    with pytest.raises(meso.Error, match=r"^ColorMap: array: nan at row 0, column 0"):
        meso.ColorMap(np.full((4, 4, 3), np.nan))
    with pytest.raises(meso.Error, match=r"^TileMesh: indices: values must lie in \[0, 3\)"):
        meso.TileMesh(np.zeros((3, 3), np.float32), np.array([[0, 1, 3]]))
    with pytest.raises(meso.Error, match=r"^TileMesh: vertices: dtype int64 is not float"):
        meso.TileMesh(np.zeros((3, 3), np.int64), np.array([[0, 1, 2]]))
    with pytest.raises(meso.Error, match=r"^options\.relief\.linear_steps: 5000 is not"):
        scene.render(options={"relief": {"linear_steps": 5000}})
    with pytest.raises(meso.Error, match=r"^camera\.fov_y_deg: must be in \(0, 180\)"):
        scene.camera.fov_y_deg = 190
    with pytest.raises(meso.Error, match=r"wrap: 'clamp' contradicts"):
        meso.Scene.from_dict(plane_scene(meso.HeightField(asymmetric_heights()),
                                         mesostructure={"wrap": "clamp"}))
