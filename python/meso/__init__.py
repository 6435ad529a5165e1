"""meso from Python: scenes, renders and comparisons as NumPy arrays (docs/python.md).

    import numpy as np, meso
    heights = np.random.default_rng(1).random((64, 64)).astype(np.float32)
    scene = meso.Scene.from_dict({
        "objects": [{"shape": "plane", "size": 2, "technique": "relief",
                     "mesostructure": {"height_map": meso.HeightField(heights),
                                       "depth": 0.05}}],
        "lights": [{"type": "directional", "direction": [0.4, 1, 0.3]}]})
    image = scene.render(size=(256, 256))        # image.rgb: float32 (256, 256, 3), linear
    truth = scene.render("reference", size=(256, 256))
    print(meso.compare(image, truth)["psnr_covered"])

A binding over libmeso.so with cffi (API mode); libmeso's calls run without the GIL.
"""

from ._core import Error, Warning  # noqa: A004
from .arrays import ColorMap, HeightField, NormalMap, TileMesh
from .compare import compare, load_image
from .render import Image, Renderer
from .scene import Camera, Light, Object, Scene
from .techniques import Option, Technique, technique_isa, techniques

for _name in ("Error", "Warning", "Scene", "Camera", "Light", "Object", "HeightField",
              "ColorMap", "NormalMap", "TileMesh", "Renderer", "Image"):
    globals()[_name].__module__ = "meso"  # tracebacks say meso.Error, as the docs do

__version__ = "0.1.0"
__all__ = ["Error", "Warning", "Scene", "Camera", "Light", "Object", "HeightField",
           "ColorMap", "NormalMap", "TileMesh", "Renderer", "Image", "compare", "load_image",
           "techniques", "technique_isa", "Technique", "Option"]
