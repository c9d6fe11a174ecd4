"""Entries of pathtrace's caches on disk: the kernels' binaries (app/device/opencl.py), large scenes'
BVHs (app/compiler/bvh_cache.py) and the scenes read from slow files (app/scene/read_cache.py). An
entry is the CRC-32 of its payload (4 bytes, little-endian), then the payload. It is written whole
or not at all, and read back only where it is a regular file whose checksum matches, so that a
damaged entry is a miss: never a hang (an entry that is a FIFO), a crash (a truncated binary
handed to a driver can crash it: PoCL segfaulted on the first half of a valid one) or a wrong
tree. The check is against damage, not against forgery (the entries' names are their keys'
digests): a CRC-32 misses a random change once in 4e9 and catches every burst of up to 32 bits,
at 7x SHA-256's speed on a CPU without SHA instructions (a large scene's entries are hundreds of
megabytes, read on each warm start). The caches are an optimisation: a disk that refuses an
entry still renders."""

import os
import stat
import tempfile
import threading
import time
import zlib
from pathlib import Path

CHECKSUM_BYTES = 4
TEMPORARY = ".tmp"          # the suffix of an entry's file while it is written
STALE_SECONDS = 600         # a write's file unchanged this long is a write that ended unfinished
_writes = []                # the threads of the writes under way (write_soon)


def cache_dir() -> Path:
    """pathtrace's cache folder: PATHTRACE_CACHE, else pathtrace under XDG_CACHE_HOME (~/.cache).
    Here rather than beside the kernels' cache, so that a scene's reading asks for it without
    importing PyOpenCL, which the devices' opening imports meanwhile in a thread of its own
    (api.DevicesOpening): the reading had waited for that import."""
    base = os.environ.get("PATHTRACE_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "pathtrace")
    if os.environ.get("PATHTRACE_CACHE"):
        _warn_if_no_folder("PATHTRACE_CACHE", base)
    return Path(base)


def chosen_folder(variable: str, default: str):
    """The folder of a cache that the environment variable `variable` may name (0: the cache is
    off, None), else cache_dir()/default."""
    chosen = os.environ.get(variable, "")
    if chosen == "0":
        return None
    if chosen:
        _warn_if_no_folder(variable, chosen)
    return Path(chosen) if chosen else cache_dir() / default


_warned_folders = set()


def _warn_if_no_folder(variable: str, path: str):
    """One warning, once, where the variable names something that is no folder (a file): the
    caches are then not kept, which pathtrace goes on without, as without a writable folder."""
    if variable not in _warned_folders and os.path.exists(path) and not os.path.isdir(path):
        from pathtrace.errors import cut, warn
        _warned_folders.add(variable)
        warn(f"{variable}: '{cut(path, 200)}' is not a folder; pathtrace keeps nothing there")


def checksum(chunks) -> bytes:
    crc = 0
    for chunk in chunks:
        crc = zlib.crc32(chunk, crc)
    return crc.to_bytes(CHECKSUM_BYTES, "little")


def read_entry(path: Path):
    """The payload of the entry at path, as a writable memoryview, or None where there is none,
    it is not a regular file or its checksum does not match."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):      # a FIFO would block the open for ever
            return None
        data = bytearray(info.st_size)
        with open(path, "rb") as f:
            if f.readinto(data) != len(data):
                return None
    except OSError:
        return None
    payload = memoryview(data)[CHECKSUM_BYTES:]
    if len(data) < CHECKSUM_BYTES or checksum([payload]) != data[:CHECKSUM_BYTES]:
        return None
    return payload


def write_entry(path: Path, *chunks) -> bool:
    """Writes an entry whose payload is the chunks (bytes-like) end to end: to a temporary file
    renamed over path, so that the entry is whole or absent. False where the disk refuses it (a
    read-only or full disk), leaving no partial file. The temporary file's name is its writer's
    alone (two threads may write one entry at once); one that a killed process left behind is
    removed by a later prune."""
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(TEMPORARY, path.name + ".", path.parent)
        tmp = Path(name)
        with open(handle, "wb") as f:
            f.write(checksum(chunks))
            for chunk in chunks:
                f.write(chunk)
        os.replace(tmp, path)
        return True
    except OSError:
        try:
            if tmp is not None:
                tmp.unlink()
        except OSError:
            pass
        return False


def prune(where: Path, pattern: str, limit: int):
    """Removes the least recently used entries of `where` that match `pattern` until the rest
    take at most `limit` bytes (a read entry's time is touched: pathtrace.compiler.bvh_cache),
    and the temporary files of writes that ended STALE_SECONDS ago or more without their entry
    (a process killed, or leaving at an interrupt, as it wrote)."""
    try:
        entries = [(e.stat().st_mtime, e.stat().st_size, e) for e in where.glob(pattern)]
        unfinished = [(e.stat().st_mtime, e) for e in where.glob("*" + TEMPORARY)]
    except OSError:
        return
    for changed, write in unfinished:
        if changed < time.time() - STALE_SECONDS:
            try:
                write.unlink()
            except OSError:
                pass
    total = sum(size for _, size, _ in entries)
    for _, size, entry in sorted(entries, key=lambda e: e[0]):
        if total <= limit:
            break
        try:
            entry.unlink()
            total -= size
        except OSError:
            pass


def write_soon(path: Path, chunks: list, pattern: str, limit: int):
    """write_entry(path, *chunks) in a thread of its own, then prune(path.parent, pattern, limit),
    so that a first image does not wait for a large entry. The interpreter waits for it at its
    exit; a command that leaves past that (os._exit) calls wait_for_writes first. A write cut
    short leaves a temporary file, not an entry."""
    # not a daemon, whatever the thread that starts it (the viewer reads scenes in a daemon thread)
    thread = threading.Thread(target=_write_and_prune, args=(path, chunks, pattern, limit), name="cache write",
                              daemon=False)
    _writes.append(thread)
    thread.start()


def _write_and_prune(path: Path, chunks: list, pattern: str, limit: int):
    if write_entry(path, *chunks):
        prune(path.parent, pattern, limit)


def wait_for_writes():
    """Returns once the entries being written (write_soon) are written."""
    while _writes:
        _writes.pop().join()
