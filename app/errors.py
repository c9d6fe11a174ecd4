"""The one exception type the command line turns into a message and a non-zero exit."""


class UserError(Exception):
    """A problem with what the user gave us (a file, a field, a flag), stated in one line that
    names where it is and what is wrong."""


def warn(message: str):
    """One warning line on standard error: something pathtrace did instead of what was asked."""
    import sys
    print(f"pathtrace: warning: {message}", file=sys.stderr)


def format_bytes(n: float) -> str:
    """A size for messages: '512 MB', '6.4 GB'."""
    for unit, size in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{int(n)} bytes"


def short(value) -> str:
    """A value the user gave, for a message: its repr (quoted, escapes shown), cut to 60
    characters, so that a huge or binary value cannot flood the terminal."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
