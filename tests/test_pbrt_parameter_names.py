"""The parameter names the pbrt reader reads, per pbrt-v4 type, against those pbrt-v4's Create()
functions read (tests/pbrt_parameter_names.json, extracted from pbrt-v4's sources): a name the
reader takes that pbrt-v4 does not know (as `conedelta` was, for `conedeltaangle`) fails."""

import json
from pathlib import Path

import numpy as np
import pytest

import pathtrace.scene.pbrt.reader as pbrt_reader
from pathtrace.scene import load_scene
from pathtrace.scene.pbrt.tokens import ParamList

TABLE = json.loads((Path(__file__).parent / "pbrt_parameter_names.json").read_text())

# one directive of each type, with what it cannot do without; the line's key in TABLE
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
]


def names_read(tmp_path, monkeypatch) -> dict:
    """Per key of CORPUS, the names the reader looked up (ParamList.get or type_of) in that
    directive's parameters, from a file of CORPUS's lines."""
    from PIL import Image
    Image.fromarray(np.zeros((2, 2, 3), np.uint8)).save(tmp_path / "t.png")
    lines, keys = [], {}
    for key, text in CORPUS:
        lines += text.split("\n")
        keys[len(lines)] = key                  # the key of the directive on the last line
    (tmp_path / "s.pbrt").write_text("WorldBegin\n" + "\n".join(lines) + '\nShape "sphere"\n')
    read, owner = {}, {}
    original_parameters, get, type_of = pbrt_reader.parameters, ParamList.get, ParamList.type_of

    def parameters(tokens):
        params = original_parameters(tokens)
        owner[id(params)] = int(tokens.where(tokens.peek()[2] - 1).rsplit(":", 1)[1]) - 1   # the directive's line
        return params

    def note(params, name):
        key = keys.get(owner.get(id(params)))
        if key:
            read.setdefault(key, set()).add(name)
    monkeypatch.setattr(pbrt_reader, "parameters", parameters)
    monkeypatch.setattr(ParamList, "get", lambda self, name, *a, **k: (note(self, name), get(self, name, *a, **k))[1])
    monkeypatch.setattr(ParamList, "type_of", lambda self, name: (note(self, name), type_of(self, name))[1])
    load_scene(str(tmp_path / "s.pbrt"))
    return read


def test_the_table_lists_what_the_reader_reads(tmp_path, monkeypatch):
    read = names_read(tmp_path, monkeypatch)
    assert {k: sorted(v) for k, v in read.items()} == {k: sorted(v) for k, v in TABLE["reader"].items()}


@pytest.mark.parametrize("key", sorted(TABLE["reader"]))
def test_every_name_the_reader_reads_is_pbrt_v4s(key):
    unknown = set(TABLE["reader"][key]) - set(TABLE["pbrt-v4"][key])
    assert not unknown, f"{key}: the reader reads {sorted(unknown)}, which pbrt-v4 does not"
