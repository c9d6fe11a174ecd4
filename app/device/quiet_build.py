"""A program's build without PyOpenCL's warning of a non-empty build log where the log says
nothing wrong, a warning that printed a line and PyOpenCL's source to a user's terminal:
- ptxas's register report, which the occupancy trials ask for and read (app/device/occupancy.py),
  and which a tuned binary rebuilt from the cache with its options gives again;
- NVIDIA's note, since its driver 550, that each kernel's noinline attribute is overridden,
  given for every kernel of every program though none asks for it (pyFAI issue 2368, John the
  Ripper issue 5456: harmless).
A log with anything else in it, a compiler's real warning, is passed on as before."""

import re
import warnings

import pyopencl as cl

# the line NVIDIA's driver writes for every kernel (seen with driver 580.159.04 on an H200)
KERNEL_NOINLINE_NOTE = re.compile(r"\(\): Warning: Function \w+ is a kernel, so overriding noinline attribute\. "
                                  r"The function may be inlined when called\.")


def build_quietly(program: cl.Program, options: list[str], devices=None, report: bool = False) -> cl.Program:
    """`program` built with `options` for `devices` (None: the program's). `report`: its log is
    expected (ptxas's report, which the caller reads), and never warned of."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        built = program.build(options=options, devices=devices)
    for w in caught:
        if issubclass(w.category, cl.CompilerWarning) and (report or says_nothing_wrong(built, devices)):
            continue
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return built


def says_nothing_wrong(program: cl.Program, devices=None) -> bool:
    """Whether every line of the program's build logs is blank or NVIDIA's kernel note."""
    for device in devices or program.get_info(cl.program_info.DEVICES):
        log = program.get_build_info(device, cl.program_build_info.LOG) or ""
        if any(line.strip() and not KERNEL_NOINLINE_NOTE.fullmatch(line.strip()) for line in log.splitlines()):
            return False
    return True
