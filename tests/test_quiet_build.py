"""A program's build log in pathtrace's words (app/device/quiet_build.py): nothing for a log
that says nothing wrong (NVIDIA's per-kernel noinline note, the register report a caller asked
for), one warning line for one that does; PyOpenCL's own warning never."""

from types import SimpleNamespace

import pytest

import pathtrace.device.quiet_build as quiet_build

NOTE = ("(): Warning: Function render_nee is a kernel, so overriding noinline attribute. The function may be "
        "inlined when called.")
REPORT = ("ptxas info    : Function properties for render_nee\n    2512 bytes stack frame, 0 bytes spill stores, "
          "0 bytes spill loads\nptxas info    : Used 96 registers, used 0 barriers\nptxas         .     0 bytes stack frame")


class LoggingProgram:
    """A stand-in for cl.Program whose build leaves `log`."""

    def __init__(self, log: str):
        self.log = log

    def build(self, options, devices):
        return self

    def get_build_info(self, device, what):
        return self.log

    def get_info(self, what):
        return [SimpleNamespace(name="Stand-in device ")]


def said(log: str, monkeypatch, report=False, devices=(SimpleNamespace(name="Stand-in device"),)) -> list:
    lines = []
    monkeypatch.setattr(quiet_build, "warn", lines.append)
    quiet_build.build_quietly(LoggingProgram(log), ["-DA"], list(devices) if devices else None, report=report)
    return lines


@pytest.mark.parametrize("log,count,more", [
    ("", 0, False),
    (NOTE, 0, False),
    ("\n" + NOTE + "\n" + NOTE.replace("render_nee", "mean_half4") + "\n\n", 0, False),
    ("<kernel>:12:5: warning: unused variable 'x'", 1, False),
    (NOTE + "\n<kernel>:12:5: warning: unused variable 'x'\n<kernel>:13:1: warning: another", 1, True),
    (REPORT, 1, True),          # a report nobody asked for is something the log says (its four lines)
])
def test_only_a_log_that_says_something_is_one_line(log, count, more, monkeypatch):
    lines = said(log, monkeypatch)
    assert len(lines) == count, lines
    if count:
        assert lines[0].startswith("Stand-in device: the kernels' build log says: ")
        assert "\n" not in lines[0] and ("more lines)" in lines[0]) == more


def test_a_report_the_caller_reads_is_not_repeated_but_what_else_the_log_says_is(monkeypatch):
    assert not said(REPORT, monkeypatch, report=True)
    lines = said(REPORT + "\n<kernel>:12:5: warning: unused variable 'x'", monkeypatch, report=True)
    assert lines == ["Stand-in device: the kernels' build log says: <kernel>:12:5: warning: unused variable 'x'"]


def test_the_programs_devices_are_read_where_none_are_given(monkeypatch):
    assert said("<kernel>:1:1: warning: x", monkeypatch, devices=None) == [
        "Stand-in device: the kernels' build log says: <kernel>:1:1: warning: x"]


def test_pyopencls_own_warning_is_not_shown():
    """In a process that has opened a device (imported the builder), PyOpenCL's warning of a
    non-empty log prints nothing: pathtrace's line above says what there is to say."""
    import subprocess
    import sys
    code = ("import warnings, pyopencl, pathtrace.device.opencl; "
            "warnings.warn('non-empty logs', pyopencl.CompilerWarning); warnings.warn('other', UserWarning)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and "CompilerWarning" not in r.stderr and "UserWarning: other" in r.stderr, r.stderr
