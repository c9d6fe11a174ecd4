"""A program's build, and what its build log says, in pathtrace's words. PyOpenCL warns of every
non-empty build log (CompilerWarning), which printed a line of its source to a user's terminal
for logs that say nothing wrong:
- ptxas's register report, which the occupancy trials ask for and read (app/device/occupancy.py),
  and which a tuned binary rebuilt from the cache with its options gives again;
- NVIDIA's note, since its driver 550, that each kernel's noinline attribute is overridden,
  given for every kernel of every program though none asks for it (pyFAI issue 2368, John the
  Ripper issue 5456: harmless).
So PyOpenCL's warning is not shown (one filter for the process, set when pathtrace opens a
device: a filter changed around each build is not thread-safe, and builds run in threads), and
each build's log is read here instead: a line that is neither of those, a compiler's real
warning, is one warning line of pathtrace's."""

import re
import warnings

import pyopencl as cl

from pathtrace.errors import cut, warn

warnings.filterwarnings("ignore", category=cl.CompilerWarning)

# the line NVIDIA's driver writes for every kernel (seen with driver 580.159.04 on an H200)
KERNEL_NOINLINE_NOTE = re.compile(r"\(\): Warning: Function \w+ is a kernel, so overriding noinline attribute\. "
                                  r"The function may be inlined when called\.")


def build_quietly(program: cl.Program, options: list[str], devices=None, report: bool = False) -> cl.Program:
    """`program` built with `options` for `devices` (None: the program's), and a warning of its
    log's lines that say something (log_lines). `report`: the log holds ptxas's report, which
    the caller reads."""
    built = program.build(options=options, devices=devices)
    for device in devices or built.get_info(cl.program_info.DEVICES):
        lines = log_lines(built.get_build_info(device, cl.program_build_info.LOG) or "", report)
        if lines:
            more = f" (and {len(lines) - 1} more lines)" if len(lines) > 1 else ""
            warn(f"{device.name.strip()}: the kernels' build log says: {cut(lines[0], 200)}{more}")
    return built


# ptxas's report: its lines, and a function's properties on a line of their own as nvcc prints them
PTXAS_REPORT = re.compile(r"ptxas\b.*|\d+ bytes stack frame, .*")


def log_lines(log: str, report: bool = False) -> list[str]:
    """The lines of a build log that say something: neither blank, nor NVIDIA's kernel note, nor
    (where `report`) ptxas's report."""
    lines = (line.strip() for line in log.splitlines())
    return [line for line in lines if line and not KERNEL_NOINLINE_NOTE.fullmatch(line)
            and not (report and PTXAS_REPORT.fullmatch(line))]
