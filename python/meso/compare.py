"""meso.compare: the metrics of `meso compare` (docs/compare.md) on images, arrays or files."""

import math
import os

import numpy as np

from ._core import Context, Owned, argument_error, ffi, fspath, image_view, lib
from .render import Image


def load_image(path):
    """A PNG's values as libmeso loads them (float32 (height, width, channels) in [0, 1], no
    colour conversion: an sRGB file gives its sRGB values), for compare() and plots."""
    context = Context()
    out = ffi.new("meso_image **")
    context.check(lib.meso_image_load_png(context.ptr, fspath(path, "path"), out))
    image = Owned(out[0], lib.meso_image_destroy)
    return _copy_image(image.ptr)


def _copy_image(image):
    count = image.width * image.height * image.channels
    values = np.frombuffer(ffi.buffer(image.pixels, 4 * count), dtype=np.float32)
    shape = (image.height, image.width) + ((image.channels,) if image.channels > 1 else ())
    return values.reshape(shape).copy()


def _coverage_beside(path):
    """x.png -> x.coverage.png when it exists (as `meso compare` finds masks)."""
    text = os.fspath(path)
    stem = text[:-4] if text.endswith(".png") else text
    candidate = stem + ".coverage.png"
    return candidate if os.access(candidate, os.R_OK) else None


def _operand(value, name):
    """(colour array, coverage array or None) of an Image, an array or a PNG path."""
    if isinstance(value, Image):
        return value.rgb, value.coverage
    if isinstance(value, (str, bytes, os.PathLike)):
        mask = _coverage_beside(value)
        return load_image(value), (load_image(mask) if mask else None)
    array = np.asarray(value)
    if array.ndim not in (2, 3) or array.dtype.kind != "f" or 0 in array.shape[:2]:
        raise argument_error(f"compare: {name}: must be a meso.Image, a PNG path or a float "
                             f"array (height, width[, channels]), not {array.dtype} "
                             f"{array.shape}")
    return np.ascontiguousarray(array, dtype=np.float32), None


def compare(a, b, diff_scale=0.25, background=(0.0, 0.0, 0.0)):
    """Compare image a with image b (usually the reference) as `meso compare A B --json`:
    a dict of psnr, psnr_identical, psnr_covered, rmse, rmse_covered, ssim, max_error,
    coverage_iou, covered_both, covered_only_a, covered_only_b, coverage_from, width, height,
    and diff, the false-colour difference (float32 (height, width, 3): black 0 through blue,
    green, yellow to red at diff_scale).

    a, b  meso.Image (colour and coverage as rendered, linear), PNG paths (values as stored;
          A.coverage.png beside A is its mask, as for the program) or float arrays.
    Coverage comes from both masks, or when either lacks one, from the pixels that differ
    from `background`. PSNR is inf for identical images, psnr_covered nan when no pixel is
    covered by both (the program's JSON writes null for both)."""
    color_a, mask_a = _operand(a, "a")
    color_b, mask_b = _operand(b, "b")
    if color_a.shape[:2] != color_b.shape[:2]:
        raise argument_error(f"compare: a is {color_a.shape[1]}x{color_a.shape[0]} but b is "
                             f"{color_b.shape[1]}x{color_b.shape[0]}")
    if not (isinstance(diff_scale, (int, float)) and 1e-6 <= diff_scale <= 1e6):
        raise argument_error(f"compare: diff_scale: must be in [1e-6, 1e6], not {diff_scale!r}")
    for name, mask in (("a", mask_a), ("b", mask_b)):
        if mask is not None and mask.shape[:2] != color_a.shape[:2]:
            raise argument_error(f"compare: {name}'s coverage is {mask.shape[1]}x"
                                 f"{mask.shape[0]} but the images are {color_a.shape[1]}x"
                                 f"{color_a.shape[0]}")
    with_masks = mask_a is not None and mask_b is not None
    context = Context()
    image_a, image_b = image_view(color_a), image_view(color_b)
    desc = ffi.new("meso_compare_desc *")
    keep = []
    if with_masks:
        mask_a, mask_b = (np.ascontiguousarray(m, dtype=np.float32) for m in (mask_a, mask_b))
        keep = [image_view(mask_a), image_view(mask_b)]
        desc.coverage_a, desc.coverage_b = keep
    desc.background = [float(c) for c in background]
    result = ffi.new("meso_compare_result *")
    context.check(lib.meso_image_compare(context.ptr, image_a, image_b, desc, result))
    out = ffi.new("meso_image **")
    context.check(lib.meso_image_diff(context.ptr, image_a, image_b, float(diff_scale), out))
    diff_image = Owned(out[0], lib.meso_image_destroy)
    diff = _copy_image(diff_image.ptr)
    diff_image.close()
    del keep
    r = result[0]
    return {
        "width": color_a.shape[1], "height": color_a.shape[0],
        "psnr": r.psnr, "psnr_identical": math.isinf(r.psnr), "psnr_covered": r.psnr_covered,
        "rmse": r.rmse, "rmse_covered": r.rmse_covered, "ssim": r.ssim,
        "max_error": r.max_error, "coverage_iou": r.coverage_iou,
        "covered_both": r.covered_both, "covered_only_a": r.covered_only_a,
        "covered_only_b": r.covered_only_b,
        "coverage_from": "masks" if with_masks else "background colour",
        "diff": diff,
    }
