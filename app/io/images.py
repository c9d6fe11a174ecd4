"""Image files: HDR maps in, rendered images out. Linear HDR for .exr, .hdr and .pfm; tonemapped
8-bit sRGB for .png and .jpg. OpenEXR's own bindings handle .exr, OpenCV the rest (its wheels
carry no EXR codec). Every write is atomic: the image goes to a temporary file beside the
target, which is renamed over it only once complete (and with several outputs, once all are).

OpenCV and OpenEXR are imported where they are used, so that the core (scenes with constant
environments, the renderer, the benchmarks) runs with NumPy and PyOpenCL alone."""

import contextlib
import errno
import io
import os
import re
import stat
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pathtrace.errors import UserError, cut
from pathtrace.io.files import check_regular_file, shown
from pathtrace.io.tonecurve import tonemap, to_8bit

HDR_FORMATS = (".exr", ".hdr", ".pfm")
LDR_FORMATS = (".png", ".jpg", ".jpeg")


MAX_MAP_PIXELS = 1 << 26       # 8192 x 8192: a map's float32 RGB is then 768 MB


def read_hdr(path: Path, where: str, what: str = "environment map", max_side: int = None) -> np.ndarray:
    """A Radiance .hdr, OpenEXR or PFM image as linear float32 RGB, (H, W, 3); `what` it is
    and the most pixels it may have on a side name it in messages."""
    path = Path(path)
    check_regular_file(path, where, what, 4 << 30)
    size = _header_size(path)
    if size is not None and size[0] * size[1] > MAX_MAP_PIXELS:
        raise UserError(f"{where}: '{shown(path)}' claims {size[0]}x{size[1]} pixels, more than "
                        f"pathtrace takes ({MAX_MAP_PIXELS} pixels)")
    if size is not None and max_side is not None and max(size) > max_side:
        raise UserError(f"{where}: {what} '{shown(path)}' is {size[0]}x{size[1]} pixels; pathtrace takes "
                        f"at most {max_side} on a side")
    rgb = _read_exr(path) if path.suffix.lower() == ".exr" else _read_with_opencv(path)
    if rgb is None:
        raise UserError(f"{where}: '{shown(path)}' is not a readable HDR image (.hdr, .exr or .pfm)")
    if max_side is not None and max(rgb.shape[:2]) > max_side:
        raise UserError(f"{where}: {what} '{shown(path)}' is {rgb.shape[1]}x{rgb.shape[0]} pixels; "
                        f"pathtrace takes at most {max_side} on a side")
    if not np.all(np.isfinite(rgb)) or rgb.min() < 0:
        raise UserError(f"{where}: '{shown(path)}' holds negative, NaN or infinite pixels")
    return rgb


def _header_size(path: Path):
    """(width, height) as a .pfm or Radiance .hdr header states it, read before any decoder
    allocates for it; None where the header is not one of those (the decoder then refuses it)."""
    with open(path, "rb") as f:
        head = f.read(4096)
    lines = head.split(b"\n")
    try:
        if lines[0] in (b"PF", b"Pf"):
            w, h = lines[1].split()
            return int(w), int(h)
        if lines[0].startswith(b"#?"):
            blank = lines.index(b"")
            y, h, x, w = lines[blank + 1].split()
            return int(w), int(h)
    except (ValueError, IndexError):
        return None
    return None


def _read_with_opencv(path: Path):
    import cv2
    # silent: a truncated file would print OpenCV's own error line before ours; decoded from
    # memory: no file name reaches OpenCV
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    data = np.fromfile(path, np.uint8)
    try:
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED | cv2.IMREAD_ANYDEPTH | cv2.IMREAD_COLOR)
    except cv2.error:      # an empty file fails OpenCV's assertion instead of returning None
        return None
    if image is None or image.ndim != 3 or image.dtype not in (np.float32, np.float16):
        return None
    return np.ascontiguousarray(image[..., 2::-1], np.float32)


_QUIET = threading.Lock()      # the standard descriptors are the process's: one quieting at a time


@contextlib.contextmanager
def _quiet_c_library():
    """Standard output and error (file descriptors 1 and 2) sent to /dev/null for the duration:
    OpenEXR's C library prints its own lines about a damaged file to standard error
    (EXR_ERR_BAD_CHUNK_LEADER ...) and its C++ layer to standard output ("Warning: Exception
    raised reading pixel data ..."), before the one line pathtrace gives. C's buffered output is
    flushed before the descriptors come back, or a line kept in its buffer would be written at
    exit. A descriptor that is closed is left so."""
    import sys
    with _QUIET:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:          # (None under pythonw)
                stream.flush()
        _flush_c_streams()
        saved = {fd: copy for fd, copy in ((fd, _copy_above_standard(fd)) for fd in (1, 2)) if copy is not None}
        try:
            with open(os.devnull, "w") as null:
                for fd in saved:
                    os.dup2(null.fileno(), fd)
            yield
        finally:
            _flush_c_streams()
            for fd, copy in saved.items():
                os.dup2(copy, fd)
                os.close(copy)


def _copy_above_standard(fd: int):
    """A copy of descriptor fd numbered above 2 (a copy may take the number of a standard one
    that is closed, which quieting would then reuse), or None where fd is closed."""
    try:
        os.fstat(fd)
    except OSError:
        return None
    low = []
    copy = os.dup(fd)
    while copy <= 2:
        low.append(copy)
        copy = os.dup(fd)
    for extra in low:
        os.close(extra)
    return copy


def _flush_c_streams():
    """C's fflush of every output stream, where the C library can be named (POSIX)."""
    if os.name != "posix":
        return
    import ctypes
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):
        pass


def _read_exr(path: Path):
    """OpenEXR is given the file's bytes, not its name: its bindings take only names that are
    UTF-8."""
    import OpenEXR
    try:
        data = Path(path).read_bytes()
        with _quiet_c_library(), OpenEXR.File(io.BytesIO(data)) as f:
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


def _write_exr(path: str, rgb: np.ndarray, layers: dict = {}):
    """RGB, and each of `layers` as the channels <name>.R, <name>.G, <name>.B."""
    import OpenEXR
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    channels = {"RGB": np.ascontiguousarray(rgb, np.float32)}
    for name, image in layers.items():
        for k, c in enumerate("RGB"):
            channels[f"{name}.{c}"] = np.ascontiguousarray(image[..., k], np.float32)
    encoded = io.BytesIO()               # bytes, not a name, as _read_exr
    with OpenEXR.File(header, channels) as f:
        f.write(encoded)
    Path(path).write_bytes(encoded.getvalue())
    return True


def check_writable(path: Path, what: str = "--output", formats=HDR_FORMATS + LDR_FORMATS):
    """Fails early, before any rendering, if `path` cannot be written (or, where `formats` is
    given, has none of those suffixes)."""
    given, path = str(path), Path(path)
    name = cut(shown(path), 100)
    if not given or given.endswith(os.sep) or os.path.isdir(given):   # (isdir: False for any error)
        raise UserError(f"{what}: '{cut(shown(given), 100)}' is {'a folder' if given else 'empty'}; "
                        f"give an image file's name, such as {cut(shown(Path(given or '.', 'image.png')), 100)}")
    if formats and path.suffix.lower() not in formats:
        raise UserError(f"{what}: '{name}' has an unknown image format (use one of {', '.join(formats)})")
    try:
        target = _target(path)
        if not target.parent.is_dir():
            raise UserError(f"{what}: folder '{cut(shown(target.parent), 100)}' does not exist")
        # the only sure test (permissions, read-only mounts, root's exceptions) is to try
        os.unlink(_temporary(target.parent))
        if len(os.fsencode(target.name)) > os.pathconf(target.parent, "PC_NAME_MAX"):
            raise OSError(errno.ENAMETOOLONG, os.strerror(errno.ENAMETOOLONG))
        info = os.stat(target) if os.path.lexists(target) else None
    except ValueError:                  # a NUL byte
        raise UserError(f"{what}: '{name}': a file name cannot hold a NUL byte") from None
    except OSError as e:
        raise UserError(f"{what}: '{name}' is not writable ({e.strerror})") from None
    if info is not None and not stat.S_ISREG(info.st_mode):
        # a device (a link to /dev/full, say), a FIFO or a folder: renaming a new file over it
        # would replace it, and writing into it is not what an image output means
        raise UserError(f"{what}: '{name}' exists and is not a regular file; pathtrace replaces only regular files")
    if not os.access(target, os.W_OK) and info is not None:
        raise UserError(f"{what}: '{name}' is not writable")


def _target(path: Path) -> Path:
    """Where writing `path` lands: a symbolic link's target, so that the link stays a link."""
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def _temporary(folder: Path, suffix: str = "") -> str:
    """A new empty file in `folder` for a write to be renamed into place. Its name holds the
    process id (.pathtrace-<pid>-...), so that those a killed process left (a SIGKILL runs no
    code to remove them) are swept by the next write to the folder: sweep()."""
    sweep(folder)
    fd, tmp = tempfile.mkstemp(prefix=f"{TEMPORARY_PREFIX}{os.getpid()}-", suffix=suffix, dir=folder)
    os.close(fd)
    return tmp


TEMPORARY_PREFIX = ".pathtrace-"
_TEMPORARY = re.compile(r"\.pathtrace-(\d+)-")
_swept = set()          # folders swept by this process


def sweep(folder: Path):
    """Removes the temporary files (_temporary) in `folder` of processes that no longer run,
    once per folder per process."""
    key = os.path.realpath(folder)
    if key in _swept:
        return
    _swept.add(key)
    try:
        names = [e.name for e in os.scandir(folder) if e.name.startswith(TEMPORARY_PREFIX)]
    except OSError:
        return
    for name in names:
        m = _TEMPORARY.match(name)
        if not m or int(m.group(1)) == os.getpid():
            continue
        try:
            os.kill(int(m.group(1)), 0)
            continue                 # its process runs (or runs as another user): not ours to take
        except ProcessLookupError:
            pass
        except (PermissionError, OverflowError, OSError):
            continue
        try:
            path = os.path.join(folder, name)
            if stat.S_ISREG(os.lstat(path).st_mode):
                os.unlink(path)
        except OSError:
            pass


class Staged:
    """Files written beside their targets under temporary ASCII names (so that any valid target
    name works, whatever its length or encoding) and renamed over them only by commit(): until
    then, and on any failure, the targets stay as they were and the temporary files are removed.
    A new file gets the permissions the umask gives; a replaced one keeps its own."""

    def __init__(self):
        self.files = []       # (temporary, target)

    def add(self, path: Path, write, what: str, errors=(OSError,)):
        """Calls write(temporary_path) -> success for a temporary file beside `path`'s target."""
        path = Path(path)
        target = _target(path)
        tmp = _temporary(target.parent, path.suffix.lower())
        self.files.append((tmp, target))
        try:
            ok = write(tmp)
        except errors as e:
            raise UserError(f"{what}: cannot write '{shown(path)}': {e}") from None
        if not ok:
            raise UserError(f"{what}: cannot write '{shown(path)}'")
        os.chmod(tmp, _mode_for(target))

    def commit(self):
        for tmp, target in self.files:
            os.replace(tmp, target)
        self.files = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for tmp, _ in self.files:
            if os.path.exists(tmp):
                os.unlink(tmp)


def _mode_for(target: Path) -> int:
    if target.exists():
        return target.stat().st_mode & 0o7777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask


def write_text(path: Path, text: str, what: str = "--json"):
    check_writable(path, what, formats=None)

    def write(tmp):
        Path(tmp).write_text(text)
        return True
    with Staged() as staged:
        staged.add(path, write, what)
        staged.commit()


@dataclass
class Output:
    """An image file to write: (H, W, 3) linear radiance, tonemapped for PNG and JPEG; `layers`,
    more such images by name, go into an EXR file beside its RGB (the noisy image beside the
    denoised one); `raw` values (an albedo or an encoded normal) are stored in PNG and JPEG as
    they are, clipped to [0, 1], without exposure, tone curve or sRGB."""
    path: Path
    image: np.ndarray
    layers: dict = field(default_factory=dict)
    raw: bool = False


def write_images(outputs, exposure: float = 0.0, curve: str = "standard", what: str = "--output"):
    """Writes each Output. All or none: the files are renamed into place only once every one is
    complete."""
    suffixes = [Path(out.path).suffix.lower() for out in outputs]
    errors = (OSError, RuntimeError, ValueError)
    if any(suffix != ".exr" for suffix in suffixes):
        import cv2          # OpenCV encodes the other formats; an EXR alone does without its import
        errors += (cv2.error,)
    with Staged() as staged:
        for out, suffix in zip(outputs, suffixes):
            check_writable(out.path, what)
            staged.add(out.path, _image_writer(suffix, out, exposure, curve), what, errors=errors)
        staged.commit()


def write_image(path: Path, linear: np.ndarray, exposure: float = 0.0, curve: str = "standard",
                what: str = "--output"):
    write_images([Output(path, linear)], exposure, curve, what)


def _image_writer(suffix: str, out: Output, exposure: float, curve: str):
    """write(path) for one format. OpenCV encodes in memory and Python writes the bytes, so no
    file name reaches OpenCV's writer (which crashed on names that are not UTF-8)."""
    if suffix == ".exr":
        return lambda tmp: _write_exr(tmp, out.image, out.layers)

    def write(tmp):
        import cv2
        if suffix in HDR_FORMATS:
            data = np.ascontiguousarray(out.image[..., ::-1], np.float32)
        elif out.raw:
            data = np.ascontiguousarray(to_8bit(np.clip(out.image, 0.0, 1.0))[..., ::-1])
        else:
            data = np.ascontiguousarray(to_8bit(tonemap(out.image, exposure, curve))[..., ::-1])
        ok, encoded = cv2.imencode(".jpg" if suffix == ".jpeg" else suffix, data)
        if ok:
            Path(tmp).write_bytes(encoded.tobytes())
        return ok
    return write
