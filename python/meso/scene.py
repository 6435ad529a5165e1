"""meso.Scene: a scene file or dict made into libmeso's meso_scene, with its camera, lights and
objects readable and settable in place."""

import json
import math
import threading
import weakref

import numpy as np

from . import arrays
from ._core import Context, Owned, argument_error, ffi, fspath, lib

_KIND_NAMES = {
    lib.MESO_MESOSTRUCTURE_NONE: None,
    lib.MESO_MESOSTRUCTURE_HEIGHT_FIELD: "height_field",
    lib.MESO_MESOSTRUCTURE_SOLID: "solid",
}
_WRAP_NAMES = {lib.MESO_WRAP_DEFAULT: "repeat", lib.MESO_WRAP_REPEAT: "repeat",
               lib.MESO_WRAP_CLAMP: "clamp"}


def _vec3(value):
    return (value.x, value.y, value.z)


def _finite3(where, value, non_negative=False):
    try:
        x, y, z = (float(c) for c in value)
    except (TypeError, ValueError):
        raise argument_error(f"{where}: must be 3 numbers, not {value!r}") from None
    if not all(math.isfinite(c) for c in (x, y, z)):
        raise argument_error(f"{where}: must be finite, not {value!r}")
    if non_negative and min(x, y, z) < 0:
        raise argument_error(f"{where}: must be >= 0, not {value!r}")
    return (x, y, z)


def _set_vec3(target, value):
    target.x, target.y, target.z = value


def _keep_alive_array(pointer, count, dtype, shape, owner):
    """A read-only NumPy view of `count` items at a C pointer, which keeps `owner` (the scene's
    C handle) alive as long as the view lives: no copy, no dangling pointer."""
    if pointer == ffi.NULL or count == 0:
        return None
    itemsize = np.dtype(dtype).itemsize
    keeper = ffi.gc(ffi.cast("char *", pointer), lambda _, owner=owner: None)
    array = np.frombuffer(ffi.buffer(keeper, count * itemsize), dtype=dtype).reshape(shape)
    array.flags.writeable = False
    return array


class Camera:
    """The scene's camera (a view of the C struct): eye, target, up (3-tuples) and fov_y_deg.
    Set any of them (scene.camera.eye = (0, 1, 2)) or several at once with set(); a renderer
    reads the camera at the start of every frame."""

    __slots__ = ("_scene",)

    def __init__(self, scene):
        self._scene = scene

    def _struct(self):
        return self._scene._ptr.camera

    eye = property(lambda self: _vec3(self._struct().eye),
                   lambda self, value: self.set(eye=value))
    target = property(lambda self: _vec3(self._struct().target),
                      lambda self, value: self.set(target=value))
    up = property(lambda self: _vec3(self._struct().up), lambda self, value: self.set(up=value))
    fov_y_deg = property(lambda self: self._struct().fov_y_deg,
                         lambda self, value: self.set(fov_y_deg=value))

    def set(self, eye=None, target=None, up=None, fov_y_deg=None):
        """Change several fields at once, checked as the scene loader checks "camera"."""
        eye = _finite3("camera.eye", self.eye if eye is None else eye)
        target = _finite3("camera.target", self.target if target is None else target)
        up = _finite3("camera.up", self.up if up is None else up)
        fov = self.fov_y_deg if fov_y_deg is None else fov_y_deg
        try:
            fov = float(fov)
        except (TypeError, ValueError):
            raise argument_error(f"camera.fov_y_deg: must be a number, not {fov!r}") from None
        if not 0.0 < fov < 180.0:
            raise argument_error(f"camera.fov_y_deg: must be in (0, 180), not {fov:g}")
        view = np.subtract(target, eye, dtype=np.float32)
        length = float(np.linalg.norm(view))
        if length <= 1e-6:
            raise argument_error("camera.target: must differ from the eye")
        up_length = float(np.linalg.norm(np.asarray(up, np.float32)))
        side = np.cross(view / length, np.asarray(up, np.float32) / max(up_length, 1e-30))
        if up_length == 0.0 or float(np.linalg.norm(side)) <= 1e-4:
            raise argument_error("camera.up: must not be zero or along the view direction")
        with self._scene._lock:
            struct = self._struct()
            _set_vec3(struct.eye, eye)
            _set_vec3(struct.target, target)
            _set_vec3(struct.up, up)
            struct.fov_y_deg = fov

    def as_dict(self):
        return {"eye": list(self.eye), "target": list(self.target), "up": list(self.up),
                "fov_y_deg": self.fov_y_deg}

    def __repr__(self):
        return f"meso.Camera({self.as_dict()})"


class Light:
    """One light of the scene (a view of the C struct): type "directional" (direction toward
    the light, kept unit) or "point" (position), and color (linear RGB intensity)."""

    __slots__ = ("_scene", "_index")

    def __init__(self, scene, index):
        self._scene, self._index = scene, index

    def _struct(self):
        return self._scene._ptr.lights[self._index]

    @property
    def type(self):
        return "point" if self._struct().type == lib.MESO_LIGHT_POINT else "directional"

    direction = property(lambda self: _vec3(self._struct().direction),
                         lambda self, value: self._set(direction=value))
    position = property(lambda self: _vec3(self._struct().position),
                        lambda self, value: self._set(position=value))
    color = property(lambda self: _vec3(self._struct().color),
                     lambda self, value: self._set(color=value))

    def _set(self, direction=None, position=None, color=None):
        where = f"lights[{self._index}]"
        values = _check_light(where, self.type, direction, position, color)
        with self._scene._lock:
            struct = self._struct()
            for field, value in values.items():
                _set_vec3(getattr(struct, field), value)

    def as_dict(self):
        d = {"type": self.type, "color": list(self.color)}
        if self.type == "point":
            d["position"] = list(self.position)
        else:
            d["direction"] = list(self.direction)
        return d

    def __repr__(self):
        return f"meso.Light({self.as_dict()})"


def _check_light(where, kind, direction, position, color):
    values = {}
    if direction is not None:
        if kind != "directional":
            raise argument_error(f"{where}.direction: a {kind} light has no direction")
        d = np.asarray(_finite3(f"{where}.direction", direction), dtype=np.float32)
        length = float(np.linalg.norm(d))
        if length <= 1e-12:
            raise argument_error(f"{where}.direction: must not be zero")
        values["direction"] = tuple(float(c) for c in d / np.float32(length))
    if position is not None:
        if kind != "point":
            raise argument_error(f"{where}.position: a {kind} light has no position")
        values["position"] = _finite3(f"{where}.position", position)
    if color is not None:
        values["color"] = _finite3(f"{where}.color", color, non_negative=True)
    return values


class Lights:
    """The scene's lights: a sequence of Light views; assign a list of dicts to replace them
    all (scene.lights = [{"type": "directional", "direction": (1, 1, 0)}])."""

    __slots__ = ("_scene",)

    def __init__(self, scene):
        self._scene = scene

    def __len__(self):
        return self._scene._ptr.num_lights

    def __getitem__(self, index):
        count = len(self)
        if isinstance(index, slice):
            return [Light(self._scene, i) for i in range(count)[index]]
        if not -count <= index < count:
            raise IndexError(f"lights[{index}]: the scene has {count} lights")
        return Light(self._scene, index % count)

    def __repr__(self):
        return f"meso.Lights({[light.as_dict() for light in self]})"


def _replace_lights(scene, lights):
    lights = list(lights)
    if len(lights) > lib.MESO_SCENE_MAX_LIGHTS:
        raise argument_error(f"lights: {len(lights)} lights exceed the limit of "
                             f"{lib.MESO_SCENE_MAX_LIGHTS}")
    checked = []
    for index, light in enumerate(lights):
        where = f"lights[{index}]"
        if isinstance(light, Light):
            light = light.as_dict()
        if not isinstance(light, dict):
            raise argument_error(f"{where}: must be a dict, not {light!r}")
        unknown = set(light) - {"type", "direction", "position", "color"}
        if unknown:
            raise argument_error(f"{where}.{sorted(unknown)[0]}: unknown key")
        kind = light.get("type")
        if kind not in ("directional", "point"):
            raise argument_error(f"{where}.type: must be \"directional\" or \"point\", "
                                 f"not {kind!r}")
        needed = "direction" if kind == "directional" else "position"
        if needed not in light:
            raise argument_error(f"{where}.{needed}: missing")
        values = _check_light(where, kind, light.get("direction"), light.get("position"),
                              light.get("color", (1.0, 1.0, 1.0)))
        checked.append((kind, values))
    with scene._lock:
        for index, (kind, values) in enumerate(checked):
            struct = scene._ptr.lights[index]
            struct.type = lib.MESO_LIGHT_POINT if kind == "point" else lib.MESO_LIGHT_DIRECTIONAL
            for field, value in values.items():
                _set_vec3(getattr(struct, field), value)
        scene._ptr.num_lights = len(checked)


class Object:
    """One object of the scene (a view of the C struct). Readable: name, technique, options,
    albedo, specular, shininess, mesostructure, height_field (a read-only array), mesh (read-
    only arrays). Settable while no renderer of the scene is open (a renderer prepares its
    objects once): technique, options, albedo, specular, shininess, height_field."""

    __slots__ = ("_scene", "_index")

    def __init__(self, scene, index):
        self._scene, self._index = scene, index

    def _struct(self):
        return self._scene._ptr.objects[self._index]

    def _where(self, field):
        return f"objects[{self._index}].{field}"

    def _check_editable(self, field):
        count = self._scene.open_renderers
        if count:
            raise argument_error(
                f"{self._where(field)}: the scene has {count} open renderer(s), prepared from "
                f"its objects; close them (Renderer.close, or a with block) first")

    @property
    def name(self):
        return ffi.string(self._struct().name).decode()

    @property
    def technique(self):
        return ffi.string(self._struct().technique).decode()

    @technique.setter
    def technique(self, name):
        self._check_editable("technique")
        if not isinstance(name, str) or lib.meso_technique_find(name.encode()) == ffi.NULL:
            from .techniques import techniques
            raise argument_error(f"{self._where('technique')}: unknown technique {name!r} "
                                 f"(known: {', '.join(techniques())})")
        with self._scene._lock:
            self._struct().technique = name.encode()

    @property
    def options(self):
        """{technique: {name: value}}; technique "" is the flat form (the object's own)."""
        struct = self._struct()
        result = {}
        for k in range(struct.num_options):
            option = struct.options[k]
            technique = ffi.string(option.technique).decode()
            result.setdefault(technique, {})[ffi.string(option.name).decode()] = option.value
        return result

    @options.setter
    def options(self, options):
        self._check_editable("options")
        flat = _flatten_options(self._scene._context, self._where("technique_options"),
                                options, allow_flat=True)
        if len(flat) > lib.MESO_OPTIONS_MAX:
            raise argument_error(f"{self._where('technique_options')}: {len(flat)} options "
                                 f"exceed the limit of {lib.MESO_OPTIONS_MAX}")
        with self._scene._lock:
            struct = self._struct()
            for k, (technique, name, value) in enumerate(flat):
                struct.options[k].technique = technique.encode()
                struct.options[k].name = name.encode()
                struct.options[k].value = value
            struct.num_options = len(flat)

    def _material_vec3(self, field, value):
        self._check_editable(f"material.{field}")
        value = _finite3(self._where(f"material.{field}"), value, non_negative=True)
        with self._scene._lock:
            _set_vec3(getattr(self._struct().material, field), value)

    albedo = property(lambda self: _vec3(self._struct().material.albedo),
                      lambda self, value: self._material_vec3("albedo", value))
    specular = property(lambda self: _vec3(self._struct().material.specular),
                        lambda self, value: self._material_vec3("specular", value))

    @property
    def shininess(self):
        return self._struct().material.shininess

    @shininess.setter
    def shininess(self, value):
        self._check_editable("material.shininess")
        if not isinstance(value, (int, float, np.number)) or not math.isfinite(value) or value <= 0:
            raise argument_error(f"{self._where('material.shininess')}: must be a finite "
                                 f"number > 0, not {value!r}")
        with self._scene._lock:
            self._struct().material.shininess = float(value)

    @property
    def mesostructure(self):
        """{"kind": "height_field" | "solid" | None, "source", "depth", "wrap"}."""
        m = self._struct().mesostructure
        return {"kind": _KIND_NAMES.get(m.kind), "source": ffi.string(m.source).decode(),
                "depth": m.depth, "wrap": _WRAP_NAMES.get(m.wrap, "repeat")}

    @property
    def height_field(self):
        """The heights (height, width) float32, read-only and without a copy; None when the
        object's mesostructure is not a height field."""
        hf = self._struct().mesostructure.height_field
        if self._struct().mesostructure.kind != lib.MESO_MESOSTRUCTURE_HEIGHT_FIELD or \
                hf == ffi.NULL:
            return None
        return _keep_alive_array(hf.heights, hf.width * hf.height, np.float32,
                                 (hf.height, hf.width), self._scene._handle)

    @height_field.setter
    def height_field(self, field):
        self._check_editable("height_field")
        if isinstance(field, np.ndarray):
            field = arrays.HeightField(field, wrap=self.mesostructure["wrap"])
        if not isinstance(field, arrays.HeightField):
            raise argument_error(f"{self._where('height_field')}: must be a meso.HeightField "
                                 f"or an array, not {type(field).__name__}")
        struct = self._struct()
        if struct.mesostructure.kind != lib.MESO_MESOSTRUCTURE_HEIGHT_FIELD:
            raise argument_error(f"{self._where('height_field')}: the object's mesostructure "
                                 f"is not a height field")
        wrap = lib.MESO_WRAP_CLAMP if field.wrap == "clamp" else lib.MESO_WRAP_REPEAT
        context = self._scene._context
        out = ffi.new("meso_heightfield **")
        context.check(lib.meso_heightfield_create_from_image(context.ptr, field._image(), wrap,
                                                             out))
        with self._scene._lock:
            old = struct.mesostructure.height_field
            struct.mesostructure.height_field = out[0]
            struct.mesostructure.wrap = wrap
            struct.mesostructure.source = (field.name or "array").encode()[:63]
            # the old field may still be read through views handed out: freed with the scene
            self._scene._retired.append(Owned(old, lib.meso_heightfield_destroy))

    @property
    def mesh(self):
        """The world-space mesh as read-only arrays without a copy: positions, normals (N, 3),
        uvs (N, 2) or None, indices (M, 3)."""
        mesh = self._struct().mesh
        handle = self._scene._handle
        n, m = mesh.num_vertices, mesh.num_triangles
        return {
            "positions": _keep_alive_array(mesh.positions, 3 * n, np.float32, (n, 3), handle),
            "normals": _keep_alive_array(mesh.normals, 3 * n, np.float32, (n, 3), handle),
            "uvs": _keep_alive_array(mesh.uvs, 2 * n, np.float32, (n, 2), handle),
            "indices": _keep_alive_array(mesh.indices, 3 * m, np.uint32, (m, 3), handle),
        }

    def __repr__(self):
        return (f"meso.Object({self.name!r}, technique={self.technique!r}, "
                f"mesostructure={self.mesostructure})")


def _flatten_options(context, where, options, allow_flat=False, technique=None):
    """{technique: {name: value}} (or {name: value} for `technique` / the flat form) as
    (technique, name, value) rows, each checked against its technique's option table."""
    if options is None:
        return []
    if not isinstance(options, dict):
        raise argument_error(f"{where}: must be a dict {{technique: {{name: value}}}}, "
                             f"not {type(options).__name__}")
    rows = []
    for key, value in options.items():
        if isinstance(value, dict):
            for name, number in value.items():
                rows.append((key, name, number))
        elif technique is not None:
            rows.append((technique, key, value))
        elif allow_flat:
            rows.append(("", key, value))
        else:
            raise argument_error(f"{where}.{key}: must be a dict of {key}'s options "
                                 f"(or give technique=)")
    checked = []
    for tech, name, value in rows:
        if isinstance(value, (bool, np.bool_)):
            value = 1.0 if value else 0.0
        if not isinstance(value, (int, float, np.number)):
            raise argument_error(f"{where}.{tech}.{name}: must be a number or a bool, "
                                 f"not {value!r}")
        if not isinstance(tech, str) or not isinstance(name, str):
            raise argument_error(f"{where}: keys must be strings")
        if len(tech.encode()) >= lib.MESO_NAME_MAX or len(name.encode()) >= lib.MESO_NAME_MAX:
            raise argument_error(f"{where}.{tech}.{name}: longer than "
                                 f"{lib.MESO_NAME_MAX - 1} bytes")
        if tech:
            label = f"{where}.{tech}.{name}".encode()
            context.check(lib.meso_technique_check_option(context.ptr, tech.encode(),
                                                          name.encode(), float(value), label))
        checked.append((tech, name, float(value)))
    return checked


_RESOURCE_KEYS = {"height_map": arrays.HeightField, "color_map": arrays.ColorMap,
                  "normal_map": arrays.NormalMap, "solid": arrays.TileMesh}


class _Resources:
    """The arrays a dict holds where a scene file names files, given to meso_scene_create."""

    def __init__(self, scene_name):
        self.scene_name = scene_name
        self.items = []  # (name, data)
        self.by_id = {}

    def name_of(self, data):
        if id(data) not in self.by_id:
            name = data.name or f"<{type(data).__name__} {len(self.items)}>"
            if any(name == existing for existing, _ in self.items):
                name = f"{name} ({len(self.items)})"
            self.by_id[id(data)] = name
            self.items.append((name, data))
        return self.by_id[id(data)]

    def replace(self, value, path):
        """`value` with every array object replaced by its resource name."""
        if isinstance(value, dict):
            out = {}
            for key, item in value.items():
                where = f"{path}.{key}" if path else str(key)
                if key in _RESOURCE_KEYS and isinstance(item, np.ndarray) and key != "solid":
                    item = (_RESOURCE_KEYS[key](item, wrap=value.get("wrap", "repeat"))
                            if key == "height_map" else _RESOURCE_KEYS[key](item))
                if isinstance(item, arrays.HeightField):
                    wrap = value.get("wrap")
                    if wrap is not None and wrap != item.wrap:
                        raise argument_error(f"{self.scene_name}: {path}.wrap: {wrap!r} "
                                             f"contradicts the HeightField's wrap "
                                             f"{item.wrap!r}")
                    out.setdefault("wrap", item.wrap)
                out[key] = self.replace(item, where)
            if "wrap" in value:
                out["wrap"] = value["wrap"]
            return out
        if isinstance(value, (list, tuple)):
            return [self.replace(item, f"{path}[{k}]") for k, item in enumerate(value)]
        if isinstance(value, (arrays.HeightField, arrays.ColorMap, arrays.TileMesh)):
            return self.name_of(value)
        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, np.generic):
            return value.item()
        return value

    def to_c(self):
        keep = []
        if not self.items:
            return ffi.NULL, 0, keep
        resources = ffi.new("meso_scene_resource[]", len(self.items))
        for k, (name, data) in enumerate(self.items):
            arrays.fill_resource(resources[k], name, data, keep)
        keep.append(resources)
        return resources, len(self.items), keep


class Scene:
    """A scene (docs/scene-format.md) in libmeso. Make one with Scene.load(path) or
    Scene.from_dict(d, base_dir); render it with scene.render(...) or a Renderer.

    Threads: a scene's renderers draw one frame at a time; setting the camera, lights or
    objects waits for the frame that is drawing."""

    def __init__(self, *args, **kwargs):
        raise TypeError("use meso.Scene.load(path) or meso.Scene.from_dict(d, base_dir)")

    @classmethod
    def _adopt(cls, context, pointer, keep=()):
        scene = cls.__new__(cls)
        scene._context = context
        scene._retired = []
        # destroyed after every renderer (they keep the handle), before the context and the
        # height fields replaced by Object.height_field (views may still read those)
        scene._handle = Owned(pointer, lib.meso_scene_destroy, context, scene._retired, keep)
        scene._ptr = pointer
        scene._lock = threading.RLock()
        scene._renderers = weakref.WeakSet()
        return scene

    @classmethod
    def load(cls, path, progress=None):
        """Load a scene file; relative paths inside resolve against its folder. Raises
        meso.Error with the message `meso render` prints ("scene.json: objects[0].technique:
        unknown technique 'relif' ..."). progress: see meso.Renderer."""
        context = Context(progress=progress)
        out = ffi.new("meso_scene **")
        context.check(lib.meso_scene_load(context.ptr, fspath(path, "path"), out))
        return cls._adopt(context, out[0])

    @classmethod
    def from_dict(cls, d, base_dir=".", name="scene", progress=None):
        """A scene from a dict shaped like a scene file. Where the file names a PNG or a tile
        mesh ("height_map", "color_map", "normal_map", "solid"), the dict may hold a
        meso.HeightField, ColorMap, NormalMap or TileMesh (or a NumPy array for the maps);
        libmeso converts them as it converts those files. Relative paths resolve against
        base_dir; `name` names the scene in messages."""
        if not isinstance(d, dict):
            raise argument_error(f"{name}: must be a dict, not {type(d).__name__}")
        resources = _Resources(name)
        plain = resources.replace(d, "")
        try:
            text = json.dumps(plain, indent=1, allow_nan=False)
        except ValueError as error:
            raise argument_error(f"{name}: {error} (NaN and infinity are not JSON numbers)") \
                from None
        except TypeError as error:
            raise argument_error(f"{name}: {error}") from None
        context = Context(progress=progress)
        c_resources, count, keep = resources.to_c()
        desc = ffi.new("meso_scene_desc *")
        text_c, name_c = ffi.new("char[]", text.encode()), ffi.new("char[]", name.encode())
        base_c = ffi.new("char[]", fspath(base_dir, "base_dir"))
        desc.json, desc.name, desc.base_dir = text_c, name_c, base_c
        desc.resources, desc.num_resources = c_resources, count
        out = ffi.new("meso_scene **")
        context.check(lib.meso_scene_create(context.ptr, desc, out))
        return cls._adopt(context, out[0])

    # ---- what the scene holds -------------------------------------------------------------

    @property
    def path(self):
        return ffi.string(self._ptr.path).decode(errors="replace")

    @property
    def size(self):
        """(width, height) of the scene's image: what render() draws unless given a size."""
        return (self._ptr.width, self._ptr.height)

    @size.setter
    def size(self, value):
        from .render import check_size
        width, height = check_size(value)
        with self._lock:
            self._ptr.width, self._ptr.height = width, height

    @property
    def encoding(self):
        return "linear" if self._ptr.encoding == lib.MESO_ENCODING_LINEAR else "srgb"

    background = property(lambda self: _vec3(self._ptr.background),
                          lambda self, value: self._set_vec3("background", value))
    ambient = property(lambda self: _vec3(self._ptr.ambient),
                       lambda self, value: self._set_vec3("ambient", value))

    def _set_vec3(self, field, value):
        value = _finite3(field, value, non_negative=True)
        with self._lock:
            _set_vec3(getattr(self._ptr, field), value)

    @property
    def camera(self):
        return Camera(self)

    @camera.setter
    def camera(self, value):
        if isinstance(value, Camera):
            value = value.as_dict()
        if not isinstance(value, dict) or set(value) - {"eye", "target", "up", "fov_y_deg"}:
            raise argument_error("camera: must be a dict of eye, target, up, fov_y_deg")
        Camera(self).set(**value)

    @property
    def lights(self):
        return Lights(self)

    @lights.setter
    def lights(self, value):
        _replace_lights(self, value)

    @property
    def objects(self):
        return tuple(Object(self, i) for i in range(self._ptr.num_objects))

    @property
    def open_renderers(self):
        return sum(1 for renderer in list(self._renderers) if renderer._handle.ptr is not None)

    # ---- rendering --------------------------------------------------------------------------

    def renderer(self, technique=None, samples=1, options=None, threads=0, progress=None,
                 fallback=False, wireframe=False, frame_progress=False):
        """A meso.Renderer of this scene (prepared once, for many frames)."""
        from .render import Renderer
        return Renderer(self, technique=technique, samples=samples, options=options,
                        threads=threads, progress=progress, fallback=fallback,
                        wireframe=wireframe, frame_progress=frame_progress)

    def render(self, technique=None, size=None, samples=1, options=None, threads=0,
               progress=None, fallback=False, wireframe=False):
        """One frame: prepare (bake what the technique needs, from the bake cache when it
        holds it), draw, and return a meso.Image. technique None: each object's own;
        size (width, height), None: the scene's; options {technique: {name: value}}
        (meso help TECHNIQUE); threads 0: every core; progress: a hook as in meso.Renderer,
        which also follows the frame."""
        with self.renderer(technique, samples, options, threads, progress, fallback,
                           wireframe, frame_progress=progress is not None) as renderer:
            return renderer.render(size)

    def __repr__(self):
        return (f"meso.Scene({self.path!r}, {self.size[0]}x{self.size[1]}, "
                f"{len(self.objects)} object(s), {len(self.lights)} light(s))")
