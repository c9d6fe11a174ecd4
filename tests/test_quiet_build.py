"""A program's build passes PyOpenCL's warning of a non-empty log on unless the log says nothing
wrong (app/device/quiet_build.py): NVIDIA's per-kernel noinline note, or the register report a
caller asked for."""

import warnings

import pyopencl
import pytest

from pathtrace.device.quiet_build import build_quietly

NOTE = ("(): Warning: Function render_nee is a kernel, so overriding noinline attribute. The function may be "
        "inlined when called.")


class LoggingProgram:
    """A stand-in for cl.Program whose build leaves `log` and warns as PyOpenCL does of a non-empty one."""

    def __init__(self, log: str):
        self.log = log

    def build(self, options, devices):
        if self.log:
            warnings.warn("From-source build succeeded, but resulted in non-empty logs", pyopencl.CompilerWarning)
        return self

    def get_build_info(self, device, what):
        return self.log


def compiler_warnings(log: str, report=False) -> list:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build_quietly(LoggingProgram(log), ["-DA"], ["device"], report=report)
    return [w for w in caught if issubclass(w.category, pyopencl.CompilerWarning)]


@pytest.mark.parametrize("log,warned", [
    ("", False),
    (NOTE, False),
    ("\n" + NOTE + "\n" + NOTE.replace("render_nee", "mean_half4") + "\n\n", False),
    ("<kernel>:12:5: warning: unused variable 'x'", True),
    (NOTE + "\n<kernel>:12:5: warning: unused variable 'x'", True),
])
def test_only_a_log_that_says_something_wrong_is_warned_of(log, warned):
    assert bool(compiler_warnings(log)) == warned


def test_a_report_the_caller_reads_is_not_warned_of():
    assert not compiler_warnings("ptxas info    : Used 96 registers, used 0 barriers", report=True)
    assert compiler_warnings("ptxas info    : Used 96 registers, used 0 barriers")
