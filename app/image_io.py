"""Image files: HDR maps in, rendered images out. Linear HDR for .exr, .hdr and .pfm; tonemapped
8-bit sRGB for .png and .jpg. OpenEXR's own bindings handle .exr, OpenCV the rest (its wheels
carry no EXR codec). Every write is atomic: the image goes to a temporary file beside the
target, which is renamed over it only once complete.

OpenCV and OpenEXR are imported where they are used, so that the core (scenes with constant
environments, the renderer, the benchmarks) runs with NumPy and PyOpenCL alone."""

import os
import tempfile
from pathlib import Path

import numpy as np

from app.errors import UserError
from app.tonemap import tonemap, to_8bit

HDR_FORMATS = (".exr", ".hdr", ".pfm")
LDR_FORMATS = (".png", ".jpg", ".jpeg")


def read_hdr(path: Path, where: str) -> np.ndarray:
    """A Radiance .hdr, OpenEXR or PFM image as linear float32 RGB, (H, W, 3)."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{where}: environment map '{path}' does not exist")
    rgb = _read_exr(path) if path.suffix.lower() == ".exr" else _read_with_opencv(path)
    if rgb is None:
        raise UserError(f"{where}: '{path}' is not a readable HDR image (.hdr, .exr or .pfm)")
    if not np.all(np.isfinite(rgb)) or rgb.min() < 0:
        raise UserError(f"{where}: '{path}' holds negative, NaN or infinite pixels")
    return rgb


def _read_with_opencv(path: Path):
    import cv2
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED | cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)
    if image is None or image.ndim != 3 or image.dtype not in (np.float32, np.float16):
        return None
    return np.ascontiguousarray(image[..., 2::-1], np.float32)


def _read_exr(path: Path):
    import OpenEXR
    try:
        with OpenEXR.File(str(path)) as f:
            channels = f.channels()
            if "RGB" in channels:
                rgb = channels["RGB"].pixels
            elif all(c in channels for c in "RGB"):
                rgb = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
            else:
                return None
    except Exception:   # the bindings raise bare exceptions for unreadable files
        return None
    return np.ascontiguousarray(rgb[..., :3], np.float32)


def _write_exr(path: str, rgb: np.ndarray):
    import OpenEXR
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {"RGB": np.ascontiguousarray(rgb, np.float32)}) as f:
        f.write(path)
    return True


def check_writable(path: Path, what: str = "--output", formats=HDR_FORMATS + LDR_FORMATS):
    """Fails early, before any rendering, if `path` cannot be written (or, where `formats` is
    given, has none of those suffixes)."""
    path = Path(path)
    if formats and path.suffix.lower() not in formats:
        raise UserError(f"{what}: '{path}' has an unknown image format (use one of {', '.join(formats)})")
    if not path.parent.is_dir():
        raise UserError(f"{what}: folder '{path.parent}' does not exist")
    try:   # the only sure test (permissions, read-only mounts, root's exceptions) is to try
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise UserError(f"{what}: '{path}' is not writable ({e.strerror})") from None
    if path.is_dir() or (path.exists() and not os.access(path, os.W_OK)):
        raise UserError(f"{what}: '{path}' is not writable")


def write_atomically(path: Path, write, what: str, errors=(OSError,)):
    """Calls write(temporary_path) -> success for a temporary file beside `path` (same suffix,
    so format-sniffing writers choose right), then renames it over `path`; on any failure the
    temporary file is removed and `path` is left as it was."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        try:
            ok = write(tmp)
        except errors as e:
            raise UserError(f"{what}: cannot write '{path}': {e}") from None
        if not ok:
            raise UserError(f"{what}: cannot write '{path}'")
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text(path: Path, text: str, what: str = "--json"):
    check_writable(path, what, formats=None)

    def write(tmp):
        Path(tmp).write_text(text)
        return True
    write_atomically(path, write, what)


def write_image(path: Path, linear: np.ndarray, exposure: float = 0.0, curve: str = "standard",
                what: str = "--output"):
    """Writes (H, W, 3) linear radiance: as is for HDR formats, tonemapped for PNG and JPEG."""
    import cv2
    path = Path(path)
    check_writable(path, what)
    suffix = path.suffix.lower()
    if suffix == ".exr":
        write_atomically(path, lambda tmp: _write_exr(tmp, linear), what, errors=(OSError, RuntimeError))
        return
    if suffix in HDR_FORMATS:
        data = np.ascontiguousarray(linear[..., ::-1], np.float32)
    else:
        data = np.ascontiguousarray(to_8bit(tonemap(linear, exposure, curve))[..., ::-1])
    write_atomically(path, lambda tmp: cv2.imwrite(tmp, data), what, errors=(cv2.error, OSError))
