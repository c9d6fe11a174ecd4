"""The one exception type the command line turns into a message and a non-zero exit."""


class UserError(Exception):
    """A problem with what the user gave us (a file, a field, a flag), stated in one line that
    names where it is and what is wrong."""
