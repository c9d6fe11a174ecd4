"""Mesh files read in other Python processes: MeshFiles' way with a scene of many small OBJ files on
a machine of many cores (pathtrace.scene.meshes), whose other cores idle while one process reads
them: a small file's reading is hundreds of short NumPy operations, which threads take one at a
time under the interpreter's lock (docs/notes/performance-2026-11.md, 2026-11-30: OBJ files
read in other processes).

Each process is `python -m pathtrace.scene.meshes` (serve_reading there), given its share of the
files (in the reader's order, pickled, on its standard input) and answering on its standard output
with, per file, the mesh and its warning lines or its problem, and the stamps of the files it
checked, which this process notes for the scene's cache (pathtrace.io.files.noted). Not multiprocessing:
its start methods other than fork import the user's main module again in each process (a script
without a main guard would run again), and a fork of a process whose other threads may hold
locks (the devices' opening, beside the reading) is not safe. A process that fails leaves its
files to be read in this one: their results are (None, [])."""

import os
import pickle
import subprocess
import sys
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

from pathtrace.io.files import noted


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
        for future, (result, problem, files) in zip(futures, self._in_a_process(requests)):
            noted(files)
            if problem is not None:
                future.set_exception(problem)
            else:
                future.set_result(result)

    def _in_a_process(self, requests: list) -> list:
        # the folder the running pathtrace was imported from, first: a checkout run in place
        package_parent = str(Path(sys.modules["pathtrace"].__file__).parent.parent)
        path = os.pathsep.join([package_parent] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
        try:
            with self._lock:
                if self._closed:
                    raise OSError("closed")
                process = subprocess.Popen([sys.executable, "-m", "pathtrace.scene.meshes"], stdin=subprocess.PIPE,
                                           stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                           env={**os.environ, "PYTHONPATH": path})
                self._running.add(process)
            out, _ = process.communicate(pickle.dumps(requests))
            with self._lock:
                self._running.discard(process)
            if process.returncode == 0:
                return pickle.loads(out)
        except Exception:      # whatever the process or its answer did: read here instead
            pass
        return [((None, []), None, [])] * len(requests)

    def close(self):
        """Ends the processes still reading (a problem found stops the reader) and waits."""
        with self._lock:
            self._closed = True
            for process in self._running:
                process.kill()
        self._pool.shutdown(wait=True)
