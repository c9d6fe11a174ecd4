"""The pbrt tokenizer (app/scene/pbrt/tokens.py): the short bracketed lists converted in bulk
read as each converted alone would, with the same checks, and lists that hold words fall back
to words, so that the bulk pass changes only the time a file takes."""

from pathlib import Path

import numpy as np
import pytest

from pathtrace.errors import UserError
from pathtrace.scene.pbrt.tokens import FLOAT32_MAX, Tokens, _list_tokens

LISTS = ["[ 1 2 3 ]", "[]", "[ \n ]", "[-1.5e3\t+2 .5]", "[ 1e40 ]", "[ nan 1 ]", "[ inf ]", "[ 2147483648 ]",
         "[ -2147483647 ]", "[ 2.5 ]", "[ 0 1 2\n 3 4 5 ]"]


def _same(a, b):
    return a[0] == b[0] and a[2] == b[2] and (np.array_equal(a[1], b[1], equal_nan=True) if a[0] == "numbers"
                                              else a[1] == b[1])


@pytest.mark.parametrize("words", [[], ["true"], ["1-2"], ["0x10"]])
def test_lists_converted_in_bulk_read_as_each_alone(words):
    # `words`: a list the bulk pass cannot take, which sends every list the one-by-one way
    lists = LISTS + [f"[ {' '.join(words)} ]"] * bool(words)
    text = 'Shape "x" # a comment [ 1 2 ]\n' + "\n".join(f'"float p{k}" {v}' for k, v in enumerate(lists))
    tokens = Tokens(text, Path("f.pbrt"))
    expected = [("word", "Shape", 0), ("string", "x", 6)]
    at = text.index("\n") + 1
    for k, v in enumerate(lists):
        expected.append(("string", f"float p{k}", at))
        at += len(f'"float p{k}" ')
        expected.extend(_list_tokens("list", v, at))
        at += len(v) + 1
    expected.append(("end", None, len(text)))
    assert len(tokens.tokens) == len(expected) and all(map(_same, tokens.tokens, expected)), tokens.tokens
    for kind, value, offset in tokens.tokens:
        if offset in tokens.checked:
            in_range = bool(np.all(np.abs(value) <= FLOAT32_MAX))
            whole = in_range and bool(np.all((value == np.round(value)) & (np.abs(value) < 2**31)))
            assert tokens.checked[offset] == (in_range, whole), (value, tokens.checked[offset])
    assert bool(tokens.checked) == (not words)


def test_tokens_name_their_lines():
    tokens = Tokens('A\n\n"b" [ 1\n2 ]\n  C', Path("f.pbrt"))
    assert [tokens.line(offset) for _, _, offset in tokens.tokens] == [1, 3, 3, 5, 5]
    with pytest.raises(UserError, match=r"^f.pbrt:2: an unterminated string$"):
        Tokens('A\n"b\n"', Path("f.pbrt"))
