"""Loop subdivision of a triangle mesh as pbrt-v4's `loopsubdiv` shape makes it
(src/pbrt/util/loopsubdiv.cpp; Loop 1987, with Warren's weights): each level splits every
triangle in four, moving each old vertex to (1 - n beta) p + beta (its n neighbours), beta = 3/16
for n = 3 and 3 / (8 n) otherwise, or on the boundary to 3/4 p + 1/8 (its two boundary
neighbours), and putting a new vertex on each edge at 3/8 of its ends and 1/8 of the two
vertices facing it, or on the boundary at its midpoint. After the last level every vertex is
pushed to its place on the limit surface (gamma = 1 / (n + 3 / (8 beta)); on the boundary 3/5 p +
1/5 of its boundary neighbours), and its normal is the cross product of the limit surface's two
tangents, which pbrt-v4 takes from the vertex's ordered ring of neighbours: on the shading side
pbrt-v4 turns the surface to (app/scene/meshes.py: place_mesh winds the faces to it).

The mesh's topology is pbrt-v4's: the control mesh's triangles are joined across an edge in the
order they name it (the first two to name it, then the next two: a sheet whose triangles are
listed twice, wound both ways, is a closed "pillow"), and each level's children are joined as
their parents were, not by their corners' numbers. A new vertex is made once for each pair of
corners that an edge joins (pbrt-v4's edgeVerts), from the first triangle that has that edge, and
a vertex's ring is walked from the triangle pbrt-v4 starts at (SDVertex::startFace): where the
two sides of a pillow share corners, each side's ring is its own.

Everything is NumPy over the half-edges: half-edge 3 f + k runs from corner k of face f to corner
k + 1, its twin is the one running back, and turning about a vertex is next(twin(h)) one way
and twin(prev(h)) the other, as pbrt-v4's nextFace and prevFace."""

from typing import NamedTuple

import numpy as np

LEVELS = 3                 # pbrt-v4's default "levels"
MAX_TRIANGLES = 1 << 25    # what the subdivided mesh may hold (4^levels times the control mesh's)


class Topology(NamedTuple):
    faces: np.ndarray      # (F, 3) corners
    twin: np.ndarray       # (3F,) each half-edge's twin, -1 on the boundary
    start: np.ndarray      # (V,) the half-edge leaving each vertex in the triangle its ring starts at, -1: none
    boundary: np.ndarray   # (V,) whether the fan its ring walks is open (pbrt-v4's SDVertex::boundary)


def loop_subdivide(vertices: np.ndarray, faces: np.ndarray, levels: int = LEVELS) -> tuple:
    """(vertices, faces, normals) of the control mesh (vertices (V, 3), faces (F, 3), wound
    consistently) subdivided `levels` times and pushed to the limit surface. Its every triangle is
    kept, a degenerate one too (pbrt-v4 subdivides them, and their children have area). A vertex
    whose faces are several fans (a bow tie, two cones at one apex, a third face on an edge) moves
    by the one fan its ring walks, as pbrt-v4's does. Raises ValueError where a face repeats a
    vertex or names one the mesh has not, where two faces joined across an edge run it the same
    way (pbrt-v4's walk needs a consistently wound mesh), or where the result would pass
    MAX_TRIANGLES."""
    p, f = np.asarray(vertices, np.float64).reshape(-1, 3), np.asarray(faces, np.int64).reshape(-1, 3)
    if not len(f) or levels < 0:
        raise ValueError("indices: no triangles to subdivide" if not len(f) else f"levels: {levels} is negative")
    if f.min() < 0 or f.max() >= len(p):
        raise ValueError(f"indices: a triangle names vertex {int(f.max() if f.max() >= len(p) else f.min())}, "
                         f"of {len(p)}")
    if np.any((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 2] == f[:, 0])):
        raise ValueError("indices: a triangle repeats a vertex, which Loop subdivision cannot walk")
    if len(f) << (2 * levels) > MAX_TRIANGLES:
        raise ValueError(f"levels: {levels} levels make {len(f) << (2 * levels):,} triangles of {len(f):,}, "
                         f"more than {MAX_TRIANGLES:,}")
    topology = control_topology(f, len(p))
    rings = _Rings(topology)
    for _ in range(levels):
        p, topology = refine(p, topology, rings)
        rings = _Rings(topology)
    p = _limit_positions(p, topology, rings)
    return p, topology.faces, _limit_normals(p, topology, rings)


def _sums(index: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """(n, 3) sums of the rows of `values` by their `index`."""
    return np.stack([np.bincount(index, values[:, c], minlength=n) for c in range(3)], axis=1)


def _ends(f: np.ndarray) -> tuple:
    """Each half-edge's origin and end."""
    return f.reshape(-1), np.roll(f, -1, axis=1).reshape(-1)


def _turns(m: int) -> tuple:
    """Each of m half-edges' next and previous half-edge round its triangle."""
    corner = np.arange(m)
    return corner - corner % 3 + (corner + 1) % 3, corner - corner % 3 + (corner + 2) % 3


def _most_faces(origin: np.ndarray, n: int) -> int:
    """The most triangles about any of the n vertices (half-edges leave a vertex once per face)."""
    return int(np.bincount(origin, minlength=n).max())


def _pairs(f: np.ndarray, n: int) -> tuple:
    """Each half-edge's origin and end, and its pair of corners as one number, the same for the
    half-edges that run between the same two of the n vertices either way."""
    origin, end = _ends(f)
    return origin, end, np.minimum(origin, end) * n + np.maximum(origin, end)


def control_topology(f: np.ndarray, n: int) -> Topology:
    """The control mesh's topology as pbrt-v4 makes it: the half-edges of each pair of corners
    joined two by two in the order the faces name them; each vertex's ring starting at the last
    face that names it; a vertex is on the boundary where the walk from that face about it, face
    after face, meets an edge without a twin before it comes back (so that of a vertex where a
    closed fan meets an open one, only the fan walked counts)."""
    origin, end, key = _pairs(f, n)
    order = np.argsort(key, kind="stable")
    ordered = key[order]
    first = np.ones(len(order), bool)
    first[1:] = ordered[1:] != ordered[:-1]
    rank = np.arange(len(order)) - np.maximum.accumulate(np.where(first, np.arange(len(order)), 0))
    pairs = np.flatnonzero((rank % 2 == 0) & np.append(ordered[1:] == ordered[:-1], False))
    a_half, b_half = order[pairs], order[pairs + 1]
    if np.any(origin[a_half] == origin[b_half]):
        raise ValueError("indices: two triangles that share an edge run it the same way (wound inconsistently)")
    twin = np.full(len(order), -1)
    twin[a_half], twin[b_half] = b_half, a_half
    start = np.full(n, -1)
    np.maximum.at(start, origin, np.arange(len(origin)))      # the last named (pbrt-v4's startFace)
    nxt, _ = _turns(len(origin))
    boundary = np.zeros(n, bool)
    h, walking = start.copy(), np.flatnonzero(start >= 0)
    for _ in range(_most_faces(origin, n)):     # h -> next(twin(h)): the next face
        across = twin[h[walking]]
        boundary[walking[across < 0]] = True
        walking, across = walking[across >= 0], across[across >= 0]
        h[walking] = nxt[across]
        walking = walking[h[walking] != start[walking]]
    return Topology(f, twin, start, boundary)


def _beta(valence: np.ndarray) -> np.ndarray:
    return np.where(valence == 3, 3.0 / 16.0, 3.0 / (8.0 * np.maximum(valence, 1)))


def refine(p: np.ndarray, t: Topology, rings: "_Rings") -> tuple:
    """One level: the old vertices moved, then a new vertex for each pair of corners an edge joins,
    made from the first half-edge that names the pair and that half-edge's twin; each face's four
    children as pbrt-v4 orders them (a corner's child for each corner, then the middle), joined as
    their parents were."""
    n, f = len(p), t.faces
    ring_sum, boundary_sum = rings.sums(p)
    beta = _beta(rings.valence)[:, None]
    even = np.where(t.boundary[:, None], 0.75 * p + 0.125 * boundary_sum,
                    (1 - rings.valence[:, None] * beta) * p + beta * ring_sum)
    origin, end, key = _pairs(f, n)
    _, made_by, odd_of = np.unique(key, return_index=True, return_inverse=True)
    h, across = made_by, t.twin[made_by]                 # the half-edge that makes each new vertex, its twin
    opposite = np.roll(f, -2, axis=1).reshape(-1)          # each half-edge's corner facing it
    a, b = p[origin[h]], p[end[h]]
    inner = across >= 0
    facing = p[opposite[h]] + p[opposite[np.where(inner, across, h)]]
    odd = np.where(inner[:, None], 0.375 * (a + b) + 0.125 * facing, 0.5 * (a + b))
    v0, v1, v2 = f[:, 0], f[:, 1], f[:, 2]
    o0, o1, o2 = (n + odd_of.reshape(-1, 3)[:, k] for k in range(3))     # the new vertices of edges 01, 12, 20
    children = np.stack([np.stack([v0, o0, o2], 1), np.stack([o0, v1, o1], 1), np.stack([o2, o1, v2], 1),
                         np.stack([o0, o1, o2], 1)], 1).reshape(-1, 3)
    # child c of face g is face 4 g + c; edge j of face g splits into its first half, edge j of
    # child j, and its second, edge j of child j + 1; the first half of one side of an edge is
    # the twin of the second half of the other (pbrt-v4's "update face neighbor pointers")
    g = np.repeat(np.arange(len(f)), 3)
    j = np.tile(np.arange(3), len(f))
    first_half = 3 * (4 * g + j) + j
    second_half = 3 * (4 * g + (j + 1) % 3) + j
    twin = np.full(12 * len(f), -1)
    joined = t.twin >= 0
    other = t.twin[joined]
    twin[first_half[joined]] = second_half[other]
    twin[second_half[joined]] = first_half[other]
    # the middle child's edge k joins edge (2, 0, 1)[k] of corner child (1, 2, 0)[k], its siblings
    # (pbrt-v4: children[3]->f[j] = children[NEXT(j)])
    faces4 = 4 * np.arange(len(f))[:, None]
    middle = (3 * (faces4 + 3) + np.arange(3)).reshape(-1)
    sibling = (3 * (faces4 + np.array([1, 2, 0])) + np.array([2, 0, 1])).reshape(-1)
    twin[middle], twin[sibling] = sibling, middle
    # an even vertex starts at its parent's start face's child at its corner, a new one at the
    # middle child of the face that made it
    parent = t.start
    start_even = np.where(parent >= 0, 3 * (4 * (parent // 3) + parent % 3) + parent % 3, -1)
    start_odd = 3 * (4 * (h // 3) + 3) + h % 3
    return np.concatenate([even, odd]), Topology(children, twin, np.concatenate([start_even, start_odd]),
                                                 np.concatenate([t.boundary, ~inner]))


def _limit_positions(p: np.ndarray, t: Topology, rings: "_Rings") -> np.ndarray:
    ring_sum, boundary_sum = rings.sums(p)
    gamma = (1.0 / (rings.valence + 3.0 / (8.0 * _beta(rings.valence))))[:, None]
    return np.where(t.boundary[:, None], 0.6 * p + 0.2 * boundary_sum, (1 - rings.valence[:, None] * gamma) * p
                    + gamma * ring_sum)


class _Rings:
    """Each vertex's neighbours in pbrt-v4's order (SDVertex::oneRing), as flat arrays of (vertex,
    place, neighbour), walked from the vertex's start (Topology.start): about an interior vertex
    face after face (h -> next(twin(h))); about a boundary vertex from the last face one way, its
    first neighbour that face's next vertex and then each face's previous one going back (h ->
    twin(prev(h))). Each step takes only the vertices still walking, so that the work is the
    rings' length, not the most neighbours times the vertices; `valence` is each ring's length
    (pbrt-v4's SDVertex::valence). A vertex of several fans walks the one its start face is in."""

    def __init__(self, t: Topology):
        origin, end = _ends(t.faces)
        m, n = len(origin), len(t.start)
        steps = _most_faces(origin, n) + 1
        nxt, prev = _turns(m)
        h = t.start.copy()
        walking = np.flatnonzero((h >= 0) & t.boundary)
        for _ in range(steps):                   # a boundary vertex's to the last face one way
            on = t.twin[h[walking]] >= 0
            walking = walking[on]
            h[walking] = nxt[t.twin[h[walking]]]
        used = np.flatnonzero(h >= 0)
        vertex, place, neighbour = [used], [np.zeros(len(used), np.int64)], [end[h[used]]]
        start, walking, j = h.copy(), used, 1
        while len(walking) and j <= steps:
            inner = walking[~t.boundary[walking]]
            step = nxt[t.twin[h[inner]]]
            on = step != start[inner]
            inner, step = inner[on], step[on]
            h[inner] = step
            outer = walking[t.boundary[walking]]
            vertex += [inner, outer]
            place += [np.full(len(inner) + len(outer), j)]
            neighbour += [end[h[inner]], origin[prev[h[outer]]]]
            back = t.twin[prev[h[outer]]]
            outer, back = outer[back >= 0], back[back >= 0]
            h[outer] = back
            walking = np.concatenate([inner, outer])
            j += 1
        self.vertex, self.place, self.neighbour = np.concatenate(vertex), np.concatenate(place), np.concatenate(neighbour)
        self.valence = np.bincount(self.vertex, minlength=n)

    def sums(self, p: np.ndarray) -> tuple:
        """Each vertex's sum of its ring's points, and of its first and last (on the boundary, its
        two boundary neighbours: pbrt-v4's weightBoundary)."""
        ring_sum = _sums(self.vertex, p[self.neighbour], len(self.valence))
        return ring_sum, self.at(p, 0) + self.at(p, np.maximum(self.valence - 1, 0))

    def at(self, p: np.ndarray, j) -> np.ndarray:
        """Each vertex's neighbour at place j (an int, or one per vertex) of its ring: (V, 3), zero
        where its ring is shorter."""
        j = np.broadcast_to(j, self.valence.shape)
        chosen = self.place == j[self.vertex]
        out = np.zeros((len(self.valence), 3))
        out[self.vertex[chosen]] = p[self.neighbour[chosen]]
        return out


def _limit_normals(p: np.ndarray, topology: Topology, rings: _Rings) -> np.ndarray:
    """Each vertex's normal S x T from its limit tangents, as pbrt-v4 computes them: about an
    interior vertex S and T are its ring weighted by cos and sin of 2 pi j / n; on the boundary S
    runs between its two boundary neighbours and T has weights by its count of neighbours."""
    n, count = len(p), rings.valence
    v, j, r = rings.vertex, rings.place, p[rings.neighbour]
    angle = 2 * np.pi * j / np.maximum(count[v], 1)
    s = _sums(v, np.cos(angle)[:, None] * r, n)
    t = _sums(v, np.sin(angle)[:, None] * r, n)
    r0, r1, r2, r3 = (rings.at(p, k) for k in range(4))
    last = rings.at(p, np.maximum(count - 1, 0))
    theta = np.pi / np.maximum(count - 1, 1)
    inside = (j >= 1) & (j < count[v] - 1)
    weight = np.where(inside, (2 * np.cos(theta[v]) - 2) * np.sin(j * theta[v]), 0.0)
    t_boundary = -(np.sin(theta)[:, None] * (r0 + last) + _sums(v, weight[:, None] * r, n))
    for c, value in ((2, r0 + r1 - 2 * p), (3, r1 - p), (4, -r0 + 2 * r1 + 2 * r2 - r3 - 2 * p)):
        t_boundary = np.where((count == c)[:, None], value, t_boundary)
    on = topology.boundary & (count >= 2)
    s = np.where(on[:, None], last - r0, s)
    t = np.where(on[:, None], t_boundary, t)
    normal = np.cross(s, t)
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return normal / np.where(length > 0, length, 1.0)
