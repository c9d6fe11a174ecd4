"""Every registered light type (pathtrace.lights.registry.LIGHTS) through next-event estimation:
a light that paths can hit (area lights, the environment) against the image of paths alone,
which meet it by chance; a delta light, which no path can hit, by its declared examples
(DeltaLight.examples) chosen by power and through the light tree alike, and dark without NEE.
A new type is tested by being registered. One program (the generic one) renders them all."""

import numpy as np
import pytest

from pathtrace.lights.registry import DELTA_LIGHTS, LIGHTS
from pathtrace.scene.toml_reader import read_scene_dict
from tests.test_lights import floor_under
from tests.test_nee import SCENE_SPP_BY_NEE, image_mean

FLOOR = {"camera": {"eye": [0, 2.5, 3.5], "look_at": [0, 0.3, 0]},
         "render": {"max_depth": 3, "russian_roulette": "off"},
         "materials": {"floor": {"type": "diffuse", "rho_d": [0.7, 0.5, 0.3]}},
         "meshes": [{"vertices": [[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]], "faces": [[0, 3, 2, 1]],
                     "material": "floor"}]}
# the lights that paths can hit, each in a scene of its own: a small emitting sphere over the
# floor in a black world; the floor and a ball under a sky
HIT_SCENES = {
    "area": {**FLOOR, "environment": {"color": 0},
             "spheres": [{"center": [0.5, 0.8, 0], "radius": 0.25, "material": {"type": "emitter", "Le": [8, 6, 4]}}]},
    "environment": {**FLOOR, "environment": {"color": [0.6, 0.7, 1.0]},
                    "spheres": [{"center": [0, 0.5, 0], "radius": 0.5, "material": {"type": "diffuse", "rho_d": 0.8}}]},
}
DELTA_EXAMPLES = [(f"{name}-{k}", {"type": name, **params}) for name, cls in DELTA_LIGHTS.items()
                  for k, params in enumerate(cls.examples)]


@pytest.fixture(autouse=True)
def generic_program(monkeypatch):
    monkeypatch.setenv("PATHTRACE_PROGRAM", "generic")


def test_every_registered_type_is_in_the_suite():
    """A delta light by the examples it declares; one that paths can hit by a scene above."""
    for name in LIGHTS:
        if name in DELTA_LIGHTS:
            assert DELTA_LIGHTS[name].__dict__.get("examples"), f"{name} declares no examples"
        else:
            assert name in HIT_SCENES, f"light type {name} has no scene here"


@pytest.mark.parametrize("name", list(HIT_SCENES))
def test_nee_by_power_and_by_the_tree_converge_to_the_image_of_paths_alone(backend, name):
    scene = read_scene_dict(HIT_SCENES[name], name).with_settings(seed=3)
    plain, plain_error = image_mean(backend, scene.with_settings(nee=False), SCENE_SPP_BY_NEE[False])
    assert np.all(plain > 0)
    for sampler in ("power", "tree"):
        mean, error = image_mean(backend, scene.with_settings(nee=True, light_sampler=sampler, seed=4),
                                 SCENE_SPP_BY_NEE[True])
        assert np.all(np.abs(mean - plain) <= 5 * np.hypot(error, plain_error) + 1e-6 * plain), (sampler, mean, plain)


@pytest.mark.parametrize("key,light", DELTA_EXAMPLES, ids=[key for key, _ in DELTA_EXAMPLES])
def test_a_delta_light_lights_alike_through_either_sampler_and_never_without_nee(backend, key, light):
    """Chosen by power or through the light tree (whose bounds of the light, tree_bounds, once
    refused every point a hard-edged spot lit: review 2026-11-28, F4), the floor's image is the
    same within noise, and lit; without next-event estimation it is black. The light is given
    twice, so that the tree has two leaves to choose between (one light makes no tree)."""
    by_power, _, _, error = floor_under([light, light], backend, sampler="power")
    by_tree, _, _, tree_error = floor_under([light, light], backend, sampler="tree")
    assert by_power.max() > 0
    assert np.all(np.abs(by_power - by_tree) <= 5 * np.hypot(error, tree_error) + 1e-5 * by_power + 1e-7)
    assert floor_under(light, backend, nee=False)[0].max() == 0
