"""How much memory this process can still take on the host: the checks that refuse, in one line
and before anything is allocated, a scene or an image that would not fit (app/compiler/compiled.py,
app/rendering/renderer.py), where a failed allocation would end in a MemoryError deep in NumPy or an
assertion inside the OpenCL driver."""

import os


def available_host_memory():
    """Bytes this process can still allocate: MemAvailable from /proc/meminfo, or less where a
    control group caps the process's memory (a container, a batch job) or a limit on its address
    space does (ulimit -v); None where none of them can be read."""
    limits = [x for x in (_meminfo_available(), cgroup_memory_left(), address_space_left()) if x is not None]
    return min(limits) if limits else None


def _meminfo_available():
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


def cgroup_memory_left(root: str = "/sys/fs/cgroup", membership: str = "/proc/self/cgroup"):
    """The memory control group's limit less its usage, in bytes: cgroup v2 (memory.max,
    memory.current) or v1 (memory.limit_in_bytes, memory.usage_in_bytes). The group's files are
    looked for at its path under the hierarchy and, as inside a container, at the hierarchy's
    root. None where there is no limit ("max", or v1's near-2^63) or no such files."""
    try:
        with open(membership) as f:
            lines = [line.rstrip("\n").split(":", 2) for line in f]
    except OSError:
        return None
    for fields in lines:
        if len(fields) != 3:
            continue
        _, controllers, path = fields
        if controllers == "":
            names, base = ("memory.max", "memory.current"), root
        elif "memory" in controllers.split(","):
            names, base = ("memory.limit_in_bytes", "memory.usage_in_bytes"), os.path.join(root, "memory")
        else:
            continue
        for folder in (os.path.join(base, path.lstrip("/")), base):
            try:
                with open(os.path.join(folder, names[0])) as f:
                    limit = f.read().strip()
                with open(os.path.join(folder, names[1])) as f:
                    used = int(f.read().strip())
            except (OSError, ValueError):
                continue
            if limit == "max" or int(limit) >= 1 << 62:
                break
            return max(int(limit) - used, 0)
    return None


def address_space_left():
    """What the soft limit on the address space (RLIMIT_AS, ulimit -v) leaves beyond the process's
    present size, in bytes; None where there is no limit or it cannot be read."""
    try:
        import resource
        limit, _ = resource.getrlimit(resource.RLIMIT_AS)
        if limit == resource.RLIM_INFINITY:
            return None
        with open("/proc/self/statm") as f:
            size = int(f.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (ImportError, OSError, ValueError, IndexError):
        return None
    return max(limit - size, 0)
