"""Renders, comparisons, errors, threads and the GIL, against the meso program."""

import json
import threading
import time

import numpy as np
import pytest

import meso
from conftest import asymmetric_heights, plane_scene, run_program, write_png


@pytest.fixture(scope="module")
def scene():
    return meso.Scene.from_dict(plane_scene(meso.HeightField(asymmetric_heights())))


def test_metrics_and_difference_equal_meso_compare(tmp_path, scene):
    relief = scene.render("relief", options={"relief": {"linear_steps": 4}})
    truth = scene.render("reference")
    relief.save(tmp_path / "a.png", coverage=tmp_path / "a.coverage.png", bits=16,
                encoding="linear")
    truth.save(tmp_path / "b.png", coverage=tmp_path / "b.coverage.png", bits=16,
               encoding="linear")
    status, out, err = run_program("compare", tmp_path / "a.png", tmp_path / "b.png", "--json",
                                   "-o", tmp_path / "diff.png")
    assert status == 0, err
    program = json.loads(out)
    from_files = meso.compare(tmp_path / "a.png", tmp_path / "b.png")
    from_images = meso.compare(relief, truth)
    assert program["coverage_from"] == from_files["coverage_from"] == "masks"
    assert 20 < program["psnr_covered"] < 60  # a real difference, not identical images
    for key in ("psnr", "psnr_covered", "rmse", "rmse_covered", "ssim", "max_error",
                "coverage_iou", "covered_both", "covered_only_a", "covered_only_b", "width",
                "height"):
        # the program prints %.6g; the files hold the images at 16 bits
        assert f"{from_files[key]:.6g}" == f"{program[key]:.6g}", key
        assert from_images[key] == pytest.approx(program[key], rel=1e-3, abs=1e-5), key
    # the difference image: the program writes it as an 8-bit linear PNG
    written = meso.load_image(tmp_path / "diff.png")
    assert np.array_equal(np.round(np.clip(from_files["diff"], 0, 1) * 255) / 255,
                          np.round(written * 255) / 255)


def test_an_error_message_equals_the_programs(tmp_path):
    bad_key = plane_scene("cones.png")
    bad_key["objects"][0]["mesostructure"]["dpeth"] = 1
    bad_technique = plane_scene("cones.png", technique="relif")
    write_png(tmp_path / "cones.png", asymmetric_heights())
    for name, scene in (("bad-key.json", bad_key), ("bad-technique.json", bad_technique),
                        ("missing.json", None)):
        path = tmp_path / name
        if scene is not None:
            path.write_text(json.dumps(scene))
        status, _, err = run_program("render", path, "-o", tmp_path / "out.png")
        with pytest.raises(meso.Error) as error:
            meso.Scene.load(path).render()
        assert err.strip() == f"meso: {error.value}"
        assert (status == 2) == error.value.bad_input


def test_the_frame_equals_the_programs(tmp_path, scene):
    for technique in ("relief", "reference"):
        scene.render(technique, size=(64, 48)).save(tmp_path / "py.png", bits=16)
        (tmp_path / "scene.json").write_text(json.dumps(plane_scene("cones.png", technique)))
        write_png(tmp_path / "cones.png", asymmetric_heights())
        status, _, err = run_program("render", tmp_path / "scene.json", "--size", "64x48",
                                     "--bits", "16", "-o", tmp_path / "program.png")
        assert status == 0, err
        assert (tmp_path / "py.png").read_bytes() == (tmp_path / "program.png").read_bytes()


@pytest.mark.parametrize("technique", ["relief", "tessellation", "reference"])
def test_threads_1_and_2_give_identical_arrays(scene, technique):
    one = scene.render(technique, threads=1, samples=4)
    two = scene.render(technique, threads=2, samples=4)
    assert np.array_equal(one.rgb, two.rgb)
    assert np.array_equal(one.coverage, two.coverage)
    assert np.array_equal(one.depth, two.depth)


def test_python_runs_while_a_frame_renders(scene):
    """The GIL is released during libmeso's calls: a Python loop in this thread keeps
    counting while another thread's frame is being drawn."""
    with scene.renderer("relief", samples=64, threads=1,
                        options={"relief": {"linear_steps": 64}}) as renderer:
        span = {}

        def draw():
            span["start"] = time.perf_counter()
            renderer.render((192, 144))
            span["end"] = time.perf_counter()

        worker = threading.Thread(target=draw)
        ticks = []
        worker.start()
        while worker.is_alive():
            ticks.append(time.perf_counter())
        worker.join()
    during = [t for t in ticks if span["start"] < t < span["end"]]
    assert span["end"] - span["start"] > 0.02  # a frame long enough to tell
    # with the GIL held through the call this thread could not run at all inside the frame
    assert len(during) > 1000, (len(during), span)


def test_arrays_are_the_memory_the_frame_was_drawn_into(scene):
    with scene.renderer("relief") as renderer:
        image = renderer.render()
        fb = image._framebuffer
        address = int(meso._core.ffi.cast("uintptr_t", fb.color))
        assert image.rgb.__array_interface__["data"][0] == address
        assert image.coverage.__array_interface__["data"][0] == \
            int(meso._core.ffi.cast("uintptr_t", fb.coverage))
        assert image.rgb.dtype == np.float32 and image.rgb.shape == (72, 96, 3)
        before = image.rgb
        scene.camera.eye = (0.5, 1.5, 2.1)
        again = renderer.render(out=image)  # drawn into the same arrays
        assert again is image and np.shares_memory(before, again.rgb)


def test_a_kept_renderer_follows_the_camera_without_preparing_again():
    scene = meso.Scene.from_dict(plane_scene(meso.HeightField(asymmetric_heights())))
    with scene.renderer("relief") as renderer:
        first = renderer.render()
        prepared = renderer.stats["prepare_seconds"]
        scene.camera.eye = (-0.6, 1.4, 1.9)
        scene.lights[0].direction = (0.5, 0.8, 0.2)
        moved = renderer.render()
        assert renderer.stats["prepare_seconds"] == prepared
    fresh = scene.render("relief")
    assert not np.array_equal(first.rgb, moved.rgb)
    assert np.array_equal(moved.rgb, fresh.rgb)


def test_objects_change_only_without_open_renderers():
    scene = meso.Scene.from_dict(plane_scene(meso.HeightField(asymmetric_heights())))
    renderer = scene.renderer("relief")
    with pytest.raises(meso.Error, match=r"^objects\[0\]\.technique: the scene has 1 open"):
        scene.objects[0].technique = "parallax"
    renderer.close()
    scene.objects[0].technique = "parallax"
    flat = np.full((16, 16), 0.5, np.float32)
    scene.objects[0].height_field = meso.HeightField(flat)
    assert np.array_equal(scene.objects[0].height_field, flat)
    assert scene.render().technique is None
    with pytest.raises(meso.Error, match=r"unknown technique 'relif'"):
        scene.objects[0].technique = "relif"


def test_techniques_are_the_tables_of_meso_help():
    techniques = meso.techniques()
    assert "relief" in techniques and "reference" in techniques
    for technique in techniques.values():
        status, out, _ = run_program("help", technique.name)
        assert status == 0
        assert technique.paper in out
        for option in technique.options.values():
            row = next(line.split() for line in out.splitlines()
                       if line.split()[:1] == [option.name] and len(line.split()) > 3
                       and line.split()[1] in ("integer", "boolean", "number"))
            if option.type == "bool":
                default = "true" if option.default else "false"
            elif option.type == "float":
                default = f"{option.default:g}"
            else:
                default = str(option.default)
            assert default in row, (technique.name, option, row)
    steps = techniques["relief"].options["linear_steps"]
    assert (steps.type, steps.default, steps.min, steps.max) == ("int", 16, 1, 1024)


def test_progress_reports_a_bake_and_can_cancel_it(monkeypatch, scene):
    monkeypatch.setenv("MESO_CACHE_DIR", "off")  # bake every time
    small = {"vdm": {"resolution": 16, "num_theta": 4, "num_phi": 2, "num_curvatures": 2}}
    seen = []
    scene.render("vdm", options=small, progress=lambda label, f: seen.append((label, f)))
    assert "vdm bake" in {label for label, _ in seen}
    assert all(0.0 <= fraction <= 1.0 for _, fraction in seen)

    with pytest.raises(meso.Error) as error:
        scene.render("vdm", options=small, progress=lambda label, f: label == "vdm bake")
    assert error.value.result == "cancelled"

    class Bar:  # what tqdm.tqdm offers
        def __init__(self):
            self.n, self.descriptions = 0.0, []

        def reset(self, total):
            self.n, self.total = 0.0, total

        def set_description(self, text):
            self.descriptions.append(text)

        def update(self, amount):
            self.n += amount

    bar = Bar()
    scene.render("vdm", options=small, progress=bar)
    assert "vdm bake" in bar.descriptions and bar.total == 100 and 0 < bar.n <= 100

    class Stop(Exception):
        pass

    def fail(label, fraction):
        raise Stop(label)

    with pytest.raises(Stop):
        scene.render("vdm", options=small, progress=fail)
