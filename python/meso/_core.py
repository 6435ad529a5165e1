"""The binding's plumbing: the cffi module, meso.Error, contexts, progress and warnings."""

import os
import threading
import warnings

import numpy as np

from ._meso_cffi import ffi, lib


class Error(Exception):
    """A libmeso call failed. str(error) is meso's one-line message, the text the `meso`
    program prints after "meso: " (it names the file, key or argument, then the reason).

    result      meso's result name: "invalid argument", "malformed input", "cancelled", ...
    bad_input   True when the input is at fault (the program's exit status 2), False when
                the machine is (memory, I/O: status 1)
    """

    def __init__(self, message, result="invalid argument", bad_input=True):
        super().__init__(message)
        self.result = result
        self.bad_input = bad_input


class Warning(UserWarning):  # noqa: A001 (meso.Warning, as meso.Error)
    """A warning libmeso logged (e.g. a constant height map), issued with warnings.warn."""


def error_of(result, message):
    return Error(message, ffi.string(lib.meso_result_string(result)).decode(),
                 bool(lib.meso_result_is_bad_input(result)))


def argument_error(message):
    """meso.Error for a bad argument detected in Python, in meso's "<name>: <reason>" form."""
    return Error(message, "invalid argument", True)


class Progress:
    """Forwards libmeso's progress (label, fraction in [0, 1]) to the user's hook: a callable
    progress(label, fraction) whose true return cancels, or a tqdm-like object with update()
    (its total is set to 100 and it advances in percent). An exception raised by the hook
    cancels the work and is raised again by the call that started it."""

    def __init__(self, hook):
        self.hook = hook
        self.error = None
        self.percent = 0.0
        self.label = None
        self.handle = ffi.new_handle(self)

    def report(self, label, fraction):
        hook = self.hook
        if callable(hook) and not hasattr(hook, "update"):
            return bool(hook(label, fraction))
        if label != self.label:  # a new stage: restart the bar
            self.label = label
            self.percent = 0.0
            if hasattr(hook, "set_description"):
                hook.set_description(label)
            if hasattr(hook, "reset"):
                hook.reset(total=100)
            elif hasattr(hook, "total"):
                hook.total = 100
        percent = 100.0 * min(max(fraction, 0.0), 1.0)
        if percent > self.percent:
            hook.update(percent - self.percent)
            self.percent = percent
        return False


@ffi.def_extern()
def meso_python_progress(user, label, fraction):
    progress = ffi.from_handle(user)
    if progress.error is not None:
        return True
    try:
        return progress.report(ffi.string(label).decode() if label else "", float(fraction))
    except BaseException as exception:  # cancel, and raise it in the caller's thread
        progress.error = exception
        return True


@ffi.def_extern()
def meso_python_log(user, level, message):
    if level == lib.MESO_LOG_WARNING:
        warnings.warn(ffi.string(message).decode(errors="replace"), Warning, stacklevel=2)


class Context:
    """A meso_context: worker threads, the progress hook, the last error's message. Every
    scene, renderer and comparison has its own, so errors never mix between threads."""

    def __init__(self, threads=0, progress=None):
        self.ptr = None
        threads = check_threads(threads)
        desc = ffi.new("meso_context_desc *")
        desc.num_threads = threads
        desc.log = lib.meso_python_log
        desc.progress = lib.MESO_PROGRESS_NEVER
        self.progress = None
        if progress is True:  # the library's own bar on stderr, as `meso --progress`
            desc.progress = lib.MESO_PROGRESS_ALWAYS
        elif progress is not None and progress is not False:
            self.progress = Progress(progress)
            desc.on_progress = lib.meso_python_progress
            desc.progress_user = self.progress.handle
        out = ffi.new("meso_context **")
        if lib.meso_context_create(desc, out) != lib.MESO_OK:
            raise MemoryError("meso: out of memory for a context")
        self.ptr = out[0]

    def check(self, result):
        """Raise meso.Error (or the progress hook's exception) unless result is MESO_OK."""
        if result == lib.MESO_OK:
            return
        if self.progress is not None and self.progress.error is not None:
            error, self.progress.error = self.progress.error, None
            raise error
        message = ffi.string(lib.meso_context_last_error(self.ptr)).decode(errors="replace")
        raise error_of(result, message or ffi.string(lib.meso_result_string(result)).decode())

    def set_threads(self, threads):
        lib.meso_context_set_num_threads(self.ptr, check_threads(threads))

    @property
    def threads(self):
        return lib.meso_context_num_threads(self.ptr)

    def close(self):
        if self.ptr is not None:
            lib.meso_context_destroy(self.ptr)
            self.ptr = None

    __del__ = close


def check_threads(threads):
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 0:
        raise argument_error(f"threads: {threads!r} is not a whole number >= 0 (0: every core)")
    return int(threads)


def fspath(path, name):
    try:
        return os.fsencode(os.fspath(path))
    except TypeError:
        raise argument_error(f"{name}: {path!r} is not a path") from None


class Owned:
    """A C object and its destructor; `keep` holds what must outlive it (its context, the scene
    a renderer draws). Destroyed by close() or when the last reference goes, before `keep`."""

    __slots__ = ("ptr", "destroy", "keep", "__weakref__")

    def __init__(self, ptr, destroy, *keep):
        self.ptr = ptr
        self.destroy = destroy
        self.keep = keep

    def close(self):
        if self.ptr is not None:
            ptr, self.ptr = self.ptr, None
            self.destroy(ptr)
        self.keep = ()

    __del__ = close


def float32_view(array):
    """A C float pointer to a C-contiguous float32 array (no copy); the array must outlive it."""
    return ffi.cast("float *", ffi.from_buffer(array))


def image_view(array):
    """A meso_image struct over a (H, W) or (H, W, C) C-contiguous float32 array (no copy)."""
    image = ffi.new("meso_image *")
    image.height, image.width = array.shape[0], array.shape[1]
    image.channels = 1 if array.ndim == 2 else array.shape[2]
    image.pixels = float32_view(array)
    return image


def aligned_empty(shape, fill):
    """A float32 array of `shape` whose data starts on a 64-byte boundary (the rasterizer's
    framebuffer rows, as meso_framebuffer_create aligns them), filled with `fill` unless None."""
    count = int(np.prod(shape))
    raw = np.empty(count + 16, dtype=np.float32)
    skip = (-raw.ctypes.data % 64) // 4
    array = raw[skip:skip + count].reshape(shape)
    if fill is not None:
        array.fill(fill)
    return array


lock = threading.Lock()  # guards the module's caches (techniques)
