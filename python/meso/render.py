"""meso.Renderer and meso.Image: frames drawn by libmeso straight into NumPy arrays."""

import numpy as np

from ._core import Context, Owned, aligned_empty, argument_error, ffi, float32_view, fspath, lib
from .scene import Scene, _flatten_options


def check_size(size, name="size"):
    try:
        width, height = size
    except (TypeError, ValueError):
        raise argument_error(f"{name}: must be (width, height), not {size!r}") from None
    for value in (width, height):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value <= 0:
            raise argument_error(f"{name}: must be (width, height) of whole numbers > 0, "
                                 f"not {size!r}")
    width, height = int(width), int(height)
    if (width > lib.MESO_IMAGE_MAX_SIDE or height > lib.MESO_IMAGE_MAX_SIDE
            or width * height > lib.MESO_IMAGE_MAX_PIXELS):
        raise argument_error(f"{name}: {width}x{height} exceeds the limit of "
                             f"{lib.MESO_IMAGE_MAX_SIDE} a side, {lib.MESO_IMAGE_MAX_PIXELS} "
                             f"pixels")
    return width, height


def _framebuffer(rgb, coverage, depth):
    """A meso_framebuffer struct whose arrays are the NumPy arrays' memory (no copy)."""
    fb = ffi.new("meso_framebuffer *")
    fb.height, fb.width = coverage.shape
    fb.color = float32_view(rgb)
    fb.coverage = float32_view(coverage)
    fb.depth = float32_view(depth)
    return fb


class Image:
    """A rendered frame. The arrays are the memory libmeso drew into (no copy):

    rgb       float32 (height, width, 3), linear RGB, row 0 at the top
    coverage  float32 (height, width), the fraction of the pixel's samples covered
    depth     float32 (height, width), view depth of the nearest surface, +inf where empty
    frame_ms  the frame's time as libmeso measured it (meso_render_stats), milliseconds
    technique the technique that drew it (None: each object's own)
    encoding  the scene's: what save() writes unless told ("srgb" or "linear")
    """

    def __init__(self, rgb, coverage=None, depth=None, frame_ms=None, technique=None,
                 encoding="srgb"):
        rgb = np.asarray(rgb)
        if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.float32:
            raise argument_error(f"Image: rgb: must be float32 (height, width, 3), not "
                                 f"{rgb.dtype} {rgb.shape}")
        shape = rgb.shape[:2]
        if coverage is None:
            coverage = np.ones(shape, np.float32)
        if depth is None:
            depth = np.full(shape, np.inf, np.float32)
        for name, array in (("coverage", coverage), ("depth", depth)):
            if np.shape(array) != shape or np.asarray(array).dtype != np.float32:
                raise argument_error(f"Image: {name}: must be float32 {shape}, not "
                                     f"{np.asarray(array).dtype} {np.shape(array)}")
        self.rgb = np.ascontiguousarray(rgb)
        self.coverage = np.ascontiguousarray(coverage)
        self.depth = np.ascontiguousarray(depth)
        self.frame_ms = frame_ms
        self.technique = technique
        self.encoding = encoding
        self._framebuffer = _framebuffer(self.rgb, self.coverage, self.depth)

    @classmethod
    def _empty(cls, width, height, technique, encoding):
        image = cls.__new__(cls)
        # every pixel is written by the frame (the rasterizer clears to the background, the
        # reference fills each sample): no need to touch the pages twice
        image.rgb = aligned_empty((height, width, 3), None)
        image.coverage = aligned_empty((height, width), None)
        image.depth = aligned_empty((height, width), None)
        image.frame_ms = None
        image.technique = technique
        image.encoding = encoding
        image._framebuffer = _framebuffer(image.rgb, image.coverage, image.depth)
        return image

    @property
    def size(self):
        return (self.rgb.shape[1], self.rgb.shape[0])

    def save(self, path, coverage=None, bits=8, encoding=None):
        """Write the colour as `meso render` does: PNG with the scene's encoding (or
        `encoding`: "srgb", "linear") at 8 or 16 bits, or OpenEXR (half floats, linear) when
        the path ends in .exr; `coverage` a second path for the coverage mask (grey, linear).
        Both files or neither (written under temporary names, then renamed)."""
        if bits not in (8, 16):
            raise argument_error(f"save: bits: must be 8 or 16, not {bits!r}")
        encoding = self.encoding if encoding is None else encoding
        if encoding not in ("srgb", "linear"):
            raise argument_error(f"save: encoding: must be \"srgb\" or \"linear\", not "
                                 f"{encoding!r}")
        desc = ffi.new("meso_png_desc *")
        desc.bit_depth = bits
        desc.encoding = lib.MESO_ENCODING_LINEAR if encoding == "linear" else \
            lib.MESO_ENCODING_SRGB
        context = Context()
        coverage_path = fspath(coverage, "coverage") if coverage is not None else ffi.NULL
        context.check(lib.meso_framebuffer_save(context.ptr, self._framebuffer, desc,
                                                fspath(path, "path"), coverage_path))

    def __repr__(self):
        ms = f", {self.frame_ms:.3f} ms" if self.frame_ms is not None else ""
        return f"meso.Image({self.size[0]}x{self.size[1]}, {self.technique}{ms})"


class Renderer:
    """A scene prepared for one technique (maps baked or read from the bake cache, meshes
    set up), drawing any number of frames: move the camera or a light between frames
    (scene.camera.eye = ...) and render again, without preparing again.

    technique  None: each object's own; else every object's (meso.techniques())
    samples    1, or S: an n x n ordered grid of samples a pixel, n = ceil(sqrt(S))
    options    {technique: {name: value}} over the scene's own (meso help TECHNIQUE), or
               {name: value} for `technique`
    threads    worker threads, 0: every core; images are identical for any number
    progress   a hook for long preparations (bakes): progress(label, fraction) returning
               True to cancel, a tqdm-like object with update(), or True for libmeso's bar
    fallback   draw objects the technique cannot with their own technique instead of failing
    frame_progress  report each frame's progress to the hook too (one long reference frame)

    Use it in a with block, or close() it: while it is open the scene's objects cannot be
    changed (the renderer holds what it prepared from them). The GIL is released while it
    prepares and draws."""

    def __init__(self, scene, technique=None, samples=1, options=None, threads=0,
                 progress=None, fallback=False, wireframe=False, frame_progress=False):
        if not isinstance(scene, Scene):
            raise argument_error(f"Renderer: scene: must be a meso.Scene, not "
                                 f"{type(scene).__name__}")
        if technique is not None and not isinstance(technique, str):
            raise argument_error(f"technique: must be a name, not {technique!r}")
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or \
                samples < 1:
            raise argument_error(f"samples: must be a whole number >= 1, not {samples!r}")
        context = Context(threads, progress)
        rows = _flatten_options(context, "options", options, technique=technique)
        desc = ffi.new("meso_render_desc *")
        keep = [desc]
        if technique is not None:
            technique_c = ffi.new("char[]", technique.encode())
            keep.append(technique_c)
            desc.technique = technique_c
        desc.samples = int(samples)
        desc.wireframe = bool(wireframe)
        desc.fallback = bool(fallback)
        desc.progress = bool(frame_progress)
        if rows:
            c_options = ffi.new("meso_option[]", len(rows))
            for k, (tech, name, value) in enumerate(rows):
                c_options[k].technique = tech.encode()
                c_options[k].name = name.encode()
                c_options[k].value = value
            keep.append(c_options)
            desc.options, desc.num_options = c_options, len(rows)
        self.scene = scene
        self.technique = technique
        self.samples = int(samples)
        self._context = context
        self._desc = desc
        self._keep = keep
        out = ffi.new("meso_renderer **")
        with scene._lock:
            context.check(lib.meso_renderer_create(context.ptr, scene._ptr, desc, out))
        # destroyed before its context and before the scene it draws
        self._handle = Owned(out[0], lib.meso_renderer_destroy, context, scene._handle)
        scene._renderers.add(self)

    def _ptr(self):
        if self._handle.ptr is None:
            raise argument_error("renderer: closed")
        return self._handle.ptr

    def render(self, size=None, out=None, threads=None):
        """Draw one frame and return a meso.Image. size (width, height), None: the scene's
        (or out's). out: an Image to draw into (its arrays are reused: no allocation, the
        fastest loop; it is returned). threads: change the worker count from this frame on."""
        pointer = self._ptr()
        if out is not None:
            if not isinstance(out, Image):
                raise argument_error(f"out: must be a meso.Image, not {type(out).__name__}")
            if size is not None and check_size(size) != out.size:
                raise argument_error(f"out: is {out.size[0]}x{out.size[1]}, size is "
                                     f"{size[0]}x{size[1]}")
            image = out
            image.technique = self.technique
        else:
            width, height = check_size(self.scene.size if size is None else size)
            context = self._context
            desc = ffi.new("meso_render_desc *", {"samples": self.samples})
            context.check(lib.meso_memory_check(
                context.ptr, self.scene.path.encode(),
                lib.meso_render_memory_estimate(desc, width, height)))
            image = Image._empty(width, height, self.technique, self.scene.encoding)
        if threads is not None:
            self._context.set_threads(threads)
        with self.scene._lock:
            self._context.check(lib.meso_renderer_render(pointer, image._framebuffer))
            stats = lib.meso_renderer_get_stats(pointer)
        image.frame_ms = stats.last_frame_seconds * 1e3
        image.encoding = self.scene.encoding
        return image

    @property
    def stats(self):
        """prepare_seconds, last_frame_ms, triangles, fragments, memory_bytes (libmeso's)."""
        s = lib.meso_renderer_get_stats(self._ptr())
        return {"prepare_seconds": s.prepare_seconds, "last_frame_ms": s.last_frame_seconds * 1e3,
                "triangles": s.triangles, "fragments": s.fragments,
                "memory_bytes": s.memory_bytes}

    @property
    def object_techniques(self):
        """The technique drawing each object (with fallback, not always the one asked)."""
        pointer = self._ptr()
        return [ffi.string(lib.meso_renderer_object_technique(pointer, i)).decode()
                for i in range(len(self.scene.objects))]

    @property
    def threads(self):
        return self._context.threads

    def close(self):
        """Release what the renderer prepared; the scene's objects can be changed again."""
        with self.scene._lock:
            self._handle.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        state = "closed" if self._handle.ptr is None else f"{self.threads} thread(s)"
        return f"meso.Renderer({self.technique or 'scene techniques'}, {state})"
