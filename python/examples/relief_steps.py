#!/usr/bin/python3
"""An asymmetric height map made in NumPy, rendered with every height-field technique and the
ray-traced reference; the figure plots each technique's covered PSNR against the reference and,
for relief mapping, how it grows with relief.linear_steps (docs/python.md shows the figure).

    PYTHONPATH=build/python /usr/bin/python3 python/examples/relief_steps.py -o relief-steps.png

The first run bakes the VDM and GDM maps (tens of CPU seconds) into the bake cache
(~/.cache/meso, or $MESO_CACHE_DIR); later runs read them back.
"""

import argparse

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import meso  # noqa: E402


def cones_and_ridge(size=256, seed=5):
    """Heights in [0, 1]: cones of random radii and heights on a ramp, cut by a diagonal
    groove; nothing in it is symmetric, so a flipped u, v or a mirrored lookup shows."""
    rng = np.random.default_rng(seed)
    v, u = (np.mgrid[0:size, 0:size] + 0.5) / size
    heights = 0.3 + 0.25 * u + 0.1 * v
    for _ in range(12):
        cu, cv = rng.uniform(0, 1, 2)
        radius, top = rng.uniform(0.05, 0.16), rng.uniform(0.7, 1.0)
        # distance on the torus: the map tiles (wrap "repeat")
        du = np.minimum(abs(u - cu), 1 - abs(u - cu))
        dv = np.minimum(abs(v - cv), 1 - abs(v - cv))
        heights = np.maximum(heights, top * (1 - np.hypot(du, dv) / radius))
    groove = abs((u - 0.7 * v + 0.2) % 1.0 - 0.5)
    heights = np.where(groove < 0.03, heights * 0.2, heights)
    return np.clip(heights, 0, 1).astype(np.float32)


def scene_of(heights, size):
    return meso.Scene.from_dict({
        "image": {"width": size, "height": size, "background": [0.02, 0.02, 0.03]},
        "camera": {"eye": [0.8, 0.75, 1.9], "target": [0.0, -0.15, 0.0], "up": [0, 1, 0],
                   "fov_y_deg": 40},
        "ambient": [0.12, 0.12, 0.12],
        "lights": [{"type": "directional", "direction": [-0.75, 0.55, -0.35]}],
        "objects": [{"name": "cones", "shape": "plane", "size": 2, "uv_scale": [2, 2],
                     "material": {"albedo": [0.85, 0.75, 0.6]},
                     "mesostructure": {"height_map": meso.HeightField(heights),
                                       "depth": 0.25}}],
    })


def display(image):
    """Linear RGB -> sRGB for the screen."""
    c = np.clip(image.rgb, 0, 1)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", default="relief-steps.png")
    parser.add_argument("--size", type=int, default=256, help="image side in pixels")
    parser.add_argument("--samples", type=int, default=4,
                        help="samples a pixel (4: edges anti-aliased alike in every image)")
    arguments = parser.parse_args()

    scene = scene_of(cones_and_ridge(), arguments.size)
    samples = arguments.samples
    truth = scene.render("reference", samples=samples)
    names = [t.name for t in meso.techniques().values()
             if "height_field" in t.accepts and t.kind != "reference"]
    results = {}
    for name in names:
        image = scene.render(name, samples=samples)
        results[name] = (image, meso.compare(image, truth)["psnr_covered"])
        print(f"{name:14s} {results[name][1]:6.2f} dB  {image.frame_ms:7.2f} ms")

    steps = [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128]
    curve = []
    for n in steps:
        image = scene.render("relief", samples=samples,
                             options={"relief": {"linear_steps": n}})
        curve.append(meso.compare(image, truth)["psnr_covered"])

    figure = plt.figure(figsize=(12, 6.6), dpi=100)
    grid = figure.add_gridspec(2, 7, height_ratios=[1, 1.6], hspace=0.12, wspace=0.06)
    shown = ["reference", "bump", "parallax", "relief", "vdm", "gdm", "tessellation"]
    for column, name in enumerate(shown):
        axes = figure.add_subplot(grid[0, column])
        axes.imshow(display(truth if name == "reference" else results[name][0]))
        axes.set_title(name if name == "reference" else f"{name}\n{results[name][1]:.1f} dB",
                       fontsize=9)
        axes.axis("off")
    axes = figure.add_subplot(grid[1, :])
    axes.plot(steps, curve, "o-", color="black", label="relief (linear_steps varied)")
    colours = plt.cm.tab10(np.linspace(0, 1, 10))
    for k, name in enumerate(n for n in names if n != "relief"):
        axes.axhline(results[name][1], color=colours[k % 10], linestyle="--", linewidth=1,
                     label=f"{name} (defaults)")
    axes.axvline(meso.techniques()["relief"].options["linear_steps"].default, color="grey",
                 linestyle=":", linewidth=1)
    every = curve + [psnr for _, psnr in results.values()]
    axes.set_ylim(min(every) - 1, max(every) + 1)
    axes.set_xscale("log", base=2)
    axes.set_xticks(steps, [str(n) for n in steps])
    axes.set_xlabel("relief.linear_steps (dotted: the default)")
    axes.set_ylabel("covered PSNR against the reference (dB)")
    axes.grid(True, alpha=0.3)
    axes.legend(fontsize=8, ncol=2, loc="lower right")
    figure.suptitle("An asymmetric NumPy height map: every height-field technique against the "
                    "ray-traced reference", fontsize=11)
    figure.savefig(arguments.output, bbox_inches="tight")
    print(f"wrote {arguments.output}")


if __name__ == "__main__":
    main()
