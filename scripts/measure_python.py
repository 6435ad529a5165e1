#!/usr/bin/python3
"""The Python package's figures in docs/python.md: frame time against `meso bench`, the
Python-side cost of a frame, zero-copy arrays, and peak memory of a large render against the
program's.

    PYTHONPATH=build/python /usr/bin/python3 scripts/measure_python.py [--rounds 5]

frames   For each scene x technique: `meso bench SCENE --techniques T --frames 30 --json` and a
         kept meso.Renderer drawing 2 warm-up frames then 30 timed ones into the same Image
         (render(out=...)), alternated --rounds times so that both see the same machine load.
         Reports the medians over rounds of both, their ratio, the range and median of the
         rounds' ratios, the ratio of the quickest rounds, and the Python-side cost of a call:
         the median over frames of (wall time of renderer.render) - (libmeso's own frame
         time), which includes the part of meso_renderer_render outside its own timer.
memory   `meso render SCENE --size 2048x2048 -o x.png` and the same from Python
         (scene.render(size=(2048, 2048)).save(...)), each in a fresh process; peak resident
         set sizes (/usr/bin/time for the program, getrusage in the Python child), and
         Python's baseline (interpreter, NumPy and the package imported, nothing rendered).
calls    The package's own cost of a frame: renderer.render(out=...) against the bare cffi
         call it makes, on a 16x16 frame, 3000 times each, alternated.
--callgrind  Instruction counts instead, which machine load does not change (valgrind):
         libmeso's work in a frame from the program and from Python, and the package's own
         instructions a frame.
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import meso

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.dirname(HERE)


def bench_program(program, scene, technique, frames):
    with tempfile.NamedTemporaryFile(suffix=".json") as out:
        subprocess.run([program, "bench", scene, "--techniques", technique, "--frames",
                        str(frames), "--json", out.name, "--quiet"], check=True,
                       capture_output=True)
        run = json.load(open(out.name))["runs"][0]
    return run["median_ms"]


def bench_python(scene_path, technique, frames):
    scene = meso.Scene.load(scene_path)
    with scene.renderer(technique) as renderer:
        image = renderer.render()
        renderer.render(out=image)  # 2 warm-up frames, as meso bench
        walls, frame_ms = [], []
        for _ in range(frames):
            start = time.perf_counter()
            renderer.render(out=image)
            walls.append(1e3 * (time.perf_counter() - start))
            frame_ms.append(image.frame_ms)
    overhead_us = statistics.median(1e3 * (w - f) for w, f in zip(walls, frame_ms))
    return statistics.median(walls), statistics.median(frame_ms), overhead_us


def call_cost(scene_path, calls=3000):
    """Median microseconds of renderer.render(out=image) and of the bare cffi call
    lib.meso_renderer_render it makes, on a 16x16 `flat` frame (libmeso's work is then a few
    microseconds and the same in both), alternated; their difference is the package's cost."""
    from meso._core import lib
    scene = meso.Scene.load(scene_path)
    with scene.renderer("flat", threads=1) as renderer:
        image = renderer.render((16, 16))
        pointer, fb = renderer._handle.ptr, image._framebuffer
        package, bare = [], []
        for _ in range(calls):
            start = time.perf_counter()
            renderer.render(out=image)
            middle = time.perf_counter()
            lib.meso_renderer_render(pointer, fb)
            end = time.perf_counter()
            package.append(1e6 * (middle - start))
            bare.append(1e6 * (end - middle))
    return statistics.median(package), statistics.median(bare)


def zero_copy(scene_path):
    scene = meso.Scene.load(scene_path)
    with scene.renderer("relief") as renderer:
        image = renderer.render()
        before = image.rgb
        renderer.render(out=image)
        c_address = int(meso._core.ffi.cast("uintptr_t", image._framebuffer.color))
        return {"rgb_is_the_framebuffer": image.rgb.__array_interface__["data"][0] == c_address,
                "shares_memory_across_frames": bool(np.shares_memory(before, image.rgb)),
                "owns_data": bool(image.rgb.flags.owndata)}


CHILD = r"""
import resource, sys
import meso
if sys.argv[1] == "render":
    scene = meso.Scene.load(sys.argv[2])
    technique = sys.argv[4] if len(sys.argv) > 4 else None
    scene.render(technique, size=(2048, 2048)).save(sys.argv[3])
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def peak_rss_mb(command):
    """The peak resident set of a Python child running CHILD (it prints its own)."""
    done = subprocess.run(command, check=True, capture_output=True, text=True)
    return int(done.stdout.split()[-1]) / 1024


def memory(program, scene_path, technique):
    with tempfile.TemporaryDirectory() as folder:
        out = os.path.join(folder, "x.png")
        extra = ["--technique", technique] if technique else []
        # /usr/bin/time -f %M: the program's peak resident set in KB
        done = subprocess.run(["/usr/bin/time", "-f", "%M", program, "render", scene_path,
                               "--size", "2048x2048", "-o", out, "--quiet", *extra],
                              check=True, capture_output=True, text=True)
        program_mb = int(done.stderr.split()[-1]) / 1024
        python_mb = peak_rss_mb([sys.executable, "-c", CHILD, "render", scene_path, out,
                                 *([technique] if technique else [])])
        baseline_mb = peak_rss_mb([sys.executable, "-c", CHILD, "import"])
    return program_mb, python_mb, baseline_mb


CALLGRIND_FRAMES = r"""
import sys
import meso
from meso._core import lib
scene = meso.Scene.load(sys.argv[1])
with scene.renderer(sys.argv[2], threads=1) as renderer:
    image = renderer.render(None if sys.argv[3] == "scene" else (16, 16))
    pointer, fb = renderer._handle.ptr, image._framebuffer
    for _ in range(int(sys.argv[4])):
        if sys.argv[3] == "bare":
            lib.meso_renderer_render(pointer, fb)
        else:
            renderer.render(out=image)
"""


def instructions(command, toggle=None):
    """Instructions callgrind counts for `command` (only inside `toggle` when given)."""
    with tempfile.NamedTemporaryFile() as out:
        options = [f"--toggle-collect={toggle}"] if toggle else []
        done = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out.name}",
                               *options, *command], check=True, capture_output=True, text=True,
                              env=dict(os.environ, PYTHONHASHSEED="0"))
    line = next(line for line in done.stderr.splitlines() if "Collected :" in line)
    return int(line.split(":")[-1])


def callgrind(program, scene_path, technique, frames=300):
    """Instructions, which a loaded machine does not change: libmeso's work in one frame of
    the scene (inside meso_renderer_render, one thread) from `meso render` and from
    scene.render; and the package's own per frame: `frames` 16x16 `flat` frames through
    renderer.render(out=...) against as many bare cffi calls, whole processes counted."""
    python = [sys.executable, "-c", CALLGRIND_FRAMES, scene_path]
    in_program = instructions([program, "render", scene_path, "--technique", technique,
                               "--threads", "1", "-o",
                               os.path.join(tempfile.gettempdir(), "measure-python.png")],
                              "meso_renderer_render")
    in_python = instructions(python + [technique, "scene", "0"], "meso_renderer_render")
    package = instructions(python + ["flat", "package", str(frames)])
    bare = instructions(python + ["flat", "bare", str(frames)])
    again = instructions(python + ["flat", "bare", str(frames)])
    return in_program, in_python, (package - bare) / frames, abs(again - bare) / frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--program", default=os.path.join(SOURCE, "build", "meso"))
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--pairs", default="bricks-plane:relief,bricks-plane:flat,"
                        "bumps-sphere:parallax,bricks-teapot:relief")
    parser.add_argument("--callgrind", action="store_true",
                        help="instruction counts instead (valgrind; minutes)")
    arguments = parser.parse_args()
    if arguments.callgrind:
        bricks = os.path.join(SOURCE, "examples", "bricks-plane.json")
        in_program, in_python, package, noise = callgrind(arguments.program, bricks, "relief")
        print(f"bricks-plane relief 512x512, one thread, instructions inside "
              f"meso_renderer_render: meso render {in_program / 1e6:.3f} M, scene.render "
              f"{in_python / 1e6:.3f} M ({in_python / in_program - 1:+.4%})")
        print(f"the package's own instructions a frame: {package:.0f} (between two identical "
              f"runs: {noise:.0f} a frame); a kept renderer's frame: "
              f"{(in_python + package) / in_program:.5f}x the program's")
        return
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load {os.getloadavg()[0]:.2f}; meso ISA {meso.technique_isa()}")
    print(f"{'scene':14s} {'technique':10s} {'bench ms':>9s} {'python ms':>9s} {'ratio':>6s} "
          f"{'round ratios':>22s} {'best ratio':>10s} {'python-side us':>15s}")
    for pair in arguments.pairs.split(","):
        name, technique = pair.split(":")
        scene = os.path.join(SOURCE, "examples", name + ".json")
        bench, python, overhead = [], [], []
        for _ in range(arguments.rounds):
            bench.append(bench_program(arguments.program, scene, technique, arguments.frames))
            wall, _, cost = bench_python(scene, technique, arguments.frames)
            python.append(wall)
            overhead.append(cost)
        b, p = statistics.median(bench), statistics.median(python)
        ratios = sorted(q / r for q, r in zip(python, bench))
        spread = f"{ratios[0]:.3f}..{ratios[-1]:.3f} ({statistics.median(ratios):.3f})"
        # the quietest round of each: what a quiet machine would give
        print(f"{name:14s} {technique:10s} {b:9.3f} {p:9.3f} {p / b:6.3f} {spread:>22s} "
              f"{min(python) / min(bench):10.3f} {statistics.median(overhead):15.1f}",
              flush=True)
    bricks = os.path.join(SOURCE, "examples", "bricks-plane.json")
    package, bare = call_cost(bricks)
    print(f"a 16x16 flat frame: renderer.render(out=...) {package:.2f} us, the bare cffi call "
          f"{bare:.2f} us: the package adds {package - bare:.2f} us a frame")
    print("zero copy:", zero_copy(bricks))
    for technique in (None, "reference"):
        program_mb, python_mb, baseline_mb = memory(arguments.program, bricks, technique)
        print(f"peak RSS, 2048x2048 bricks-plane ({technique or 'bump'}), rendered and saved: "
              f"program {program_mb:.1f} MB, Python {python_mb:.1f} MB "
              f"({python_mb / program_mb:.3f}x); Python with the package imported and nothing "
              f"rendered: {baseline_mb:.1f} MB", flush=True)


if __name__ == "__main__":
    main()
