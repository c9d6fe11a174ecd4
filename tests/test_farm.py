"""The render farm on a local Ray cluster of CPU actors (app/rendering/farm.py): the merged image equals
the one-process render of the same samples, also when an actor is killed mid-render, and each
bad input is one line."""

import collections
import random
import subprocess
import sys
import types

import numpy as np
import pytest
import ray

from pathtrace.rendering import farm
from pathtrace.compiler.compiled import compile_scene
from pathtrace.errors import UserError
from pathtrace.io.images import read_hdr
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene


@pytest.fixture(scope="module")
def cluster():
    """A local cluster of 3 CPUs, the driver's own: left running between the tests here."""
    farm.connect(num_cpus=3)
    yield ray
    ray.shutdown()


@pytest.fixture
def start_actors(cluster):
    """farm.start_actors on the cluster, the actors killed as the test ends: an actor whose
    handles are dropped gives its CPU back only when Ray gets round to it (15 s once), and the
    next test's actors waited for it."""
    started = []

    def start(scenes, **options):
        actors = farm.start_actors(cluster, scenes, **options)
        started.extend(actor for actor, _ in actors)
        return actors
    yield start
    for actor in started:
        cluster.kill(actor)


@pytest.fixture(scope="module")
def scenes():
    return [compile_scene(load_scene(name).with_settings(width=40, height=24, spp=40))
            for name in ("simple", "cornell-box")]


def one_process(backend, compiled, camera, spp):
    r = Renderer(backend, compiled)
    r.set_camera(camera)
    r.add_samples(spp)
    return r.read_sum().astype(np.float64)


def test_farm_image_equals_the_one_process_render(cluster, start_actors, scenes, backend):
    actors = start_actors(scenes, cpu_actors=3)
    assert len(actors) == 3
    jobs = [farm.Job(0, scenes[0].scene.camera, 40), farm.Job(1, scenes[1].scene.camera, 24)]
    jobs += [farm.Job(0, c, 16) for c in farm.orbit(scenes[0].scene.camera, 2, 90)]
    counted = []
    sums, _ = farm.Farm(cluster, actors, scenes).render(jobs, counted.append)
    assert sum(counted) == 40 + 24 + 2 * 16
    for job, s in zip(jobs, sums):
        ref = one_process(backend, scenes[job.scene], job.camera, job.spp)
        assert s[..., 3].min() == s[..., 3].max() == job.spp          # every pixel: every sample
        np.testing.assert_allclose(s[..., :3], ref[..., :3], rtol=1e-5, atol=1e-5)
    # the orbit's second frame looks from elsewhere
    assert not np.allclose(sums[2], sums[3])


def test_an_actor_keeps_each_jobs_sums_apart_and_hands_them_over_once(cluster, start_actors, scenes, backend):
    """An actor's renderer holds one job's sums: batches of two frames of one scene, taking
    turns on one actor, each reach their own frame, and a collect hands a job's sums over once."""
    (actor, _), = start_actors(scenes, cpu_actors=1)
    cameras = farm.orbit(scenes[0].scene.camera, 2, 90)
    for job, start, count in [(0, 0, 5), (1, 0, 7), (0, 5, 3), (1, 7, 2)]:
        assert ray.get(actor.render.remote(job, 0, cameras[job], start, count)) > 0
    for job, spp in [(0, 8), (1, 9)]:
        s, sq = ray.get(actor.collect.remote(job))
        assert s[..., 3].min() == s[..., 3].max() == spp
        ref = one_process(backend, scenes[0], cameras[job], spp)
        np.testing.assert_allclose(s[..., :3], ref[..., :3], rtol=1e-5, atol=1e-5)
        assert ray.get(actor.collect.remote(job)) is None


def test_the_last_batches_are_shared_by_speed_so_that_the_actors_end_together():
    """Farm.batch_size: far from the end an actor's batch is its BATCH_SECONDS size; near it, its
    share of the samples left and of the others' pending work, in proportion to its speed."""
    fast, slow = "fast", "slow"
    speed = {fast: 300.0, slow: 100.0}
    size = {fast: 300, slow: 100}
    todo = [(0, 0, 10_000)]
    assert farm.Farm.batch_size(fast, size, speed, todo, {}, 0) == 300
    # 400 samples left, the slow actor busy for another half second (50 samples): 450 shared
    # 3:1 between the fast one, which asks now, and the slow one
    now = farm.time.perf_counter()
    pending = {"ref": farm._Call("batch", slow, 0, [(0, 80)], now + 0.5)}
    size = {fast: 1000, slow: 1000}
    n = farm.Farm.batch_size(fast, size, speed, [(0, 100, 300)], pending, 100)
    assert abs(n - 0.75 * 450) <= 2, n
    # an actor not yet measured takes its first (small) batch, and no share of the others'
    assert farm.Farm.batch_size("new", {"new": 1}, speed, todo, pending, 0) == 1
    assert farm.Farm.batch_size(fast, size, speed, [], {}, 1) == 1


def test_the_actors_splats_add_up_to_the_one_process_render(cluster, start_actors, backend):
    """Bidirectional path tracing through the farm: each actor's sums hold the light tracing
    splats of its own samples, wherever on the image they land, and the merged sums equal a
    one-process render of the same samples (the splats' atomic additions in any order: float
    rounding apart)."""
    bdpt = [compile_scene(load_scene("cornell-box").with_settings(width=24, height=16, spp=24,
                                                                   integrator="bdpt", max_depth=4))]
    actors = start_actors(bdpt, cpu_actors=2)
    job = farm.Job(0, bdpt[0].scene.camera, 24)
    f = farm.Farm(cluster, actors, bdpt)
    (s,), _ = f.render([job], None)
    assert s[..., 3].min() == s[..., 3].max() == 24
    assert f.lost == 0 and len(f.actors) == 2
    ref = one_process(backend, bdpt[0], job.camera, 24)
    np.testing.assert_allclose(s[..., :3], ref[..., :3], rtol=2e-5, atol=1e-6)


def test_killing_an_actor_mid_render_keeps_the_exact_samples(cluster, start_actors, scenes, backend):
    actors = start_actors(scenes, cpu_actors=3)
    f = farm.Farm(cluster, actors, scenes)
    victim = actors[1][0]
    killed, counted = [], []

    def kill_once(samples):
        counted.append(samples)
        if not killed:
            cluster.kill(victim)
            killed.append(samples)

    job = farm.Job(1, scenes[1].scene.camera, 120)
    (s,), _ = f.render([job], kill_once)
    assert killed and f.lost >= 1 and victim not in f.actors
    # the progress takes back the dead actor's samples, which the others render again
    assert sum(counted) == 120
    assert s[..., 3].min() == s[..., 3].max() == 120
    ref = one_process(backend, scenes[1], job.camera, 120)
    np.testing.assert_allclose(s[..., :3], ref[..., :3], rtol=1e-5, atol=1e-5)


def test_a_worker_killed_by_the_system_is_reported_in_one_line_not_by_ray(cluster, start_actors, scenes, backend,
                                                                          capfd):
    """A worker process killed outright (SIGKILL, as the OOM killer does) used to bring Ray's
    'A worker died or was killed ...' paragraph to the terminal while the render went on; the
    farm reports the loss itself (Farm.lost_workers) and the image still holds every sample."""
    import os
    import signal
    import time
    actors = start_actors(scenes, cpu_actors=2)
    f = farm.Farm(cluster, actors, scenes)
    victim = actors[0][0]
    pid = ray.get(victim.__ray_call__.remote(lambda self: os.getpid()))
    killed = []

    def kill_once(samples):
        if not killed:
            os.kill(pid, signal.SIGKILL)
            killed.append(samples)

    job = farm.Job(0, scenes[0].scene.camera, 200)
    (s,), _ = f.render([job], kill_once)
    assert killed and f.lost_workers == 1
    assert s[..., 3].min() == s[..., 3].max() == 200
    time.sleep(3)            # Ray's error listener reports a death a moment after it
    out, err = capfd.readouterr()
    assert "worker died" not in (out + err).lower() and "raylet" not in out + err, out + err


def test_a_worker_without_a_usable_device_is_one_clear_error(cluster, scenes, capsys):
    with pytest.raises(UserError, match="no farm worker could open an OpenCL device.*no OpenCL device matches 'no-such-device'"):
        farm.start_actors(cluster, scenes, cpu_actors=1, cpu_device="no-such-device")
    assert "a worker has no usable device" in capsys.readouterr().out


def test_no_cluster_at_the_address_is_one_line(tmp_path):
    for address, message in [("127.0.0.1:9", "cannot reach a Ray cluster there"),
                             ("nonsense", "give host:port")]:
        r = subprocess.run([sys.executable, "-m", "pathtrace", "farm", "render", "simple", "--address",
                            address, "-o", str(tmp_path / "x.png")], capture_output=True, text=True,
                           timeout=60)
        assert r.returncode == 1 and message in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.iterdir())


def test_output_names_must_tell_the_images_apart(tmp_path, capsys):
    from pathtrace.cli.main import main
    assert main(["farm", "render", "simple", "demo", "-o", str(tmp_path / "x.png")]) == 1
    assert "several images would share a name" in capsys.readouterr().err
    assert main(["farm", "render", "simple", "-o", str(tmp_path / "{nope}.png")]) == 1
    assert "only {name} and {frame}" in capsys.readouterr().err
    # an orbit without frames was passed over without a word
    assert main(["farm", "render", "simple", "--orbit", "90", "-o", str(tmp_path / "x.png")]) == 1
    assert "--orbit: the turn of the frames' orbit; give --frames N too" in capsys.readouterr().err


def test_farm_render_from_the_command_line(tmp_path):
    """`pathtrace farm render` with a local cluster of its own: three frames of an orbit, each
    the one-process render of its camera."""
    pattern = str(tmp_path / "frame-{frame}.pfm")
    r = subprocess.run([sys.executable, "-m", "pathtrace", "farm", "render", "simple", "--size", "32x20",
                        "--spp", "12", "--frames", "3", "--orbit", "60", "--num-cpus", "2",
                        "--cpu-actors", "2", "-o", pattern, "-q"], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frame-0.pfm", "frame-1.pfm", "frame-2.pfm"]
    images = [read_hdr(tmp_path / f"frame-{k}.pfm", "test") for k in range(3)]
    assert all(np.isfinite(i).all() and i.shape == (20, 32, 3) for i in images)
    assert not np.allclose(images[0], images[2])


# --- Farm.render against a deterministic model of Ray: its actors run DeviceActor's own methods
# on renderers whose sums say which samples of which camera they hold, and the model's scheduler
# runs their calls, kills actors and fails calls at chosen random moments.

class _ModelError(Exception):
    pass


class _ModelRenderer:
    """Sums of one pixel: the samples' indices + 1, their squares, the camera (a number) per sample, and the count."""

    def set_camera(self, camera):
        self.camera, self.s = camera, np.zeros((1, 1, 4))

    def add_samples(self, count, start):
        i = np.arange(start, start + count) + 1.0
        self.s += [i.sum(), (i * i).sum(), count * (1000 * self.camera + 1), count]

    def choose_queue_plan(self, count):
        pass

    def finish(self):
        pass

    def read_sum(self):
        return self.s.copy()

    def read_sum_sq(self):
        return 2 * self.s


class _ModelCall:
    def __init__(self, actor, method, args):
        self.actor, self.method, self.args, self.state, self.result = actor, method, args, "queued", None


class _ModelActor:
    def __init__(self, model, impl, seconds_per_sample):
        self.model, self.impl, self.seconds_per_sample = model, impl, seconds_per_sample
        self.calls, self.dead = collections.deque(), False
        self.render = types.SimpleNamespace(remote=lambda *a: self.call("render", a))
        self.collect = types.SimpleNamespace(remote=lambda *a: self.call("collect", a))

    def call(self, method, args):
        c = _ModelCall(self, method, args)
        if self.dead:
            c.state = "failed"
        else:
            self.calls.append(c)
        return c


class _Model:
    """Ray as Farm.render uses it (wait, get, kill), run in this process."""

    def __init__(self, seed, actors, scenes, kills=0, failures=0):
        self.rng = random.Random(seed)
        self.kills, self.failures = kills, failures
        self.exceptions = types.SimpleNamespace(RayError=_ModelError)
        cls = farm._actor_class(types.SimpleNamespace(remote=lambda **_: (lambda c: c)))
        self.actors = []
        for _ in range(actors):
            impl = object.__new__(cls)
            impl.renderers, impl.jobs, impl.aside = [_ModelRenderer() for _ in range(scenes)], {}, {}
            self.actors.append(_ModelActor(self, impl, self.rng.choice([1e-3, 3e-3, 1e-2])))

    def kill(self, actor):
        actor.dead = True
        for c in actor.calls:
            c.state = "failed"
        actor.calls.clear()

    def step(self) -> bool:
        live = [a for a in self.actors if not a.dead]
        if self.kills and live and self.rng.random() < 0.05:
            self.kills -= 1
            self.kill(self.rng.choice(live))
            return True
        busy = [a for a in live if a.calls]
        if not busy:
            return False
        a = self.rng.choice(busy)
        c = a.calls.popleft()
        if self.failures and self.rng.random() < 0.05:      # the call fails, the actor lives on
            self.failures -= 1
            c.state = "failed"
            return True
        c.result = getattr(a.impl, c.method)(*c.args)
        if c.method == "render":
            c.result = c.args[4] * a.seconds_per_sample * self.rng.uniform(0.5, 1.5)
        c.state = "done"
        return True

    def wait(self, calls, num_returns=1):
        while True:
            ready = [c for c in calls if c.state != "queued"]
            if ready:
                pick = self.rng.choice(ready)
                return [pick], [c for c in calls if c is not pick]
            assert self.step(), "the farm waits on calls that no actor will answer"

    def get(self, call):
        if call.state == "failed":
            raise _ModelError(call.method)
        return call.result


def _model_scenes(n):
    settings = types.SimpleNamespace(width=1, height=1)
    return [types.SimpleNamespace(scene=types.SimpleNamespace(settings=settings)) for _ in range(n)]


def _expected(job):
    i = np.arange(job.spp) + 1.0
    return np.array([i.sum(), (i * i).sum(), job.spp * (1000 * job.camera + 1), job.spp])


@pytest.mark.parametrize("trouble", [dict(kills=4), dict(failures=3), dict(kills=2, failures=2)])
def test_every_sample_once_whatever_dies_or_fails_and_when(trouble):
    """Actors killed, and calls failing on living actors, at random moments of random renders
    (1-4 actors, 1-5 jobs over 1-2 scenes): every job's sums hold each of its samples once, of
    its own camera, and the progress adds up to what was asked; or, with every actor gone, the
    one-line error."""
    outcomes = collections.Counter()
    for seed in range(300):
        rng = random.Random(seed)
        scenes = rng.choice([1, 2])
        model = _Model(seed, rng.choice([1, 2, 3, 4]), scenes, **trouble)
        jobs = [farm.Job(rng.randrange(scenes), camera, rng.choice([1, 2, 5, 17, 40]))
                for camera in range(rng.randint(1, 5))]
        f = farm.Farm(model, [(a, "model") for a in model.actors], _model_scenes(scenes))
        reported = []
        try:
            sums, sums_sq = f.render(jobs, reported.append)
        except UserError as e:
            assert "every farm worker died" in str(e) and not f.actors
            outcomes["all died"] += 1
            continue
        for job, s, sq in zip(jobs, sums, sums_sq):
            np.testing.assert_array_equal(s[0, 0], _expected(job))
            np.testing.assert_array_equal(sq[0, 0], 2 * _expected(job))
        assert sum(reported) == sum(job.spp for job in jobs)
        outcomes["rendered"] += 1
    assert outcomes["rendered"] > 200, outcomes


def test_a_second_render_after_one_cut_short_holds_its_own_samples_alone():
    """A render stopped part-way (Ctrl-C reaches it through on_batch) leaves its sums on the
    actors; the same farm's next render does not add them to its own."""
    model = _Model(3, 2, 1)
    f = farm.Farm(model, [(a, "model") for a in model.actors], _model_scenes(1))

    def stop_at_the_third(count, calls=[]):
        calls.append(count)
        if len(calls) == 3:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        f.render([farm.Job(0, 7, 50)], stop_at_the_third)
    job = farm.Job(0, 1, 20)
    (s,), _ = f.render([job])
    np.testing.assert_array_equal(s[0, 0], _expected(job))
