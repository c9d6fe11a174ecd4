"""A render farm on Ray (docs/farm.md): one actor per OpenCL device of a Ray cluster renders
batches of sample indices into sums it keeps, and the driver merges each actor's sums once an
image is done.

What travels: the driver reads the scene files and compiles each scene once (meshes, maps and the
BVH become arrays); the compiled scenes go to the cluster once, through Ray's object store, so
workers need no files of their own. A batch is (job, first sample, count), and its answer is the
seconds it took; an actor adds its batches of a job to sums it keeps and hands them over when
the driver collects the finished job. A dead actor's batches not yet collected are issued again
to the others, and sums are added only when collected, so every image has exactly the samples
asked for, none twice. Because a sample's random numbers are keyed on its index (kernels/rng.cl),
the image equals a one-device render of the same samples by the same program up to the order of
float additions (an actor may draw its first batches with the generic program while its scene's
own builds: pathtrace.device.programs; the two agree in expectation, not sample for sample).

Batches grow towards BATCH_SECONDS on each actor's measured speed; the last ones are cut so that
every actor finishes at once (Farm.batch_size), as several devices in one process do
(pathtrace.rendering.multidevice).

Jobs are the stills of several scenes, or the frames of a camera orbit, all in one queue."""

import collections
import math
import socket
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from pathtrace.cameras import Camera
from pathtrace.errors import UserError, cut, short
from pathtrace.rendering.launches import next_launch_size

BATCH_SECONDS = 1.0       # a batch's target duration: long enough that transfers are amortised


@dataclass
class Job:
    """One image: `spp` samples of a compiled scene (an index into the farm's scenes, whose
    settings give the size) seen by a camera."""
    scene: int
    camera: Camera
    spp: int
    output: str = ""


def orbit(camera: Camera, frames: int, degrees: float) -> list[Camera]:
    """The cameras of a turn by `degrees` of the eye about the look-at point, around the
    world's y axis, in `frames` steps (the first frame is the scene's camera)."""
    cameras = []
    for k in range(frames):
        a = math.radians(degrees * k / frames)
        c, s = math.cos(a), math.sin(a)
        rel = camera.eye - camera.look_at
        turned = camera.copy()
        turned.eye = camera.look_at + np.array([c * rel[0] + s * rel[2], rel[1], -s * rel[0] + c * rel[2]])
        cameras.append(turned)
    return cameras


def _actor_class(ray):
    @ray.remote(max_restarts=0)
    class DeviceActor:
        """One OpenCL device of one node with the farm's scenes uploaded."""

        def __init__(self, scenes, device_spec: str):
            from pathtrace.device.opencl import choose_device, list_devices
            from pathtrace.rendering.renderer import Renderer
            if device_spec == "gpu":
                # Ray reserves a GPU for this actor and hides the others from CUDA; should the
                # OpenCL driver still list them all, take the reserved one by its number
                ids = ray.get_gpu_ids()
                if ids and sum(d.kind == "GPU" for d in list_devices()) > 1:
                    device_spec = f"gpu:{int(ids[0])}"
            backend = choose_device(device_spec, log=lambda line: None)
            self.device = backend.device.describe()
            self.renderers = [Renderer(backend, compiled) for compiled in scenes]
            self.jobs = {}      # scene -> the job whose sums its renderer holds
            self.aside = {}     # job -> (sum, sum_sq) read back from a renderer that went on to another job

        def describe(self) -> str:
            return self.device

        def render(self, job, scene: int, camera: Camera, start: int, count: int) -> float:
            """Adds samples start .. start+count-1 of every pixel to the sums of `job` (the
            driver's key of it); returns the seconds they took. A renderer holds one job's sums
            on its device: another job's, if it held them, are read back and kept in this
            process's memory first."""
            renderer = self.renderers[scene]
            if self.jobs.get(scene) != job:
                self._put_aside(scene)
                renderer.set_camera(camera)     # resets the sums
                self.jobs[scene] = job
            t0 = time.perf_counter()
            renderer.choose_queue_plan(count)   # path_queue "auto": once, by trial renders
            renderer.add_samples(count, start)
            renderer.finish()
            return time.perf_counter() - t0

        def collect(self, job):
            """Job `job`'s sums of the batches rendered since the last collect: (sum, sum_sq),
            (H, W, 4) float32 each, or None where there were none. They are dropped here."""
            for scene in [scene for scene, held in self.jobs.items() if held == job]:
                self._put_aside(scene)
            return self.aside.pop(job, None)

        def _put_aside(self, scene: int):
            job = self.jobs.pop(scene, None)
            if job is None:
                return
            renderer = self.renderers[scene]
            sums = renderer.read_sum(), renderer.read_sum_sq()
            kept = self.aside.get(job)
            self.aside[job] = sums if kept is None else (kept[0] + sums[0], kept[1] + sums[1])

    return DeviceActor


def _import_ray():
    try:
        import ray
    except ImportError:
        raise UserError("the farm needs Ray: install pathtrace with the 'farm' extra "
                        "(.venv/bin/python -m pip install '.[farm]')") from None
    return ray


def connect(address: str = None, num_cpus: int = None, num_gpus: int = None):
    """Joins the Ray cluster at `address` ('auto': the one started on this machine with
    `ray start`), or starts a local one (of num_cpus CPUs and num_gpus GPUs, default all) when
    no address is given."""
    ray = _import_ray()
    if address and address != "auto":
        _check_reachable(address)
    if not ray.is_initialized():
        try:
            ray.init(address=address, num_cpus=num_cpus, num_gpus=num_gpus, include_dashboard=False,
                     logging_level="ERROR", log_to_driver=False)
        except (ConnectionError, RuntimeError, ValueError) as e:
            raise UserError(f"--address {short(address)}: cannot reach a Ray cluster: "
                            f"{str(e).strip().splitlines()[0]}") from None
        _drop_worker_death_reports()
    return ray


def _drop_worker_death_reports():
    """Ray's driver prints every error the cluster reports, a worker's death among them, as a
    paragraph on standard output ('(raylet) A worker died or was killed ...'), whatever
    log_to_driver says: its error listener calls ray._private.worker.print_to_stdstream. The
    farm gives a dead worker's batches to the others and reports the loss in its own summary
    line (Farm.lost_workers), so those reports are dropped; worker logs pass as before. A Ray
    without that function (a future version) prints them."""
    from ray._private import worker
    show = getattr(worker, "print_to_stdstream", None)
    if show is None or getattr(show, "drops_raylet_reports", False):
        return

    def drop_raylet_reports(data, ignore_prefix):
        if data.get("pid") != "raylet":
            show(data, ignore_prefix)
    drop_raylet_reports.drops_raylet_reports = True
    worker.print_to_stdstream = drop_raylet_reports


def _check_reachable(address: str, seconds: float = 3.0):
    """Ray retries an unreachable head for minutes, printing as it goes: try its port first."""
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not (port.isascii() and port.isdigit() and len(port) <= 5 and int(port) < 65536):
        raise UserError(f"--address {short(address)}: give host:port (the head's GCS port, 6379 by "
                        "default), or 'auto'")
    try:
        socket.create_connection((host, int(port)), timeout=seconds).close()
    except (OSError, UnicodeError, ValueError) as e:     # UnicodeError: a host IDNA refuses
        raise UserError(f"--address {short(address)}: cannot reach a Ray cluster there "
                        f"({cut(getattr(e, 'strerror', None) or str(e))})") from None


def start_actors(ray, scenes, cpu_actors: int = None, cpu_device: str = "cpu"):
    """One actor per GPU of the cluster (Ray shows each the GPU it reserved), and `cpu_actors`
    actors on `cpu_device` (default: one if the cluster has no GPU), spread over the nodes.
    Actors whose device cannot be opened are dropped with a line saying why; none left is an
    error."""
    Actor = _actor_class(ray)
    scenes_ref = ray.put(scenes)
    gpus = int(ray.cluster_resources().get("GPU", 0))
    if cpu_actors is None:
        cpu_actors = 0 if gpus else 1
    actors = [Actor.options(num_gpus=1, num_cpus=0).remote(scenes_ref, "gpu") for _ in range(gpus)]
    actors += [Actor.options(num_cpus=1, scheduling_strategy="SPREAD").remote(scenes_ref, cpu_device)
               for _ in range(cpu_actors)]
    live, problems = [], []
    for actor in actors:
        try:
            live.append((actor, ray.get(actor.describe.remote())))
        except ray.exceptions.RayError as e:
            problems.append(_cause(e))
    for problem in problems:
        print(f"pathtrace farm: a worker has no usable device: {problem}", flush=True)
    if not live:
        raise UserError("no farm worker could open an OpenCL device"
                        + (f" ({problems[0]})" if problems else " (the cluster has no GPU and --cpu-actors is 0)"))
    return live


def _cause(error) -> str:
    """The last line of a Ray error's cause: the worker's own exception."""
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    return lines[-1] if lines else type(error).__name__


class _Call(NamedTuple):
    """A call of an actor's that Farm.render awaits."""
    kind: str               # "batch" (DeviceActor.render) or "collect"
    actor: object
    job: int
    ranges: list            # (start, count): the job's samples it renders, or hands over
    ends: float = math.inf  # a batch's expected end (perf_counter), at the actor's last speed


class Farm:
    """Renders jobs of `spp` samples on the live actors, issuing again the batches of those that
    die."""

    def __init__(self, ray, actors, scenes):
        self.ray = ray
        self.actors = dict(actors)          # actor -> device description
        self.scenes = scenes
        self.lost = 0                       # batches issued again because their actor died
        self.started = len(self.actors)
        self.renders = 0                    # calls of render: with a job's index, its key on the actors

    @property
    def lost_workers(self) -> int:
        """How many workers died during the renders so far."""
        return self.started - len(self.actors)

    def render(self, jobs: list[Job], on_batch=None):
        """The merged (sum, sum_sq) of each job, (H, W, 4) float64 each. on_batch(samples per
        pixel) after each batch an actor renders, and on_batch(-samples) for those of a dead
        actor, which are rendered again."""
        ray = self.ray
        self.renders += 1
        key = self.renders      # an actor's sums of an earlier render, cut short, are not this one's
        sizes = [self.scenes[job.scene].scene.settings for job in jobs]
        sums = [np.zeros((s.height, s.width, 4), np.float64) for s in sizes]
        sums_sq = [np.zeros_like(s) for s in sums]
        done = [0] * len(jobs)
        # every range of samples is in one place: unissued (in job order), in a pending batch,
        # held by its actor, or in a pending collect
        todo = collections.deque((j, 0, job.spp) for j, job in enumerate(jobs))
        held = {actor: collections.defaultdict(list) for actor in self.actors}   # actor -> job -> ranges
        pending = {}            # ref -> _Call
        size = {actor: 1 for actor in self.actors}      # next batch size of each actor
        speed = {}              # actor -> samples per second, as last measured
        report = on_batch or (lambda count: None)

        def issue(actor):
            if not todo:
                return
            j, start, count = todo.popleft()
            take = min(count, self.batch_size(actor, size, speed, todo, pending, count))
            if take < count:
                todo.appendleft((j, start + take, count - take))
            ref = actor.render.remote((key, j), jobs[j].scene, jobs[j].camera, start, take)
            ends = time.perf_counter() + take / speed[actor] if actor in speed else math.inf
            pending[ref] = _Call("batch", actor, j, [(start, take)], ends)

        def lose(ranges, rendered: bool):
            """Puts a dead actor's ranges, (job, start, count) each, back in the queue; `rendered`:
            their batches had been reported."""
            for r in ranges:
                todo.appendleft(r)
                if rendered:
                    report(-r[2])
            self.lost += len(ranges)

        def refill():
            for a in self.actors:
                if not any(c.kind == "batch" and c.actor is a for c in pending.values()):
                    issue(a)

        for actor in self.actors:
            issue(actor)
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            kind, actor, j, ranges, _ = pending.pop(ready[0])
            try:
                answer = ray.get(ready[0])
            except ray.exceptions.RayError:
                # the actor died (or its device failed): what it rendered or held goes back to
                # the queue, to be rendered by the others
                lose([(j, start, count) for start, count in ranges], kind == "collect")
                if actor in self.actors:
                    del self.actors[actor]
                    lose([(jj, start, count) for jj, rs in held.pop(actor).items() for start, count in rs], True)
                    ray.kill(actor)     # one whose device failed would hold it, and answer again
                if not self.actors:
                    raise UserError("every farm worker died; nothing written") from None
                refill()
                continue
            if kind == "collect":
                if answer is not None:
                    sums[j] += answer[0]
                    sums_sq[j] += answer[1]
                done[j] += sum(count for _, count in ranges)
                continue
            if actor not in self.actors:     # an answer after a failure of the same actor
                lose([(j, *ranges[0])], False)
                refill()
                continue
            (start, count), = ranges
            held[actor][j].append((start, count))
            speed[actor] = count / max(answer, 1e-9)
            size[actor] = next_launch_size(count, answer, BATCH_SECONDS)
            report(count)
            if not any(t[0] == j for t in todo) and \
                    not any(c.kind == "batch" and c.job == j for c in pending.values()):
                for a, jobs_held in held.items():     # the job is rendered: its sums come home
                    if jobs_held.get(j):
                        pending[a.collect.remote((key, j))] = _Call("collect", a, j, jobs_held.pop(j))
            issue(actor)
        assert done == [job.spp for job in jobs], done
        return sums, sums_sq

    @staticmethod
    def batch_size(actor, size, speed, todo, pending, count) -> int:
        """Samples for `actor`'s next batch: `size[actor]`, towards BATCH_SECONDS at its measured
        speed; near the end, its share of what is left, so that every actor finishes at once: the
        unissued samples and the pending batches' remaining time shared in proportion to the
        actors' speeds (an actor not yet measured takes none of it)."""
        if actor not in speed:
            return size[actor]
        now = time.perf_counter()
        left = sum(c for _, _, c in todo) + count
        batches = [c for c in pending.values() if c.kind == "batch"]
        busy = sum(speed.get(c.actor, 0.0) * max(min(c.ends, now + BATCH_SECONDS) - now, 0.0) for c in batches)
        total = sum(speed.get(c.actor, 0.0) for c in batches) + speed[actor]
        share = math.ceil(speed[actor] * (left + busy) / total)
        return max(1, min(size[actor], share))
