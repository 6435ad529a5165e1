"""NumPy arrays as meso data: height maps, colour and normal maps, tile meshes.

Each class checks its array once, when made, and raises meso.Error naming the argument
("HeightField: array: NaN at row 3, column 7"). Scene.from_dict takes them where a scene file
names a PNG or a tile mesh ("height_map", "color_map", "normal_map", "solid"); libmeso then
converts them exactly as it converts those files (meso_scene_create's resources).
"""

import numpy as np

from ._core import argument_error, ffi, image_view, lib

_WRAPS = ("repeat", "clamp")


def _samples_to_float(owner, name, array, channels):
    """The float32 values a PNG of these samples loads as (core_png.c: an 8-bit sample v is
    (float)v * (1.0f / 255.0f), a 16-bit one (float)v * (1.0f / 65535.0f); float32 arithmetic,
    so the bits match), or float data checked finite and in [0, 1]."""
    where = f"{owner}: {name}"
    if not isinstance(array, np.ndarray):
        try:
            array = np.asarray(array)
        except (TypeError, ValueError) as error:
            raise argument_error(f"{where}: not an array ({error})") from None
    if array.ndim not in channels:
        shapes = " or ".join({2: "(height, width)", 3: "(height, width, channels)"}[n]
                             for n in channels)
        raise argument_error(f"{where}: shape {array.shape} is not {shapes}")
    if array.shape[0] == 0 or array.shape[1] == 0:
        raise argument_error(f"{where}: shape {array.shape} has no texels")
    if array.ndim == 3 and not 1 <= array.shape[2] <= 4:
        raise argument_error(f"{where}: {array.shape[2]} channels (1 to 4)")
    height, width = array.shape[:2]
    if (width > lib.MESO_IMAGE_MAX_SIDE or height > lib.MESO_IMAGE_MAX_SIDE
            or width * height > lib.MESO_IMAGE_MAX_PIXELS):
        raise argument_error(f"{where}: {width}x{height} exceeds the limit of "
                             f"{lib.MESO_IMAGE_MAX_SIDE} a side, {lib.MESO_IMAGE_MAX_PIXELS} "
                             f"pixels")
    dtype = array.dtype
    if dtype.kind == "u" and dtype.itemsize in (1, 2):
        scale = np.float32(1) / np.float32(255 if dtype.itemsize == 1 else 65535)
        values = array.astype(np.float32) * scale
    elif dtype.kind == "f":
        values = np.ascontiguousarray(array, dtype=np.float32)
        bad = ~np.isfinite(values)
        if bad.any():
            index = np.argwhere(bad)[0]
            raise argument_error(f"{where}: {values[tuple(index)]} at row {index[0]}, "
                                 f"column {index[1]} (values must be finite)")
        outside = (values < 0) | (values > 1)
        if outside.any():
            index = np.argwhere(outside)[0]
            raise argument_error(f"{where}: {values[tuple(index)]:g} at row {index[0]}, "
                                 f"column {index[1]} is outside [0, 1]")
    else:
        raise argument_error(f"{where}: dtype {dtype} is not float, uint8 or uint16")
    return np.ascontiguousarray(values, dtype=np.float32)


def _check_wrap(owner, wrap):
    if wrap not in _WRAPS:
        raise argument_error(f"{owner}: wrap: must be \"repeat\" or \"clamp\", not {wrap!r}")
    return wrap


class HeightField:
    """A height map from a 2-D array: h in [0, 1], 1 on the mesh and 0 at the shell's depth
    below it (meso's inward convention), row 0 at the top of the map (v = 1).

    array  float (values in [0, 1], checked), uint8 (v / 255) or uint16 (v / 65535): the same
           values a PNG of those samples gives, so an array and its 16-bit PNG render alike.
    wrap   "repeat" or "clamp": the mesostructure's "wrap" in Scene.from_dict (set there
           unless the dict says otherwise; a contradiction is an error).
    """

    kind = "image"

    def __init__(self, array, wrap="repeat", name=None):
        self.values = _samples_to_float("HeightField", "array", array, (2,))
        self.values.flags.writeable = False
        self.wrap = _check_wrap("HeightField", wrap)
        self.name = name
        self.encoding = "linear"

    @property
    def shape(self):
        return self.values.shape

    def _image(self):
        return image_view(self.values)

    def __repr__(self):
        return f"meso.HeightField({self.shape[1]}x{self.shape[0]}, wrap={self.wrap!r})"


class ColorMap:
    """A colour map from an array (height, width, 3 or 4) or (height, width), float in [0, 1],
    uint8 or uint16 as HeightField. encoding "srgb" (as a PNG: decoded to linear for shading)
    or "linear" (used as given)."""

    kind = "image"

    def __init__(self, array, encoding="srgb", name=None):
        self.values = _samples_to_float("ColorMap", "array", array, (2, 3))
        self.values.flags.writeable = False
        if encoding not in ("srgb", "linear"):
            raise argument_error(
                f"ColorMap: encoding: must be \"srgb\" or \"linear\", not {encoding!r}")
        self.encoding = encoding
        self.name = name

    def _image(self):
        return image_view(self.values)

    def __repr__(self):
        return f"meso.ColorMap({self.values.shape[1]}x{self.values.shape[0]}, {self.encoding})"


class NormalMap(ColorMap):
    """A tangent-space normal map (height, width, 3): x, y, z in [-1, 1] stored as (c + 1) / 2,
    as in a PNG (OpenGL convention unless the material says "normal_map_convention")."""

    def __init__(self, array, name=None):
        values = np.asarray(array)
        if values.ndim != 3 or values.shape[-1] not in (3, 4):
            raise argument_error(f"NormalMap: array: shape {values.shape} is not "
                                 f"(height, width, 3)")
        super().__init__(values, "linear", name)


class TileMesh:
    """A closed triangle mesh of one tile of solid mesostructure (docs/scene-format.md "solid"):
    x, y map to u, v (periodic), z to 1 - w, its top at z = 1. libmeso checks that it is
    closed, manifold and consistently oriented when the scene is made.

    vertices  (N, 3) float, finite
    indices   (M, 3) integer, each in [0, N), counter-clockwise seen from outside
    """

    kind = "mesh"

    def __init__(self, vertices, indices, name=None):
        v = np.asarray(vertices)
        if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
            raise argument_error(f"TileMesh: vertices: shape {v.shape} is not (N, 3), N > 0")
        if v.dtype.kind != "f":
            raise argument_error(f"TileMesh: vertices: dtype {v.dtype} is not float")
        self.vertices = np.ascontiguousarray(v, dtype=np.float32)
        if not np.isfinite(self.vertices).all():
            row = int(np.argwhere(~np.isfinite(self.vertices))[0][0])
            raise argument_error(f"TileMesh: vertices: row {row} is not finite")
        i = np.asarray(indices)
        if i.ndim != 2 or i.shape[1] != 3 or i.shape[0] == 0:
            raise argument_error(f"TileMesh: indices: shape {i.shape} is not (M, 3), M > 0")
        if i.dtype.kind not in "iu":
            raise argument_error(f"TileMesh: indices: dtype {i.dtype} is not an integer type")
        if i.min() < 0 or i.max() >= len(self.vertices):
            raise argument_error(f"TileMesh: indices: values must lie in [0, "
                                 f"{len(self.vertices)}), found {i.min()}..{i.max()}")
        self.indices = np.ascontiguousarray(i, dtype=np.uint32)
        self.vertices.flags.writeable = False
        self.indices.flags.writeable = False
        self.name = name

    def __repr__(self):
        return f"meso.TileMesh({len(self.vertices)} vertices, {len(self.indices)} triangles)"


def fill_resource(resource, name, data, keep):
    """Point a meso_scene_resource at `data` (a HeightField, ColorMap or TileMesh)."""
    name_c = ffi.new("char[]", name.encode())
    keep.append(name_c)
    resource.name = name_c
    if data.kind == "image":
        image = data._image()
        keep.append(image)
        resource.image = image
        resource.encoding = (lib.MESO_ENCODING_LINEAR if data.encoding == "linear"
                             else lib.MESO_ENCODING_SRGB)
    else:
        resource.positions = ffi.cast("meso_vec3 *", ffi.from_buffer(data.vertices))
        resource.num_vertices = len(data.vertices)
        resource.indices = ffi.cast("uint32_t *", ffi.from_buffer(data.indices))
        resource.num_triangles = len(data.indices)
