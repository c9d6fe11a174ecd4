"""Mesh files read in other Python processes: MeshFiles' way with a scene of many small OBJ files on
a machine of many cores (pathtrace.scene.meshes), whose other cores idle while one process reads
them: a small file's reading is hundreds of short NumPy operations, which threads take one at a
time under the interpreter's lock (docs/notes/performance-2026-11.md, 2026-11-30: OBJ files
read in other processes).

Each process runs serve_reading, given its share of the files (in the
reader's order, pickled, on its standard input) and answering on its standard output with, per
file, the mesh and its warning lines or its problem, and the stamps of the files it checked, which
this process notes for the scene's cache (pathtrace.io.files.noted). Not multiprocessing: its
start methods other than fork import the user's main module again in each process (a script
without a main guard would run again), and a fork of a process whose other threads may hold locks
(the devices' opening, beside the reading) is not safe. A process that fails (its standard
error is not kept) leaves its files to be read in this one: their results are (None, [])."""

import os
import pickle
import subprocess
import sys
import threading
from pathlib import Path
from concurrent.futures import Future, ThreadPoolExecutor

from pathtrace.errors import UserError
from pathtrace.io.files import noted, noting_files
from pathtrace.scene import mesh_cache


class Reading:
    """`requests` ((path, where) pairs) read by `processes` processes, each a consecutive share:
    `futures` holds one per request."""

    def __init__(self, requests: list, processes: int):
        self.futures = [Future() for _ in requests]
        self._running = set()
        self._lock = threading.Lock()
        self._closed = False
        share = -(-len(requests) // max(processes, 1))
        self._pool = ThreadPoolExecutor(max(processes, 1), thread_name_prefix="mesh-processes")
        for k in range(0, len(requests), share):
            self._pool.submit(self._read, requests[k:k + share], self.futures[k:k + share])

    def _read(self, requests: list, futures: list):
        try:
            answers = self._in_a_process(requests)
            for (path, _), future, (result, problem, files) in zip(requests, futures, answers):
                noted(files)
                if problem is not None:
                    future.set_exception(problem)
                else:
                    future.set_result(result)
                    self._keep(path, result, files)
        finally:          # whatever went wrong, no read waits: a file without an answer the reader reads itself
            for future in futures:
                if not future.done():
                    future.set_result((None, []))

    @staticmethod
    def _keep(path, result: tuple, files: list):
        """A mesh a process read without a warning, collected (pathtrace.scene.mesh_cache) under
        the stamp the process read it at."""
        mesh, notes = result
        at = [s for s in files if s[0] == str(Path(path).absolute())]
        if not notes and at:
            mesh_cache.collect(at[0], mesh)

    def _in_a_process(self, requests: list) -> list:
        """The answers of a process that reads `requests`, one per request, or [] where it fails.
        It imports pathtrace as this process did (sys.path, as PYTHONPATH), with nothing before
        it (-P), and the reading function by name rather than by running meshes.py as __main__,
        whose import after its package's (which imports it) Python warns of. NumPy's OpenBLAS
        loads there with one thread: with a thread per core in each of 16 processes, spinning as
        OpenBLAS's threads do once started, the H200 machine's reading took 1.6 s, not 1.1 s
        (docs/notes/performance-2026-12.md, twenty-second session)."""
        try:
            with self._lock:
                if self._closed:
                    return []
                process = subprocess.Popen(
                    [sys.executable, "-P", "-c", "from pathtrace.scene.mesh_processes import serve_reading; "
                     "from pathtrace.scene.meshes import read_mesh; serve_reading(read_mesh)"],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                    env={**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p),
                         "OPENBLAS_NUM_THREADS": "1"})
                self._running.add(process)
            out, _ = process.communicate(pickle.dumps(requests))
            with self._lock:
                self._running.discard(process)
            answers = pickle.loads(out) if process.returncode == 0 else []
            return answers if len(answers) == len(requests) else []
        except Exception:      # whatever the process or its answer did: the reader reads them itself
            return []

    def close(self):
        """Ends the processes still reading (a problem found stops the reader) and waits."""
        with self._lock:
            self._closed = True
            for process in self._running:
                process.kill()
        self._pool.shutdown(wait=True)


def serve_reading(read_mesh):
    """A reading process's work: (path, where) requests from standard input; per request, the
    mesh as read_mesh (pathtrace.scene.meshes) reads it and its warning lines, or its problem, and
    the stamps of the files checked, to standard output."""
    out = []
    for path, where in pickle.load(sys.stdin.buffer):
        notes = []
        with noting_files() as files:
            try:
                out.append(((read_mesh(path, where, notes.append), notes), None, files))
            except UserError as e:
                out.append((None, e, files))
    sys.stdout.buffer.write(pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL))
