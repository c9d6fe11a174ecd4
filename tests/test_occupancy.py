"""Register caps on NVIDIA GPUs (app/device/occupancy.py): ptxas's report read per kernel, and the
caps that would keep more warps resident."""


from pathtrace.device.occupancy import kernel_registers, most_registers, register_caps, resident_warps

# An H100's report for a scene's program (-cl-nv-verbose), as the driver wrote it.
REPORT = """
ptxas info    : 24 bytes gmem
ptxas info    : Compiling entry function 'render_aovs' for 'sm_90a'
ptxas info    : Function properties for render_aovs
ptxas         .     192 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads
ptxas info    : Used 126 registers, used 0 barriers
ptxas info    : Compile time = 209.296 ms
ptxas info    : Compiling entry function 'render_nee' for 'sm_90a'
ptxas info    : Function properties for render_nee
ptxas         .     320 bytes stack frame, 220 bytes spill stores, 220 bytes spill loads
ptxas info    : Used 96 registers, used 0 barriers
"""


def test_the_report_gives_each_kernels_registers_and_spills():
    assert kernel_registers(REPORT) == {"render_aovs": (126, 0), "render_nee": (96, 220)}
    assert kernel_registers("Build succeeded") == {}


def test_resident_warps_follow_the_register_file_in_whole_work_groups():
    # 65536 registers per SM, 2-warp work groups, 8 registers per thread allocation unit
    assert resident_warps(96, 65536, 32) == 20
    assert resident_warps(116, 65536, 32) == 16      # 120 allocated: 8 groups of 7680
    assert resident_warps(120, 65536, 32) == 16
    assert resident_warps(128, 65536, 32) == 16
    assert resident_warps(112, 65536, 32) == 18
    assert resident_warps(64, 65536, 32) == 32
    assert resident_warps(24, 65536, 32) == 64


def test_caps_are_the_occupancy_steps_down_to_four_fifths():
    assert register_caps(116) == [96, 112]
    assert register_caps(128) == [112]                # 104 keeps 18 warps too; 96 is below 4/5
    assert register_caps(96) == [80, 88]
    assert register_caps(32) == []                    # 64 warps already, the most an SM holds
    for registers in range(40, 255):
        for cap in register_caps(registers):
            assert registers * 0.8 <= cap < registers
            assert resident_warps(cap, 65536, 32) > resident_warps(registers, 65536, 32)


def test_most_registers_is_the_top_of_an_occupancy_step():
    assert most_registers(16) == 128
    assert most_registers(20) == 96
    assert most_registers(64) == 32
    for warps in range(10, 65, 2):       # 8 warps hold the most a thread may have, 255
        cap = most_registers(warps)
        assert resident_warps(cap, 65536, 32) >= warps > resident_warps(cap + 1, 65536, 32)


def report(registers, spilled):
    return (f"ptxas info    : Compiling entry function 'render_nee' for 'sm_90a'\n"
            f"ptxas         .     320 bytes stack frame, {spilled} bytes spill stores, {spilled} bytes spill loads\n"
            f"ptxas info    : Used {registers} registers, used 0 barriers\n")


class FakeProgram:
    """cl.Program on a stand-in for NVIDIA's driver: each build's log is ptxas's report for the
    register cap in its options (`uncapped` registers without one; `spill_bytes` spilled below
    `spills_below`)."""
    uncapped, spills_below, spill_bytes = 116, 100, 64

    def __init__(self, context, source):
        pass

    def build(self, options, devices):
        self.options = options
        cap = next((int(o.split("=")[1]) for o in options if o.startswith("-cl-nv-maxrregcount=")), None)
        spilled = self.spill_bytes if cap and cap < self.spills_below else 0
        self.log = report(cap or self.uncapped, spilled) if "-cl-nv-verbose" in options else ""
        self.built.append(options)
        return self

    def get_build_info(self, device, what):
        return self.log

    def get_info(self, what):
        return [FakeDevice()]


class FakeDevice:
    registers_per_block_nv, warp_size_nv, name = 65536, 32, "Stand-in NVIDIA device"


def tune(monkeypatch, **program) -> tuple:
    """build_for_occupancy on the stand-in driver (FakeProgram's settings replaced by `program`):
    the options kept, which must be those of the program returned, and each build's options."""
    import pathtrace.device.occupancy as occupancy
    Program = type("Program", (FakeProgram,), dict(program, built=[]))
    monkeypatch.setattr(occupancy.cl, "Program", Program)
    built, options = occupancy.build_for_occupancy(None, FakeDevice(), "kernel void k(void) {}", ["-DA"])
    assert options == built.options
    return options, Program.built


def capped(cap: int) -> list:
    return ["-DA", f"-cl-nv-maxrregcount={cap}", "-cl-nv-verbose"]


def test_the_options_kept_are_those_the_program_was_built_with(monkeypatch):
    """The driver caches what ptxas made, keyed by the PTX and the build options: the options that
    go with the cached binary must be the very ones of its build, the report's included, or the
    next start misses that cache and runs ptxas again (25-35 s on the H100)."""
    options, builds = tune(monkeypatch, spill_bytes=1000)
    assert options == capped(112)
    assert builds == [["-DA", "-cl-nv-verbose"], capped(96), capped(112), capped(80)]


def test_a_heavy_program_spills_for_20_warps_rather_than_keep_fewer_than_16(monkeypatch):
    """157 registers uncapped (12 warps resident), spilling below 140: the cap of 128 (16 warps)
    spills, so the program is heavy and is built at 96 (20 warps), which is kept, spills and all;
    the cap of 144 (14 warps, no spills) is not built."""
    options, builds = tune(monkeypatch, uncapped=157, spills_below=140)
    assert options == capped(96)
    assert builds == [["-DA", "-cl-nv-verbose"], capped(128), capped(96)]


def test_a_light_program_spilling_little_at_24_warps_is_built_for_them(monkeypatch):
    """116 registers (16 warps, as the height field's program), spilling 64 bytes at every cap
    tried (96, 112): it is no heavy program, so it is not built for 20 warps, but as it keeps
    fewer than LIGHT_WARPS and spills no more than LIGHT_SPILLED at 80 registers (24 warps),
    it is built there."""
    from pathtrace.device.occupancy import LIGHT_SPILLED
    assert 64 <= LIGHT_SPILLED
    options, builds = tune(monkeypatch, uncapped=116, spills_below=200)
    assert options == capped(80)
    assert builds == [["-DA", "-cl-nv-verbose"], capped(96), capped(112), capped(80)]


def test_a_light_program_spilling_much_at_24_warps_keeps_its_registers(monkeypatch):
    """The same program spilling 1000 bytes at every cap, more than LIGHT_SPILLED: it stays
    uncapped (16 warps), neither at 20 warps nor at 24."""
    from pathtrace.device.occupancy import LIGHT_SPILLED
    assert 1000 > LIGHT_SPILLED
    options, builds = tune(monkeypatch, uncapped=116, spills_below=200, spill_bytes=1000)
    assert options == ["-DA", "-cl-nv-verbose"]
    assert builds == [["-DA", "-cl-nv-verbose"], capped(96), capped(112), capped(80)]


def test_a_program_of_24_warps_or_more_is_not_rebuilt(monkeypatch):
    """80 registers (24 warps) uncapped, spilling below 76: the caps of 64 and 72 (32 and 28
    warps) spill, so the 80 registers are kept, and no build for LIGHT_WARPS follows."""
    options, builds = tune(monkeypatch, uncapped=80, spills_below=76)
    assert options == ["-DA", "-cl-nv-verbose"]
    assert builds == [["-DA", "-cl-nv-verbose"], capped(64), capped(72)]


def test_a_program_of_ten_warps_is_built_for_20(monkeypatch):
    """200 registers uncapped (10 warps): the caps in reach (down to 4/5 of that: 168) all keep
    fewer than 16 warps, so the program is built at 96 before any of them."""
    options, builds = tune(monkeypatch, uncapped=200)
    assert options == capped(96)
    assert builds == [["-DA", "-cl-nv-verbose"], capped(96)]


def test_a_program_that_would_spill_much_for_20_warps_keeps_its_cap_without_spills(monkeypatch):
    """As the heavy program above, but spilling 4000 bytes at 96 registers, more than
    MOST_SPILLED: the caps of fewer warps are tried after all, and 144, without spills, kept."""
    from pathtrace.device.occupancy import MOST_SPILLED
    assert 4000 > MOST_SPILLED
    options, builds = tune(monkeypatch, uncapped=157, spills_below=140, spill_bytes=4000)
    assert options == capped(144)
    assert builds == [["-DA", "-cl-nv-verbose"], capped(128), capped(96), capped(144)]


def said(monkeypatch) -> list:
    """The warning lines pathtrace gives of build logs (app/device/quiet_build.py), collected."""
    import pathtrace.device.quiet_build as quiet_build
    lines = []
    monkeypatch.setattr(quiet_build, "warn", lines.append)
    return lines


def test_the_register_reports_are_read_not_repeated(monkeypatch):
    """Each trial's log is ptxas's report, read for its registers: nothing of it reaches the
    user's terminal."""
    lines = said(monkeypatch)
    tune(monkeypatch)
    assert lines == []


def test_a_tuned_binary_read_from_the_cache_says_nothing(monkeypatch, tmp_path):
    """A tuned binary is cached with the options it was built with, ptxas's report among them
    (above), and rebuilt from the cache with them: that build's log is the report again, which
    PyOpenCL's warning printed to the terminal of every start that read the cache."""
    import pathtrace.device.opencl as opencl

    class Binary(FakeProgram):
        built = []

        def __init__(self, context, devices, binaries):
            assert binaries == [b"binary"]
    monkeypatch.setattr(opencl.cl, "Program", Binary)
    monkeypatch.setattr(opencl, "keeps_own_cache", lambda device: False)
    monkeypatch.setattr(opencl, "is_nvidia", lambda device: True)
    monkeypatch.setattr(opencl, "cache_entry", lambda *args: tmp_path / "entry.bin")
    monkeypatch.setattr(opencl, "_read_cached", lambda path: (capped(96), b"binary"))
    lines = said(monkeypatch)
    result = opencl.build_cached(None, FakeDevice(), "kernel void k(void) {}", ["-DA"])
    assert result.cached and Binary.built == [capped(96)] and lines == []
