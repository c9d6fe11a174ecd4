"""The property names the Mitsuba reader reads, per plugin, against those Mitsuba 3's plugins read
(tests/mitsuba_parameter_names.json, extracted from mitsuba-renderer/mitsuba3's sources): a name
the reader takes that Mitsuba 3 does not know fails, as does a name the reader reads and the
table does not list. Every property the reader does not read is warned of, naming it."""

import json
from pathlib import Path

import numpy as np
import pytest

import pathtrace.scene.mitsuba as mitsuba
from pathtrace.scene import load_scene

TABLE = json.loads((Path(__file__).parent / "mitsuba_parameter_names.json").read_text())

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
    **{f"shape {kind}": f'<shape type="{kind}"/>' for kind in ("sphere", "rectangle", "cube", "disk")},
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
    unknown = set(TABLE["reader"][key]) - set(TABLE["mitsuba3"][key])
    assert not unknown, f"{key}: the reader reads {sorted(unknown)}, which Mitsuba 3's {key} does not"


def test_every_plugin_has_its_source():
    assert set(TABLE["reader"]) == set(CORPUS) == set(TABLE["mitsuba3"]) == set(TABLE["sources"])


def test_a_property_the_reader_does_not_read_is_warned_of(tmp_path, capsys):
    path = tmp_path / "s.xml"
    path.write_text('<scene version="3.0.0">\n<shape type="sphere">\n<float name="radiuss" value="2"/>\n'
                    '<bsdf type="dielectric"><boolean name="sample_visible" value="true"/></bsdf>\n'
                    '</shape>\n<integrator type="path"><boolean name="hide_emitters" value="true"/></integrator>\n'
                    '</scene>')
    load_scene(str(path))
    err = capsys.readouterr().err
    assert f"{path}:3: <float name=\"radiuss\">: 'radiuss' is not a property pathtrace's sphere shape reads; " \
           "ignored" in err
    # a smooth dielectric has no microfacets to sample (Mitsuba 3's dielectric does not read it)
    assert "'sample_visible' is not a property pathtrace's dielectric bsdf reads" in err
    assert "'hide_emitters' is not a property pathtrace's path integrator reads" in err
