"""The one exception type the command line turns into a message and a non-zero exit."""

import re
import threading


class UserError(Exception):
    """A problem with what the user gave us (a file, a field, a flag), stated in one line that
    names where it is and what is wrong."""


_local = threading.local()     # .held: the warnings each open grouped_warnings() of this thread collects


def _held() -> list:
    if not hasattr(_local, "held"):
        _local.held = []
    return _local.held


def warn(message: str):
    """One warning line on standard error: something pathtrace did instead of what was asked
    (held, within grouped_warnings() in the same thread, to be told once with a count)."""
    held = _held()
    if held:
        held[-1].append(message)
        return
    import sys
    print(f"pathtrace: warning: {message}", file=sys.stderr)


def held_warnings() -> list:
    """The warnings that the innermost grouped_warnings() of this thread holds so far."""
    held = _held()
    return list(held[-1]) if held else []


class grouped_warnings:
    """Around the reading of a file: its warnings each once, with a count of the others like it
    ("3 like this; the first: scene.pbrt:7: 'bogus' is not a parameter ..."), where "like" is
    the same text once the leading place (path:line:) and quoted names are set aside, so that
    100,000 unknown parameters print one line, not 100,000."""

    def __enter__(self):
        _held().append([])

    def __exit__(self, *exc):
        groups = {}
        for message in _held().pop():
            key = re.sub(r"'[^']*'", "''", re.sub(r"^.*?:\d+: ", "", message))
            groups.setdefault(key, []).append(message)
        for messages in groups.values():
            warn(messages[0] if len(messages) == 1 else f"{len(messages)} like this; the first: {messages[0]}")


def with_article(word: str) -> str:
    """The word after its indefinite article: "an orthographic", "a perspective"."""
    return f"{'an' if word[:1].lower() in 'aeiou' else 'a'} {word}"


def format_bytes(n: float) -> str:
    """A size for messages: '512 MB', '6.4 GB'."""
    for unit, size in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} bytes"


def cut(text: str, limit: int = 60) -> str:
    """Text the user gave, for a message: characters that do not print (NUL, escape sequences)
    shown as escapes, and cut to `limit` characters, so that a huge or binary value cannot flood
    or garble the terminal."""
    text = escape(text)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def escape(text: str) -> str:
    """Characters that do not print (a newline, NUL, an escape sequence) as Python escapes, so
    that a message stays one line and cannot drive the terminal."""
    return text if text.isprintable() else "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def did_you_mean(given: str, choices, quoted=False) -> str:
    """"; did you mean X?" (X in single quotes where `quoted`) where one of `choices` is close to
    what was given (difflib's ratio of at least 0.6), else ""."""
    import difflib
    close = difflib.get_close_matches(given, list(choices), n=1)
    return f"; did you mean {repr(close[0]) if quoted else close[0]}?" if close else ""


def short(value) -> str:
    """A value the user gave, for a message: its repr (quoted, escapes shown), cut to 60
    characters; a boolean as the scene formats write it (true, not Python's True), a NumPy
    scalar as its number."""
    if type(value).__module__ == "numpy" and hasattr(value, "item") and getattr(value, "ndim", None) == 0:
        value = value.item()     # a NumPy scalar as the number it is, not NumPy's repr (np.int32(99))
    if isinstance(value, bool):
        return "true" if value else "false"
    return cut(repr(value))
