"""Where the BVH walk stands on a real interior, Bitterli's classroom (#59; docs/notes/performance-2026-11.md,
2026-11-29, sixth session): the nodes visited and primitives tested per ray
(pathtrace.bench.traversal_stats, depth 8 with NEE) for the builder as it is and for trees it could
build instead, each compiled into the scene in place of app/compiler/bvh.py's (the renderer is
not changed):

- main: PLOC, the binned top split and the SAH collapse (app/compiler/bvh.py);
- radius16: PLOC's search radius 16 in place of 8;
- binned: the binned SAH split (bvh.split_top) over every primitive, no PLOC;
- sweep: a top-down SAH split that sweeps every primitive along each axis (the full-sweep build,
  MacDonald and Booth 1990, as pbrt-v4's largest-quality option), on the host, in Python: slow;
- presplit-area:B and presplit-sah:B: references split before the build (Ernst and Greiner 2007,
  "Early split clipping"; Karras and Aila 2013, "Fast parallel construction of high-quality
  BVHs", section 4), B the budget of extra references per triangle. A reference is cut at the
  middle of its box's longest axis; each half's box is the triangle's part on that side,
  clipped to the reference's box. `area` cuts the references of largest box first; `sah` cuts
  only where the halves' boxes together are less than SAH_SPLIT of the reference's (a flat,
  axis-aligned triangle's halves keep 0.75 of its box, a diagonal sliver's 0.5), the largest
  area saved first. The tree is built over the references' boxes by the builder as it is; a
  triangle's row is then held once per reference (CompiledScene gathers the rows by the tree's
  order). A ray does not skip a copy of the triangle it leaves, so these counts are close, not
  exact. With --keep-whole F, a triangle whose box holds more than F of the root box's area
  (the classroom's 221 m Floor) is never cut.

Then, per scene, with the tree as it is: a pixel's work per sample (nodes + primitives, over all
its rays) and a bound on the walk's SIMT efficiency: over warps of 32 lanes (an 8x8 work-group
is two warps of four rows), the lanes' work over 32 times the busiest lane's. A warp runs at least
as long as its busiest lane, so a GPU's walk uses at most that share of its lanes.

    python docs/notes/studies/classroom_bvh_study.py SCENE [SCENE ...] [--device D] [--size WxH]
        [--spp N] [--variants main,radius16,binned,sweep,presplit-area:0.1,presplit-sah:0.03]
        [--keep-whole F]
"""

import argparse
import heapq
import os
import sys
import time

import numpy as np

import pathtrace.compiler.bvh as bvh
import pathtrace.compiler.compiled as compiled_module
from pathtrace.bench.report import default_estimator, estimator_settings
from pathtrace.bench.traversal_stats import NODES_VISITED, PRIMITIVES_TESTED, traversal_stats
from pathtrace.compiler.compiled import compile_scene
from pathtrace.device.opencl import choose_device
from pathtrace.rendering.renderer import Renderer
from pathtrace.scene import load_scene

SAH_SPLIT = 0.7
WARP = 32


def half_area(lo, hi):
    d = np.maximum(np.asarray(hi, np.float64) - lo, 0)
    return d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0]


# --- trees from a binary tree made on the host -------------------------------------------------

def from_host_tree(lo, hi, left: dict, right: dict, root: int, queue) -> bvh.BVH:
    """The BVH of a binary tree over primitives 0..n-1 whose inner nodes (numbered from n, each
    after its children) have children left[k], right[k]: its nodes go to the device builder's
    tree in batches of equal height (a batch depends only on the ones below it), then step 3 of
    app/compiler/bvh.py collapses and lays it out."""
    n = len(lo)
    box_lo, box_hi = dict(enumerate(lo)), dict(enumerate(hi))
    height = dict.fromkeys(range(n), 0)
    for k in sorted(left):
        a, b = left[k], right[k]
        box_lo[k], box_hi[k] = np.minimum(box_lo[a], box_lo[b]), np.maximum(box_hi[a], box_hi[b])
        height[k] = 1 + max(height[a], height[b])
    inner = sorted(left, key=lambda k: (height[k], k))
    number = {k: n + i for i, k in enumerate(inner)}
    number.update((i, i) for i in range(n))
    tree = bvh._Tree(bvh.builder_for(queue), lo, hi)
    heights = np.array([height[k] for k in inner])
    for h in np.unique(heights):
        ks = [inner[i] for i in np.flatnonzero(heights == h)]
        tree.add([number[left[k]] for k in ks], [number[right[k]] for k in ks],
                 np.array([box_lo[k] for k in ks], np.float32), np.array([box_hi[k] for k in ks], np.float32))
    return bvh._flatten(tree, number[root], 0)


def sweep_bvh(lo, hi, queue) -> bvh.BVH:
    """The full-sweep SAH build: each node split where the two sides' primitive counts times
    their boxes' areas sum least, over every split of the primitives sorted by centroid on each
    axis."""
    n = len(lo)
    lo64, hi64 = lo.astype(np.float64), hi.astype(np.float64)
    centroid = (lo64 + hi64) / 2
    left, right = {}, {}
    made = [n]

    def build(prims):
        if len(prims) == 1:
            return int(prims[0])
        best = (np.inf, None)
        for axis in range(3):
            order = prims[np.argsort(centroid[prims, axis], kind="stable")]
            l_lo, l_hi = np.minimum.accumulate(lo64[order]), np.maximum.accumulate(hi64[order])
            r_lo = np.minimum.accumulate(lo64[order][::-1])[::-1]
            r_hi = np.maximum.accumulate(hi64[order][::-1])[::-1]
            k = np.arange(1, len(order))
            cost = k * half_area(l_lo[:-1], l_hi[:-1]) + (len(order) - k) * half_area(r_lo[1:], r_hi[1:])
            i = int(np.argmin(cost))
            if cost[i] < best[0]:
                best = (cost[i], (order[:i + 1], order[i + 1:]))
        a, b = build(best[1][0]), build(best[1][1])
        k = made[0]
        made[0] += 1
        left[k], right[k] = a, b
        return k

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 4 * n))
    return from_host_tree(lo, hi, left, right, build(np.arange(n)), queue)


def binned_bvh(lo, hi, queue) -> bvh.BVH:
    """The builder's binned SAH split (bvh.split_top) over every primitive, without PLOC."""
    n = len(lo)
    tree = bvh._Tree(bvh.builder_for(queue), lo, hi)
    levels, root = bvh.split_top(np.arange(n, dtype=np.int32), lo, hi, n)
    for level in levels:
        tree.add(*level)
    return bvh._flatten(tree, root, 0)


# --- split references --------------------------------------------------------------------------

def cut(triangle, lo, hi, axis, plane):
    """The boxes of a triangle's parts below and above `plane` on `axis`, each clipped to the
    reference's box lo..hi; None for a side the triangle does not reach."""
    below, above = [], []
    for k in range(3):
        a, b = triangle[k], triangle[(k + 1) % 3]
        (below if a[axis] <= plane else above).append(a)
        if (a[axis] < plane) != (b[axis] < plane) and a[axis] != b[axis]:
            t = (plane - a[axis]) / (b[axis] - a[axis])
            p = [a[i] + t * (b[i] - a[i]) for i in range(3)]
            p[axis] = plane
            below.append(p)
            above.append(p)
    boxes = []
    for points, side in ((below, 0), (above, 1)):
        b_lo = [max(min(p[i] for p in points), lo[i]) for i in range(3)] if points else None
        b_hi = [min(max(p[i] for p in points), hi[i]) for i in range(3)] if points else None
        if points:
            if side == 0:
                b_hi[axis] = min(b_hi[axis], plane)
            else:
                b_lo[axis] = max(b_lo[axis], plane)
        boxes.append((b_lo, b_hi) if points and all(b_lo[i] <= b_hi[i] for i in range(3)) else None)
    return boxes


def split_references(corners: np.ndarray, budget: float, rule: str, keep_whole: float):
    """References (triangle, box) to the triangles (T, 3, 3), with up to budget * T more made by
    cutting (module docstring); returns each reference's triangle and its box, float32 rounded
    outwards."""
    triangles = corners.astype(np.float64).tolist()
    lo, hi = corners.min(axis=1).astype(np.float64), corners.max(axis=1).astype(np.float64)
    refs = [(i, list(lo[i]), list(hi[i])) for i in range(len(corners))]
    whole = half_area(lo, hi) > keep_whole * half_area(lo.min(axis=0), hi.max(axis=0))

    def candidate(r):
        """(priority, the halves) of cutting reference r, or None where the rule does not cut it."""
        t, r_lo, r_hi = refs[r]
        axis = int(np.argmax([r_hi[i] - r_lo[i] for i in range(3)]))
        halves = cut(triangles[t], r_lo, r_hi, axis, (r_lo[axis] + r_hi[axis]) / 2)
        area = float(half_area(r_lo, r_hi))
        if rule == "area":
            return area, halves
        kept = sum(float(half_area(*h)) for h in halves if h is not None)
        saved = (1.0 if None in halves else SAH_SPLIT) * area - kept
        return (saved, halves) if saved > 0 else None

    heap = []
    for r in np.flatnonzero(~whole):
        c = candidate(r)
        if c is not None:
            heap.append((-c[0], r, c[1]))
    heapq.heapify(heap)
    extra = int(budget * len(corners))
    while extra > 0 and heap:
        _, r, halves = heapq.heappop(heap)
        t = refs[r][0]
        parts = [h for h in halves if h is not None]
        refs[r] = (t, *parts[0])
        changed = [r]
        if len(parts) == 2:        # a real cut (else the reference's box only shrank)
            refs.append((t, *parts[1]))
            changed.append(len(refs) - 1)
            extra -= 1
        for q in changed:
            c = candidate(q)
            if c is not None:
                heapq.heappush(heap, (-c[0], q, c[1]))
    triangle = np.array([r[0] for r in refs], np.int64)
    r_lo = np.nextafter(np.array([r[1] for r in refs], np.float32), np.float32(-np.inf))
    r_hi = np.nextafter(np.array([r[2] for r in refs], np.float32), np.float32(np.inf))
    return triangle, r_lo, r_hi


# --- the rows ----------------------------------------------------------------------------------

def builder(variant: str, captured: dict, keep_whole: float):
    """A stand-in for compiled.cached_bvh building the variant's tree; `captured` receives the
    triangles' corners (from compiled.primitive_boxes) and what was built."""
    name, _, budget = variant.partition(":")

    def build(lo, hi, num_spheres=None, queue=None, progress=None):
        start = time.perf_counter()
        if name in ("main", "radius16") or len(lo) < 3:
            bvh.RADIUS = 16 if name == "radius16" else 8
            tree = bvh.build_bvh(lo, hi, num_spheres, queue, progress)
            bvh.RADIUS = 8
            references = len(lo)
        else:
            if num_spheres:
                raise SystemExit(f"{variant}: for trees of triangles alone")
            if name == "binned":
                tree, references = binned_bvh(lo, hi, queue), len(lo)
            elif name == "sweep":
                tree, references = sweep_bvh(lo, hi, queue), len(lo)
            else:
                corners = captured["corners"][-len(lo):]
                triangle, r_lo, r_hi = split_references(corners, float(budget), name.split("-")[1], keep_whole)
                built = bvh.build_bvh(r_lo, r_hi, 0, queue)
                tree, references = bvh.BVH(built.nodes, triangle[built.order], built.depth, built.cost), len(r_lo)
        captured.update(seconds=time.perf_counter() - start, references=references)
        return tree

    return build


def warp_work(backend, scene, width: int, height: int, spp: int) -> str:
    """Per pixel and sample, the nodes + primitives of all its rays, and the walk's SIMT
    efficiency bound over warps of WARP lanes (module docstring)."""
    renderer = Renderer(backend, scene, width, height)
    work = np.zeros((spp, height, width))
    for kind in (NODES_VISITED, PRIMITIVES_TESTED):
        renderer.count_traversal(kind)
        before = np.zeros((height, width))
        for sample in range(spp):
            renderer.add_samples(1)
            renderer.finish()
            now = renderer._read_compensated("sum_sq")[..., 3]    # the counts stand in for rays
            work[sample] += now - before
            before = now
    renderer.finish()
    # (samples, tiles down, tiles across, two warps, 32 lanes: four rows of eight)
    w = work[:, :height // 8 * 8, :width // 8 * 8]
    lanes = w.reshape(-1, height // 8, 2, WARP // 8, width // 8, 8).transpose(0, 1, 4, 2, 3, 5).reshape(-1, WARP)
    lanes = lanes[lanes.max(axis=1) > 0]
    bound = lanes.sum() / (WARP * lanes.max(axis=1)).sum()
    return (f"  work per pixel and sample {work.mean():.1f} (90th percentile {np.percentile(work, 90):.0f}); "
            f"walk's SIMT efficiency at most {bound:.3f} (warps of {WARP})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--size", default="320x176")
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--variants", default="main,radius16,binned,sweep,presplit-area:0.1,presplit-sah:0.03")
    parser.add_argument("--keep-whole", type=float, default=np.inf, metavar="F")
    args = parser.parse_args()
    os.environ["PATHTRACE_BVH_CACHE"] = "0"       # each row builds its tree (pathtrace.compiler.bvh_cache)
    width, height = map(int, args.size.split("x"))
    backend = choose_device(args.device)
    print(f"{backend.device.describe()}; {width}x{height}, {args.spp} spp, depth 8 with NEE")
    bvh.build_bvh(np.zeros((2, 3)), np.ones((2, 3)), queue=backend.queue)    # the build kernels, built
    captured = {}
    boxes = compiled_module.primitive_boxes

    def capturing_boxes(spheres, corners):
        captured["corners"] = np.asarray(corners, np.float32)
        return boxes(spheres, corners)

    compiled_module.primitive_boxes = capturing_boxes
    for path in args.scenes:
        scene = load_scene(path)
        scene = scene.with_settings(**estimator_settings(default_estimator(scene)))
        for variant in args.variants.split(","):
            if variant != "main" and scene.shapes:
                print(f"{path}: {variant}: skipped (analytic shapes are not triangles to split)")
                continue
            compiled_module.cached_bvh = builder(variant, captured, args.keep_whole)
            captured.clear()
            c = compile_scene(scene, backend.queue)
            if c.two_level:
                raise SystemExit(f"{path}: a two-level BVH (instances), which this study does not replace")
            s = traversal_stats(backend, c, width, height, args.spp)
            print(f"{os.path.basename(path):<22} {variant:<18} references {captured['references']:>8}  "
                  f"build {captured['seconds']:6.2f} s  SAH cost {c.bvh.cost:6.3f}  nodes {len(c.bvh.nodes):>7}  "
                  f"depth {c.bvh.depth:>2}  rays/sample {s.rays_per_sample:.3f}  nodes/ray {s.nodes_per_ray:5.2f}  "
                  f"prims/ray {s.primitives_per_ray:.2f}  sum {s.nodes_per_ray + s.primitives_per_ray:5.2f}", flush=True)
            if variant == "main":
                print(warp_work(backend, c, width, height, args.spp), flush=True)


if __name__ == "__main__":
    main()
