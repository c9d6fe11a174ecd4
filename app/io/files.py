"""Files the user names: the one check made before reading any of them (scene files, maps,
meshes), which also notes what a scene's reading read (pathtrace.scene.read_cache), and paths as
messages show them."""

import os
import stat
import threading
from contextlib import contextmanager
from pathlib import Path

from pathtrace.errors import UserError, cut, escape


def shown(path) -> str:
    """A path for a message, on one line: bytes that are not UTF-8 and characters that do not
    print (a newline, an escape sequence) shown as escapes."""
    return escape(str(path).encode("utf-8", "backslashreplace").decode("utf-8"))


def missing(path, what: str, where: str = None) -> UserError:
    """The one wording of a file that is not there, wherever it was named: "<where>: <what>
    '<path>' does not exist"."""
    return UserError(f"{where + ': ' if where else ''}{what} '{cut(shown(path), 100)}' does not exist")


def check_regular_file(path: Path, where: str, what: str, max_bytes: int) -> tuple:
    """Refuses, in one line, a path that does not exist, is not a regular file (a folder, a FIFO,
    a device such as /dev/zero: reading one could hang or never end) or is larger than
    max_bytes; else returns its stamp, taken before its bytes are read."""
    try:
        info = os.stat(path)
    except ValueError:                  # a NUL byte in the name
        raise UserError(f"{where}: {what} '{cut(shown(path), 100)}': a file name cannot hold a NUL byte") from None
    except FileNotFoundError:
        raise missing(path, what, where) from None
    except OSError as e:
        raise UserError(f"{where}: {what} '{cut(shown(path), 100)}': {e.strerror}") from None
    if not stat.S_ISREG(info.st_mode):
        raise UserError(f"{where}: {what} '{cut(shown(path), 100)}' is not a regular file")
    if info.st_size > max_bytes:
        raise UserError(f"{where}: {what} '{cut(shown(path), 100)}' is larger than {max_bytes >> 20} MB")
    checked = stamp(path, info)
    noted([checked])
    return checked


def noted(stamps):
    """Stamps of files checked (stamp) added to the noting_files() lists open: check_regular_file's,
    or those of a process that read files for this one (pathtrace.scene.meshes.MeshFiles)."""
    with _noting:
        for notes in _notes:
            notes.extend(stamps)


_notes = []                  # the lists that noting_files() holds open, in any thread
_noting = threading.Lock()   # mesh files are read in threads (pathtrace.scene.meshes.MeshFiles)


def stamp(path, info: os.stat_result) -> tuple:
    """What says that a file is unchanged: its path, size and time of last change."""
    return str(Path(path).absolute()), info.st_size, info.st_mtime_ns


@contextmanager
def noting_files():
    """A list of the stamps of the files checked (check_regular_file) while it is open, by any
    thread."""
    notes = []
    with _noting:
        _notes.append(notes)
    try:
        yield notes
    finally:
        with _noting:
            _notes.remove(notes)
