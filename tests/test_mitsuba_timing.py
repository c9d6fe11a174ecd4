"""Mitsuba 3 timed beside pathtrace (app/bench/mitsuba_timing.py), against a stand-in Mitsuba and Dr.Jit
that record the renders asked of them: the timed render must find its kernels compiled."""

import json
import sys
import types

import pytest

from pathtrace.bench.mitsuba_timing import mitsuba_render

# Records each render (its sample count and seed) to the file named by $RENDERS.
FAKE_MITSUBA = """
import json, os
class _Transform:
    def look_at(self, origin, target, up):
        return self
def set_variant(variant): pass
def load_file(path): return {"file": path}
def load_dict(d): return d
def ScalarTransform4f(): return _Transform()
def render(scene, sensor=None, integrator=None, spp=1, seed=0):
    with open(os.environ["RENDERS"], "a") as f:
        f.write(json.dumps({"spp": spp, "seed": seed}) + "\\n")
    return [[[0.5, 0.5, 0.5]]]
"""
FAKE_DRJIT = "def eval(*args): pass\ndef sync_thread(): pass\n"


def fake_mitsuba(folder):
    """The stand-in Mitsuba and Dr.Jit as packages in `folder`, to put on PYTHONPATH."""
    for name, text in (("mitsuba", FAKE_MITSUBA), ("drjit", FAKE_DRJIT)):
        (folder / name).mkdir()
        (folder / name / "__init__.py").write_text(text)


@pytest.mark.parametrize("rounds", [1, 3])
def test_the_timed_render_follows_an_untimed_one_of_the_same_sample_count(tmp_path, monkeypatch, rounds):
    """Dr.Jit compiles a kernel per sample count (Mitsuba 3.9.1's log: 1 and 2 spp share one,
    16 and 32 another, 24 and 48 a third), so a 1-spp warm-up left the timed render to compile
    its own, inside the timed region. With rounds, each timed render has a seed of its own."""
    fake_mitsuba(tmp_path)
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    monkeypatch.setenv("RENDERS", str(tmp_path / "renders.jsonl"))
    camera = types.SimpleNamespace(eye=(0, 1, 5), look_at=(0, 0, 0), up=(0, 1, 0), vfov=40.0)
    seconds, mean = mitsuba_render(sys.executable, "scalar_rgb", tmp_path / "scene.xml", camera, 8, 4, 24, 8,
                                   rounds)
    renders = [json.loads(line) for line in (tmp_path / "renders.jsonl").read_text().splitlines()]
    assert [r["spp"] for r in renders] == [24] * (1 + rounds)
    assert len({r["seed"] for r in renders}) == 1 + rounds
    assert len(seconds) == rounds and min(seconds) >= 0 and mean == 0.5
