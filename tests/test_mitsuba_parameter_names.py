"""The property names the Mitsuba reader reads, per plugin, against those Mitsuba 3's plugins read
(app/scene/mitsuba_known_properties.json, extracted from mitsuba-renderer/mitsuba3's sources: the
list the reader refuses unknown names by): a name the reader takes that Mitsuba 3 does not know
fails, as does a name the reader reads and tests/mitsuba_parameter_names.json does not list. A
property Mitsuba 3's plugin does not know is refused (Mitsuba 3 stops at it: "unreferenced
property"), one it knows and the reader does not read is warned of."""

import json
from pathlib import Path

import numpy as np
import pytest

import pathtrace.scene.mitsuba as mitsuba
from pathtrace.errors import UserError
from pathtrace.scene import known_names, load_scene
from tests.warned_scene import warnings_of_a_scene_that_renders

TABLE = json.loads((Path(__file__).parent / "mitsuba_parameter_names.json").read_text())    # what the reader reads
MITSUBA = known_names.document("mitsuba")                # what Mitsuba 3 reads, and where that was read

SPHERE = '<shape type="sphere"/>'
DIFFUSE = '<bsdf type="diffuse"/>'
BITMAP = '<texture type="bitmap" name="{name}"><string name="filename" value="t.png"/></texture>'
NAMELESS_BITMAP = '<texture type="bitmap"><string name="filename" value="t.png"/></texture>'  # bumpmap takes any
# one element of each plugin the reader takes, with what it cannot do without, in a scene of
# its own (a second environment would be left out whole)
CORPUS = {
    "integrator path": '<integrator type="path"/>',
    "integrator volpath": '<integrator type="volpath"/>',
    "integrator prb": '<integrator type="prb"/>',
    "integrator prbvolpath": '<integrator type="prbvolpath"/>',
    "sensor perspective": '<sensor type="perspective"/>',
    "sensor thinlens": '<sensor type="thinlens"><float name="aperture_radius" value="0.1"/></sensor>',
    "sensor orthographic": '<sensor type="orthographic"/>',
    "film hdrfilm": '<sensor type="perspective"><film type="hdrfilm"/></sensor>',
    "film specfilm": '<sensor type="perspective"><film type="specfilm"/></sensor>',
    "sampler independent": '<sensor type="perspective"><sampler type="independent"/></sensor>',
    "sampler stratified": '<sensor type="perspective"><sampler type="stratified"/></sensor>',
    "rfilter box": '<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>',
    "rfilter tent": '<sensor type="perspective"><film type="hdrfilm"><rfilter type="tent"/></film></sensor>',
    "rfilter gaussian": '<sensor type="perspective"><film type="hdrfilm"><rfilter type="gaussian"/></film></sensor>',
    "emitter constant": '<emitter type="constant"/>',
    "emitter envmap": '<emitter type="envmap"><string name="filename" value="e.pfm"/></emitter>',
    "emitter point": '<emitter type="point"/>',
    "emitter spot": '<emitter type="spot"/>',
    "emitter directional": '<emitter type="directional"/>',
    "emitter area": '<shape type="sphere"><emitter type="area"/></shape>',
    **{f"bsdf {kind}": f'<shape type="sphere"><bsdf type="{kind}"/></shape>'
       for kind in ("diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric", "thindielectric",
                    "plastic", "roughplastic", "principled", "null")},
    "bsdf twosided": f'<shape type="sphere"><bsdf type="twosided">{DIFFUSE}</bsdf></shape>',
    "bsdf mask": f'<shape type="sphere"><bsdf type="mask">{DIFFUSE}</bsdf></shape>',
    "bsdf normalmap": f'<shape type="sphere"><bsdf type="normalmap">{BITMAP.format(name="normalmap")}{DIFFUSE}'
                      '</bsdf></shape>',
    "bsdf bumpmap": f'<shape type="sphere"><bsdf type="bumpmap">{NAMELESS_BITMAP}{DIFFUSE}</bsdf></shape>',
    "bsdf blendbsdf": f'<shape type="sphere"><bsdf type="blendbsdf">{DIFFUSE}{DIFFUSE}</bsdf></shape>',
    "texture bitmap": f'<shape type="sphere"><bsdf type="diffuse">{BITMAP.format(name="reflectance")}</bsdf></shape>',
    "texture checkerboard": '<shape type="sphere"><bsdf type="diffuse"><texture type="checkerboard" '
                            'name="reflectance"/></bsdf></shape>',
    **{f"shape {kind}": f'<shape type="{kind}"/>' for kind in ("sphere", "rectangle", "cube", "disk", "cylinder")},
    "shape obj": '<shape type="obj"><string name="filename" value="t.obj"/></shape>',
    "shape ply": '<shape type="ply"><string name="filename" value="t.ply"/></shape>',
    "shape instance": f'<shape type="shapegroup" id="g">{SPHERE}</shape><shape type="instance"><ref id="g"/></shape>',
    "medium homogeneous": '<shape type="sphere"><bsdf type="null"/><medium type="homogeneous" name="interior"/></shape>',
    "phase hg": '<shape type="sphere"><bsdf type="null"/><medium type="homogeneous" name="interior">'
                '<phase type="hg"/></medium></shape>',
    "phase isotropic": '<shape type="sphere"><bsdf type="null"/><medium type="homogeneous" name="interior">'
                       '<phase type="isotropic"/></medium></shape>',
}


@pytest.fixture
def folder(tmp_path):
    from PIL import Image
    Image.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "t.png")
    (tmp_path / "e.pfm").write_bytes(b"PF\n2 2\n-1\n" + np.ones((2, 2, 3), "<f4").tobytes())
    (tmp_path / "t.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (tmp_path / "t.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    return tmp_path


def read_names(folder, monkeypatch, key) -> set:
    """The names the reader looked up in the properties of the corpus's `key` element."""
    seen = []
    original = mitsuba._Reader.warn_unread
    monkeypatch.setattr(mitsuba._Reader, "warn_unread", lambda self: (seen.append(self.props), original(self))[1])
    path = folder / "s.xml"
    extra = "" if CORPUS[key].startswith("<shape") else SPHERE
    path.write_text(f'<scene version="3.0.0">{CORPUS[key]}{extra}</scene>')
    load_scene(str(path))
    tag, kind = key.split(" ")
    found = [p for p in seen[0].values() if p.node.tag == tag and p.node.attrs.get("type") == kind]
    assert found, f"{key}: the reader never looked at the element's properties"
    return set().union(*(p.read for p in found))


@pytest.mark.parametrize("key", sorted(CORPUS))
def test_the_table_lists_what_the_reader_reads(folder, monkeypatch, key):
    assert sorted(read_names(folder, monkeypatch, key)) == sorted(TABLE["reader"][key])


@pytest.mark.parametrize("key", sorted(TABLE["reader"]))
def test_every_name_the_reader_reads_is_mitsuba_3s(key):
    unknown = set(TABLE["reader"][key]) - set(MITSUBA["mitsuba3"][key])
    assert not unknown, f"{key}: the reader reads {sorted(unknown)}, which Mitsuba 3's {key} does not"


def test_every_plugin_has_its_source():
    assert set(TABLE["reader"]) == set(CORPUS) == set(MITSUBA["mitsuba3"]) == set(MITSUBA["sources"])


@pytest.mark.parametrize("element,expected", [
    ('<shape type="sphere">\n<float name="radiuss" value="2"/>\n</shape>',
     "3: <float name=\"radiuss\">: 'radiuss' is not a property of Mitsuba 3's sphere shape, which Mitsuba 3 refuses; "
     "did you mean 'radius'?"),
    ('<shape type="sphere">\n<bsdf type="diffuse">\n<rgb name="reflectanse" value="0.5"/></bsdf>\n</shape>',
     "4: <rgb name=\"reflectanse\">: 'reflectanse' is not a property of Mitsuba 3's diffuse bsdf, which Mitsuba 3 "
     "refuses; did you mean 'reflectance'?"),
    # a texture is a property by its name too
    ('<shape type="sphere">\n<bsdf type="diffuse">\n<texture type="checkerboard" name="reflectence"/></bsdf>\n</shape>',
     "did you mean 'reflectance'?"),
    # a smooth dielectric has no microfacets to sample: Mitsuba 3's dielectric reads no sample_visible
    ('<shape type="sphere">\n<bsdf type="dielectric">\n<boolean name="sample_visible" value="true"/></bsdf>\n</shape>',
     "4: <boolean name=\"sample_visible\">: 'sample_visible' is not a property of Mitsuba 3's dielectric bsdf, which "
     "Mitsuba 3 refuses"),
])
def test_a_property_mitsuba_3_does_not_know_is_one_line_naming_the_element_and_closest_name(tmp_path, element,
                                                                                          expected):
    path = tmp_path / "s.xml"
    path.write_text(f'<scene version="3.0.0">\n{element}\n</scene>')
    with pytest.raises(UserError) as e:
        load_scene(str(path))
    message = str(e.value)
    assert message.startswith(f"{path}:") and expected in message and "\n" not in message, message


def test_a_property_mitsuba_3_knows_and_pathtrace_does_not_read_is_warned_of_once_and_renders(tmp_path, capsys,
                                                                                            backend):
    path = tmp_path / "s.xml"
    (tmp_path / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    path.write_text('<scene version="3.0.0">\n<integrator type="path"><boolean name="hide_emitters" value="true"/>'
                    '</integrator>\n<shape type="obj"><string name="filename" value="tri.obj"/>'
                    '<boolean name="flip_tex_coords" value="false"/></shape>\n'
                    '<shape type="obj"><string name="filename" value="tri.obj"/><boolean name="flip_tex_coords" '
                    'value="false"/></shape>\n<emitter type="constant"/><sensor type="perspective"><transform name="to_world">'
                    '<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform></sensor>\n</scene>')
    lines = warnings_of_a_scene_that_renders(path, capsys, backend)
    assert lines == [f"pathtrace: warning: {path}:3: <boolean name=\"flip_tex_coords\">: 'flip_tex_coords' is not a "
                     "property pathtrace's obj shape reads; ignored",
                     f"pathtrace: warning: {path}:2: <boolean name=\"hide_emitters\">: 'hide_emitters' is not a "
                     "property pathtrace's path integrator reads; ignored"], lines


def test_a_shape_takes_its_bsdf_by_its_place_whatever_its_name(tmp_path, capsys):
    """Mitsuba 3's Shape takes any BSDF object it holds (src/render/shape.cpp), as its exporters
    write it: <ref id="..." name="bsdf"/>."""
    path = tmp_path / "s.xml"
    path.write_text('<scene version="3.0.0"><bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0, 0"/>'
                    '</bsdf><shape type="sphere"><ref id="red" name="bsdf"/></shape>'
                    '<shape type="sphere"><bsdf type="conductor" name="surface"/></shape></scene>')
    scene = load_scene(str(path))
    assert capsys.readouterr().err == ""
    red, metal = (scene.materials.get(row) for row in scene.sphere_material)
    assert red.type == "diffuse" and np.allclose(red.params["rho_d"], [0.8, 0, 0]), red
    assert metal.type == "conductor", metal


def test_every_type_the_reader_takes_is_mitsuba_3s():
    """The reader refuses a type Mitsuba 3 has not (app/scene/known_names.py: refuse_unknown_type):
    every type it takes must be in that list, or a scene using it would be refused (but Mitsuba
    0.6's bdpt, which the integrators' table takes before any refusal)."""
    from pathtrace import cameras, filters
    from pathtrace.materials.surface import MITSUBA_WRAPPERS
    from pathtrace.parameters import by_format
    from pathtrace.scene import settings
    from pathtrace.scene.environment import Environment
    from pathtrace.shapes import SHAPES
    types = MITSUBA["types"]
    taken = {
        "bsdf": [*mitsuba.BSDFS_BY_NAME, *MITSUBA_WRAPPERS, "blendbsdf"],
        "texture": list(mitsuba.TEXTURES_BY_NAME),
        "shape": [*mitsuba.MESHES_BY_NAME, *SHAPES, "instance", "shapegroup"],
        "emitter": [*mitsuba.LIGHTS_BY_NAME, *Environment.mitsuba_plugins, "area"],
        "sensor": [c.mitsuba for c in cameras.CAMERAS.values() if c.mitsuba],
        "rfilter": list(by_format(filters.TYPES.values(), "mitsuba")),
        "integrator": [k for k in settings.Integrator.types["mitsuba"] if k != "bdpt"],
        "film": ["hdrfilm", "specfilm"], "medium": ["homogeneous"], "phase": ["hg", "isotropic"],
    }
    for category, names in taken.items():
        assert set(names) <= set(types[category]), (category, sorted(set(names) - set(types[category])))
