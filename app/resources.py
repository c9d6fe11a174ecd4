"""Where the kernels, shaders and assets are: inside the installed package (the wheel carries
them as pathtrace/kernels, pathtrace/shaders, pathtrace/assets) or beside it in a source checkout."""

from pathlib import Path

from pathtrace.errors import UserError

_HERE = Path(__file__).resolve().parent


def resource_dir(name: str) -> Path:
    for candidate in (_HERE / name, _HERE.parent / name):
        if candidate.is_dir():
            return candidate
    raise UserError(f"pathtrace is incomplete: its '{name}' folder is missing; install it again (./install.sh in a checkout)")
