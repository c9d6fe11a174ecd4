"""The parameter names the pbrt reader reads, per pbrt-v4 type, against those pbrt-v4's Create()
functions read (app/scene/pbrt/known_parameters.json, extracted from pbrt-v4's sources: the list
the reader refuses unknown names by), for every directive whose parameters it reads: lights,
materials, textures, media, shapes, cameras, the film, samplers, integrators and filters. A name
the reader takes that pbrt-v4 does not know (as `conedelta` was, for `conedeltaangle`) fails, as
does one the reader reads and tests/pbrt_parameter_names.json does not list. A name pbrt-v4 does
not know is refused (pbrt-v4 stops at it: ParameterDictionary::ReportUnused), one it knows and
the reader does not read is warned of."""

import json
from pathlib import Path

import numpy as np
import pytest

import pathtrace.scene.pbrt.options as pbrt_options
import pathtrace.scene.pbrt.reader as pbrt_reader
import pathtrace.scene.pbrt.state as pbrt_state
from pathtrace.scene import known_names, load_scene
from pathtrace.scene.pbrt.tokens import ParamList
from tests.commands import in_process
from tests.warned_scene import warnings_of_a_scene_that_renders


TABLE = json.loads((Path(__file__).parent / "pbrt_parameter_names.json").read_text())    # what the reader reads
PBRT = known_names.document("pbrt")                      # what pbrt-v4 reads, and where that was read

# one directive of each type, with what it cannot do without; the line's key in TABLE. OPTIONS
# come before WorldBegin; a Camera's parameters are read once the file is read, so each file
# has one camera
OPTIONS = [
    ("film rgb", 'Film "rgb"'),
    ("sampler independent", 'Sampler "independent"'),
    ("sampler stratified", 'Sampler "stratified"'),
    ("sampler zsobol", 'Sampler "zsobol"'),
    ("integrator volpath", 'Integrator "volpath"'),
    ("integrator path", 'Integrator "path"'),
    ("integrator bdpt", 'Integrator "bdpt"'),
    ("integrator mlt", 'Integrator "mlt"'),
    ("integrator sppm", 'Integrator "sppm"'),
    ("filter triangle", 'PixelFilter "triangle"'),
    ("filter box", 'PixelFilter "box"'),
    ("filter gaussian", 'PixelFilter "gaussian"'),
]
CAMERAS = [("camera perspective", 'Camera "perspective"'), ("camera orthographic", 'Camera "orthographic"'),
           ("camera spherical", 'Camera "spherical"')]
CORPUS = [
    ("light point", 'LightSource "point"'),
    ("light spot", 'LightSource "spot"'),
    ("light distant", 'LightSource "distant"'),
    ("light infinite", 'LightSource "infinite"'),
    ("arealight diffuse", 'AttributeBegin\nAreaLightSource "diffuse"'),
    (None, 'Shape "sphere"\nAttributeEnd'),
    ("material diffuse", 'MakeNamedMaterial "a" "string type" "diffuse"'),
    ("material conductor", 'MakeNamedMaterial "b" "string type" "conductor"'),
    ("material dielectric", 'MakeNamedMaterial "c" "string type" "dielectric"'),
    ("material thindielectric", 'MakeNamedMaterial "d" "string type" "thindielectric"'),
    ("material coateddiffuse", 'MakeNamedMaterial "e" "string type" "coateddiffuse"'),
    ("material coatedconductor", 'MakeNamedMaterial "f" "string type" "coatedconductor"'),
    ("material diffusetransmission", 'MakeNamedMaterial "g" "string type" "diffusetransmission"'),
    ("material mix", 'MakeNamedMaterial "h" "string type" "mix" "string materials" [ "a" "b" ]'),
    ("texture constant", 'Texture "t1" "spectrum" "constant"'),
    ("texture bilerp", 'Texture "t2" "spectrum" "bilerp"'),
    ("texture checkerboard", 'Texture "t3" "spectrum" "checkerboard"'),
    ("texture imagemap", 'Texture "t4" "spectrum" "imagemap" "string filename" "t.png"'),
    ("texture mix", 'Texture "t5" "spectrum" "mix"'),
    ("texture scale", 'Texture "t6" "spectrum" "scale"'),
    ("medium homogeneous", 'MakeNamedMedium "m" "string type" "homogeneous"'),
    ("shape sphere", 'Shape "sphere"'),
    ("shape disk", 'Shape "disk"'),
    ("shape cylinder", 'Shape "cylinder"'),
    ("shape trianglemesh", 'Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ]'),
    ("shape bilinearmesh", 'Shape "bilinearmesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 1 1 0 ]'),
    ("shape loopsubdiv", 'Shape "loopsubdiv" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]'),
    ("shape plymesh", 'Shape "plymesh" "string filename" "t.ply"'),
]


def names_read(tmp_path, monkeypatch, options, world) -> dict:
    """Per key of `options` and `world` (lists like CORPUS), the names the reader looked up
    (ParamList.get or type_of) in that directive's parameters, from a file of their lines."""
    from PIL import Image
    Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "t.png")
    (tmp_path / "t.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    lines, keys = [], {}
    for key, text in options + [(None, "WorldBegin")] + world:
        lines += text.split("\n")
        keys[len(lines)] = key                  # the key of the directive on the last line (1-based)
    (tmp_path / "s.pbrt").write_text("\n".join(lines) + '\nShape "sphere"\n')
    read, owner = {}, {}
    original_parameters, get, type_of = pbrt_reader.parameters, ParamList.get, ParamList.type_of

    def parameters(tokens):
        params = original_parameters(tokens)
        owner[id(params)] = int(tokens.where(tokens.peek()[2] - 1).rsplit(":", 1)[1])   # the directive's line
        return params

    def note(params, name):
        key = keys.get(owner.get(id(params)))
        if key:
            read.setdefault(key, set()).add(name)
    with monkeypatch.context() as m:
        for module in (pbrt_reader, pbrt_options, pbrt_state):     # each reads its directives' parameters
            m.setattr(module, "parameters", parameters)
        m.setattr(ParamList, "get", lambda self, name, *a, **k: (note(self, name), get(self, name, *a, **k))[1])
        m.setattr(ParamList, "type_of", lambda self, name: (note(self, name), type_of(self, name))[1])
        load_scene(str(tmp_path / "s.pbrt"))
    return read


def all_names_read(tmp_path, monkeypatch) -> dict:
    read = {}
    for i, camera in enumerate(CAMERAS):
        folder = tmp_path / str(i)
        folder.mkdir()
        read.update(names_read(folder, monkeypatch, [camera] + (OPTIONS if i == 0 else []), CORPUS if i == 0 else []))
    return read


def test_the_table_lists_what_the_reader_reads(tmp_path, monkeypatch):
    read = all_names_read(tmp_path, monkeypatch)
    assert {k: sorted(v) for k, v in read.items()} == {k: sorted(v) for k, v in TABLE["reader"].items()}


@pytest.mark.parametrize("key", sorted(TABLE["reader"]))
def test_every_name_the_reader_reads_is_pbrt_v4s(key):
    unknown = set(TABLE["reader"][key]) - set(PBRT["pbrt-v4"][key])
    assert not unknown, f"{key}: the reader reads {sorted(unknown)}, which pbrt-v4 does not"


def test_every_type_has_its_source():
    assert {k.split(" ")[0] for k in PBRT["pbrt-v4"]} == set(PBRT["sources"])
    assert set(TABLE["reader"]) <= set(PBRT["pbrt-v4"])


HEAD = 'LookAt 0 0 5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nLightSource "point" "rgb I" [ 5 5 5 ] "point3 from" [ 0 0 4 ]\n'


@pytest.mark.parametrize("line,expected", [
    ('Shape "sphere" "float radisu" 1', "'radisu' is not a parameter of pbrt-v4's sphere shape, which pbrt-v4 "
                                        "refuses; did you mean 'radius'?"),
    ('Material "diffuse" "rgb reflectanse" [ 1 0 0 ]\nShape "sphere"',
     "'reflectanse' is not a parameter of pbrt-v4's diffuse material, which pbrt-v4 refuses; did you mean 'reflectance'?"),
    # the name the reader once took for pbrt-v4's
    ('LightSource "spot" "float conedelta" 5\nShape "sphere"', "spot light, which pbrt-v4 refuses; did you mean "
                                                               "'conedeltaangle'?"),
    ('AreaLightSource "diffuse" "bool two_sided" true\nShape "sphere"',
     "'two_sided' is not a parameter of pbrt-v4's diffuse area light, which pbrt-v4 refuses; did you mean 'twosided'?"),
    # nothing close: no guess
    ('Shape "sphere" "float zzz" 1', "'zzz' is not a parameter of pbrt-v4's sphere shape, which pbrt-v4 refuses"),
])
def test_a_name_pbrt_v4_does_not_know_is_one_line_naming_the_file_line_type_and_closest_name(tmp_path, line, expected):
    (tmp_path / "s.pbrt").write_text(HEAD + line + "\n")
    r = in_process("render", tmp_path / "s.pbrt", "-o", tmp_path / "x.exr", "--size", "8x8", "--spp", "1")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert lines[0].startswith(f"pathtrace: error: {tmp_path / 's.pbrt'}:5: ") and expected in lines[0], lines[0]
    assert expected.endswith("refuses") == ("did you mean" not in lines[0])
    assert not (tmp_path / "x.exr").exists()


def test_a_name_pbrt_v4_knows_and_pathtrace_does_not_read_is_warned_of_once_and_renders(tmp_path, capsys, backend):
    # pbrt-v4's coateddiffuse reads 'twosided' and its samplers 'seed'; pathtrace's do not
    (tmp_path / "s.pbrt").write_text('Sampler "zsobol" "integer seed" 3 "integer pixelsamples" 1\n' + HEAD
                                     + 'Material "coateddiffuse" "bool twosided" true\nShape "sphere"\n'
                                     + 'Material "coateddiffuse" "bool twosided" false\nShape "sphere" "float radius" 2\n')
    lines = warnings_of_a_scene_that_renders(tmp_path / "s.pbrt", capsys, backend)
    assert lines == [f"pathtrace: warning: {tmp_path / 's.pbrt'}:1: 'seed' is not a parameter pathtrace's zsobol "
                     "sampler reads; ignored",
                     f"pathtrace: warning: {tmp_path / 's.pbrt'}:6: 'twosided' is not a parameter pathtrace's "
                     "coateddiffuse material reads; ignored"], lines


def test_what_a_bidirectional_integrator_has_and_pathtrace_does_not_is_warned_of(tmp_path, capsys, backend):
    """pbrt-v4's bdpt reads 'visualizestrategies', which pathtrace renders without; its mlt reads
    'chains', which a replacement by bdpt has no use for: warned of, not refused."""
    (tmp_path / "s.pbrt").write_text('Integrator "bdpt" "integer maxdepth" 3 "bool visualizestrategies" true\n' + HEAD
                                     + 'Shape "sphere"\n')
    lines = warnings_of_a_scene_that_renders(tmp_path / "s.pbrt", capsys, backend)
    assert lines == [f"pathtrace: warning: {tmp_path / 's.pbrt'}:1: 'visualizestrategies' is not a parameter "
                     "pathtrace's bdpt integrator reads; ignored"], lines
    (tmp_path / "s.pbrt").write_text('Integrator "mlt" "integer chains" 10\n' + HEAD + 'Shape "sphere"\n')
    lines = warnings_of_a_scene_that_renders(tmp_path / "s.pbrt", capsys, backend)
    assert f"pathtrace: warning: {tmp_path / 's.pbrt'}:1: 'chains' is not a parameter pathtrace's mlt integrator " \
           "reads; ignored" in lines, lines


def test_every_type_the_reader_takes_is_pbrt_v4s():
    """The reader refuses a type pbrt-v4 has not (app/scene/known_names.py: refuse_unknown_type):
    every type it takes must be in that list, or a scene using it would be refused."""
    from pathtrace import cameras
    from pathtrace.scene import settings
    from pathtrace.scene.pbrt.materials import BSDFS_BY_NAME
    from pathtrace.shapes import SHAPES
    types = PBRT["types"]
    taken = {
        "shape": [*pbrt_reader.MESHES_BY_NAME, *SHAPES],
        "material": [*BSDFS_BY_NAME, "mix", "interface", "none", ""],
        "light": [*pbrt_reader.LIGHTS_BY_NAME, "infinite"],
        "camera": [c.pbrt for c in cameras.CAMERAS.values() if c.pbrt],
        "integrator": list(settings.Integrator.types["pbrt"]),
        "film": ["rgb", "gbuffer", "spectral"],
    }
    for category, names in taken.items():
        assert set(names) <= set(types[category]), (category, sorted(set(names) - set(types[category])))
