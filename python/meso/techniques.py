"""meso.techniques(): the registry and option tables `meso help TECHNIQUE` prints."""

from collections import namedtuple

from ._core import ffi, lib, lock

Option = namedtuple("Option", "name type default min max help")
Option.__doc__ = """One row of a technique's option table: type "int", "bool" or "float";
default, min and max (inclusive) in that type; help, the line `meso help` prints."""

Technique = namedtuple("Technique", "name summary paper kind accepts options")
Technique.__doc__ = """A technique: kind "per_pixel", "geometry" or "reference"; accepts, the
set of mesostructure it draws ("none", "height_field", "solid"); options, {name: Option}."""

_KINDS = {lib.MESO_TECHNIQUE_PER_PIXEL: "per_pixel", lib.MESO_TECHNIQUE_GEOMETRY: "geometry",
          lib.MESO_TECHNIQUE_REFERENCE: "reference"}
_TYPES = {lib.MESO_OPTION_INT: ("int", int), lib.MESO_OPTION_BOOL: ("bool", bool),
          lib.MESO_OPTION_FLOAT: ("float", float)}
_ACCEPTS = ((lib.MESO_TECHNIQUE_ACCEPTS_NONE, "none"),
            (lib.MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD, "height_field"),
            (lib.MESO_TECHNIQUE_ACCEPTS_SOLID, "solid"))
_cache = None


def _text(pointer):
    return ffi.string(pointer).decode() if pointer != ffi.NULL else ""


def _read():
    result = {}
    for index in range(lib.meso_technique_count()):
        info = lib.meso_technique_get(index)
        options = {}
        for k in range(info.num_options):
            row = info.options[k]
            type_name, convert = _TYPES[row.type]
            options[_text(row.name)] = Option(_text(row.name), type_name,
                                              convert(row.default_value), convert(row.min),
                                              convert(row.max), _text(row.doc))
        accepts = frozenset(name for flag, name in _ACCEPTS if info.accepts & flag)
        result[_text(info.name)] = Technique(_text(info.name), _text(info.summary),
                                             _text(info.paper), _KINDS[info.kind], accepts,
                                             options)
    return result


def techniques():
    """{name: Technique} in the registry's order (flat, bump, ..., reference)."""
    global _cache
    with lock:
        if _cache is None:
            _cache = _read()
        return dict(_cache)


def technique_isa():
    """The instruction set the techniques run with: "avx2", "baseline" or "native" (the
    images are the same bits in each case)."""
    return _text(lib.meso_technique_isa())
