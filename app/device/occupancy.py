"""Register caps on NVIDIA GPUs: a path tracer's kernel is latency-bound, and how many warps an
SM keeps in flight to hide that latency is set by how many registers each thread holds. ptxas
allocates what it likes, and small source changes move it across an occupancy step.
So on NVIDIA's OpenCL the kernels are built once with ptxas's report (-cl-nv-verbose), and again
under the register caps that would keep more warps resident, down to 4/5 of what ptxas chose;
the lowest cap that compiles without spilling is kept, unless it leaves fewer than FEWEST_WARPS
resident: such a heavy program is built for SPILLING_WARPS instead, if no kernel spills more than
MOST_SPILLED bytes there: its kernels wait on memory, and spills to the L1-cached local memory
cost less than the warps they buy. A light program, one that keeps FEWEST_WARPS or more without
spills but fewer than LIGHT_WARPS, is built for LIGHT_WARPS if no kernel spills more than
LIGHT_SPILLED bytes there. Each rule's figures: docs/performance.md (Register caps by trial).
Other platforms build as they are."""

import math
import os
import re

import pyopencl as cl

from pathtrace.device.quiet_build import build_quietly

REPORT = "-cl-nv-verbose"
# Registers are allocated per warp in units of 256 (8 per thread) on every NVIDIA architecture
# since Maxwell (CUDA occupancy calculator); the renderer launches 8x8 work groups of 2 warps,
# and a work group is resident whole. No SM holds more than 64 warps (sm_90; fewer on some).
ALLOCATION_UNIT = 8
GROUP_WARPS = 2
MOST_WARPS = 64
LOWEST_FRACTION = 0.8
FEWEST_WARPS = 16           # a quarter of an SM's: fewer leave the BVH walk's latency unhidden
SPILLING_WARPS = 20         # where a program needs more registers than FEWEST_WARPS allow
MOST_SPILLED = 2048         # bytes of spill stores per kernel allowed for SPILLING_WARPS: the most
                            # measured to gain was 1932 (docs/notes/performance-2026-11.md); beyond, not measured
LIGHT_WARPS = 24            # where a light program keeps fewer without spills
LIGHT_SPILLED = 512         # bytes of spill stores per kernel allowed for LIGHT_WARPS: the most
                            # measured was 472 (the textured teapot, which neither gained nor lost)
# What a program tuned under this rule is tuned by: part of the program cache's key, so that
# binaries tuned under another rule are not reused (app/device/opencl.py)
TUNING_RULE = (f"{FEWEST_WARPS}/{SPILLING_WARPS} warps, {MOST_SPILLED} bytes; "
               f"light {LIGHT_WARPS} warps, {LIGHT_SPILLED} bytes")


def is_nvidia(device: cl.Device) -> bool:
    return "NVIDIA" in device.platform.name and "cl_nv_device_attribute_query" in device.extensions


def kernel_registers(log: str) -> dict:
    """Per entry function of a ptxas report: (registers, spill store bytes)."""
    found, current = {}, None
    for line in log.splitlines():
        m = re.search(r"(?:Compiling entry function|Function properties for) '?(\w+)'?", line)
        if m:
            current = m.group(1)
            found.setdefault(current, (0, 0))
        m = re.search(r"(\d+) bytes spill stores", line)
        if m and current:
            found[current] = (found[current][0], int(m.group(1)))
        m = re.search(r"Used (\d+) registers", line)
        if m and current:
            found[current] = (int(m.group(1)), found[current][1])
    return found


def resident_warps(registers: int, register_file: int, warp: int) -> int:
    """Warps resident per SM when each thread holds `registers` (work groups of GROUP_WARPS)."""
    per_thread = -(-registers // ALLOCATION_UNIT) * ALLOCATION_UNIT
    return min(MOST_WARPS, GROUP_WARPS * (register_file // (GROUP_WARPS * warp * per_thread)))


def register_caps(registers: int, register_file: int = 65536, warp: int = 32) -> list[int]:
    """The register counts below `registers`, and not below LOWEST_FRACTION of it, at which more
    warps are resident: the most registers of each such occupancy, lowest first."""
    now = resident_warps(registers, register_file, warp)
    caps = {}
    lowest = math.ceil(registers * LOWEST_FRACTION)
    for cap in range(registers - 1, lowest - 1, -1):
        warps = resident_warps(cap, register_file, warp)
        if warps > now and warps not in caps:
            caps[warps] = cap
    return sorted(caps.values())


def most_registers(warps: int, register_file: int = 65536, warp: int = 32) -> int:
    """The most registers a thread may hold with `warps` warps resident per SM."""
    return max(cap for cap in range(1, 256) if resident_warps(cap, register_file, warp) >= warps)


def _build_reporting(context: cl.Context, device: cl.Device, source: str, options: list[str]) -> cl.Program:
    """The program built with ptxas's report among `options`, its log read here rather than
    warned of (app/device/quiet_build.py)."""
    return build_quietly(cl.Program(context, source), options, [device], report=True)


def build_for_occupancy(context: cl.Context, device: cl.Device, source: str, options: list[str]):
    """The program built with the options under which it keeps the most warps resident without
    spilling (or SPILLING_WARPS or LIGHT_WARPS, spilling: see above), and those options.

    The driver keeps compiled code in its own cache (~/.nv/ComputeCache), keyed by the PTX and
    the options: where it already holds this PTX, ptxas does not run and reports nothing, and a
    scene of the same PTX as one tuned before (another version's source, the same kernels) got
    no cap. A kernel named by a random token makes
    the PTX new, so that ptxas runs and reports for every build here; the binary kept is the
    one built under the chosen options, which the driver then finds in its cache. The options
    returned are the whole of those it was built with, the report's included: the driver's cache
    is keyed by them too, and without it the next start ran ptxas on the cached PTX again
    (docs/notes/performance-2026-11.md, 2026-11-25: a first start on NVIDIA)."""
    source += f"\nkernel void occupancy_probe_{os.urandom(8).hex()}(void) {{}}\n"
    program = _build_reporting(context, device, source, options + [REPORT])
    found = kernel_registers(program.get_build_info(device, cl.program_build_info.LOG))
    if not found:
        return program, options + [REPORT]
    most = max(registers for registers, _ in found.values())
    register_file, warp = device.registers_per_block_nv, device.warp_size_nv
    built = {most: (program, options + [REPORT], found)}

    def build(cap):
        capped = options + [f"-cl-nv-maxrregcount={cap}", REPORT]
        trial = _build_reporting(context, device, source, capped)
        built[cap] = trial, capped, kernel_registers(trial.get_build_info(device, cl.program_build_info.LOG))

    def spilled(cap) -> int:
        """The most bytes a kernel spills under `cap`; -1 where ptxas reported nothing."""
        report = built[cap][2]
        return max(spills for _, spills in report.values()) if report else -1

    fuller = most_registers(SPILLING_WARPS, register_file, warp)
    lighter = most_registers(LIGHT_WARPS, register_file, warp)

    def fits(cap: int, most_spilled: int) -> bool:
        """Whether the program built under `cap` spills at most `most_spilled` bytes."""
        if cap not in built:
            build(cap)
        return 0 <= spilled(cap) <= most_spilled

    kept = most
    for cap in register_caps(most, register_file, warp):
        # caps run from the most warps down: once they keep fewer than FEWEST_WARPS, every cap
        # keeping that many has spilled, so the program is heavy, and it is built for
        # SPILLING_WARPS before any cap of fewer warps (which only a program spilling too much
        # there needs: one build fewer on a first start)
        if resident_warps(cap, register_file, warp) < FEWEST_WARPS and fits(fuller, MOST_SPILLED):
            return built[fuller][:2]
        build(cap)
        if spilled(cap) == 0:
            kept = cap
            break
    warps = resident_warps(kept, register_file, warp)
    if warps < FEWEST_WARPS and fits(fuller, MOST_SPILLED):
        kept = fuller
    elif FEWEST_WARPS <= warps < LIGHT_WARPS and fits(lighter, LIGHT_SPILLED):
        kept = lighter
    return built[kept][:2]
