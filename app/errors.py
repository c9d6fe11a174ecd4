"""The one exception type the command line turns into a message and a non-zero exit."""


class UserError(Exception):
    """A problem with what the user gave us (a file, a field, a flag), stated in one line that
    names where it is and what is wrong."""


def warn(message: str):
    """One warning line on standard error: something pathtrace did instead of what was asked."""
    import sys
    print(f"pathtrace: warning: {message}", file=sys.stderr)
