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

Everything is NumPy over the half-edges: half-edge 3 f + k runs from corner k of face f to corner
k + 1, its twin is the one running back, and turning about a vertex is next(twin(h)) one way
and twin(prev(h)) the other, as pbrt-v4's nextFace and prevFace."""

import numpy as np

LEVELS = 3                 # pbrt-v4's default "levels"
MAX_TRIANGLES = 1 << 25    # what the subdivided mesh may hold (4^levels times the control mesh's)


def loop_subdivide(vertices: np.ndarray, faces: np.ndarray, levels: int = LEVELS) -> tuple:
    """(vertices, faces, normals) of the control mesh (vertices (V, 3), faces (F, 3), wound
    consistently) subdivided `levels` times and pushed to the limit surface. Its every triangle is
    kept, a degenerate one too (pbrt-v4 subdivides them, and their children have area). Raises
    ValueError where a face repeats a vertex or names one the mesh has not, where an edge is
    shared by more than two faces or by two that run it the same way, or where a vertex's faces
    are not one fan about it (pbrt-v4's mesh walk needs a consistently wound manifold), or where
    the result would pass MAX_TRIANGLES."""
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
    edges = _Edges(p, f)
    _Rings(f, edges).check_fans()
    for _ in range(levels):
        p, f = _refine(p, f, edges)
        edges = _Edges(p, f)
    p = _limit_positions(p, edges)
    return p, f, _limit_normals(p, _Rings(f, edges), edges)


def _sums(index: np.ndarray, values: np.ndarray, n: int) -> np.ndarray:
    """(n, 3) sums of the rows of `values` by their `index`."""
    return np.stack([np.bincount(index, values[:, c], minlength=n) for c in range(3)], axis=1)


class _Edges:
    """The half-edges of a mesh: their origins, ends and twins (-1 on the boundary), each one's
    undirected edge, and per vertex its neighbours' count and sum and its boundary neighbours' sum.
    One sort of the half-edges by their undirected edge finds all of it: an edge's two half-edges
    lie side by side there."""

    def __init__(self, p: np.ndarray, f: np.ndarray):
        n = len(p)
        self.origin, self.end = f.reshape(-1), np.roll(f, -1, axis=1).reshape(-1)
        key = np.minimum(self.origin, self.end) * n + np.maximum(self.origin, self.end)
        order = np.argsort(key, kind="stable")
        ordered = key[order]
        first = np.ones(len(order), bool)
        first[1:] = ordered[1:] != ordered[:-1]
        starts = np.flatnonzero(first)
        count = np.diff(np.append(starts, len(order)))
        if np.any(count > 2):
            raise ValueError("indices: an edge is shared by more than two triangles, which Loop subdivision cannot "
                             "walk")
        self.edge = np.empty(len(order), np.int64)
        self.edge[order] = np.cumsum(first) - 1
        pair = starts[count == 2]
        a_half, b_half = order[pair], order[pair + 1]
        if np.any(self.origin[a_half] == self.origin[b_half]):
            raise ValueError("indices: two triangles that share an edge run it the same way (wound inconsistently)")
        self.twin = np.full(len(order), -1)
        self.twin[a_half], self.twin[b_half] = b_half, a_half
        self.ends = ordered[starts]                          # each edge's a * n + b, a < b
        a, b = self.ends // n, self.ends % n
        self.boundary_edge = count == 1
        both = np.concatenate([a, b])
        self.valence = np.bincount(both, minlength=n)
        self.ring_sum = _sums(both, np.concatenate([p[b], p[a]]), n)
        ba, bb = a[self.boundary_edge], b[self.boundary_edge]
        self.boundary = np.zeros(n, bool)
        self.boundary[ba] = self.boundary[bb] = True
        self.boundary_sum = _sums(np.concatenate([ba, bb]), np.concatenate([p[bb], p[ba]]), n)


def _beta(valence: np.ndarray) -> np.ndarray:
    return np.where(valence == 3, 3.0 / 16.0, 3.0 / (8.0 * np.maximum(valence, 1)))


def _refine(p: np.ndarray, f: np.ndarray, e: _Edges) -> tuple:
    """One level: the old vertices moved, then one new vertex per edge, in the edges' order; each
    face's four children as pbrt-v4 orders them (a corner's child for each corner, then the middle)."""
    n = len(p)
    beta = _beta(e.valence)[:, None]
    even = np.where(e.boundary[:, None], 0.75 * p + 0.125 * e.boundary_sum, (1 - e.valence[:, None] * beta) * p
                    + beta * e.ring_sum)
    a, b = e.ends // n, e.ends % n
    facing = _sums(e.edge, p[np.roll(f, -2, axis=1).reshape(-1)], len(e.ends))     # each half-edge's opposite corner
    odd = np.where(e.boundary_edge[:, None], 0.5 * (p[a] + p[b]), 0.375 * (p[a] + p[b]) + 0.125 * facing)
    v0, v1, v2 = f[:, 0], f[:, 1], f[:, 2]
    o0, o1, o2 = (n + e.edge.reshape(-1, 3)[:, k] for k in range(3))     # the new vertices of edges 01, 12, 20
    children = np.stack([np.stack([v0, o0, o2], 1), np.stack([o0, v1, o1], 1), np.stack([o2, o1, v2], 1),
                         np.stack([o0, o1, o2], 1)], 1).reshape(-1, 3)
    return np.concatenate([even, odd]), children


def _limit_positions(p: np.ndarray, e: _Edges) -> np.ndarray:
    gamma = (1.0 / (e.valence + 3.0 / (8.0 * _beta(e.valence))))[:, None]
    return np.where(e.boundary[:, None], 0.6 * p + 0.2 * e.boundary_sum, (1 - e.valence[:, None] * gamma) * p
                    + gamma * e.ring_sum)


class _Rings:
    """Each vertex's neighbours in pbrt-v4's order (SDVertex::oneRing), as flat arrays of (vertex,
    place, neighbour): about an interior vertex face after face (h -> next(twin(h))) from any;
    about a boundary vertex from the last face one way, its first neighbour that face's next
    vertex and then each face's previous one going back (h -> twin(prev(h))). Each step takes only
    the vertices still walking, so that the work is the rings' length, not the most neighbours
    times the vertices; `count` is each ring's length and `faces` the faces walked. A walk that
    goes round a closed fan of a vertex that lies on the boundary elsewhere (a pinch) stops after
    as many steps as the vertex has faces (check_fans refuses it)."""

    def __init__(self, f: np.ndarray, e: _Edges):
        m, n = len(e.origin), len(e.valence)
        self.corners = np.bincount(f.reshape(-1), minlength=n)      # the faces about each vertex
        steps = int(self.corners.max()) + 1
        corner = np.arange(m)
        nxt, prev = corner - corner % 3 + (corner + 1) % 3, corner - corner % 3 + (corner + 2) % 3
        h = np.full(n, -1)
        h[e.origin] = corner                     # an outgoing half-edge of each vertex (the last named)
        walking = np.flatnonzero((h >= 0) & e.boundary)
        for _ in range(steps):                   # a boundary vertex's to the last face one way
            on = e.twin[h[walking]] >= 0
            walking = walking[on]
            h[walking] = nxt[e.twin[h[walking]]]
        used = np.flatnonzero(h >= 0)
        vertex, place, neighbour = [used], [np.zeros(len(used), np.int64)], [e.end[h[used]]]
        start, walking, j = h.copy(), used, 1
        self.faces = np.zeros(n, np.int64)
        self.faces[used] = 1
        while len(walking) and j <= steps:
            inner = walking[~e.boundary[walking]]
            step = nxt[e.twin[h[inner]]]
            on = step != start[inner]
            inner, step = inner[on], step[on]
            h[inner] = step
            outer = walking[e.boundary[walking]]
            vertex += [inner, outer]
            place += [np.full(len(inner) + len(outer), j)]
            neighbour += [e.end[h[inner]], e.origin[prev[h[outer]]]]
            back = e.twin[prev[h[outer]]]
            outer, back = outer[back >= 0], back[back >= 0]
            h[outer] = back
            walking = np.concatenate([inner, outer])
            self.faces[walking] += 1
            j += 1
        self.vertex, self.place, self.neighbour = np.concatenate(vertex), np.concatenate(place), np.concatenate(neighbour)
        self.count = np.bincount(self.vertex, minlength=n)

    def check_fans(self):
        """Refuses a vertex whose faces are not the one fan the walk goes round (two cones at one
        apex, a triangle on a cone's tip): pbrt-v4 would walk one fan and leave the rest."""
        if np.any(self.faces != self.corners):
            raise ValueError("indices: a vertex joins fans of triangles that share no edge (a bow tie), which Loop "
                             "subdivision cannot walk")

    def at(self, p: np.ndarray, j) -> np.ndarray:
        """Each vertex's neighbour at place j (an int, or one per vertex) of its ring: (V, 3), zero
        where its ring is shorter."""
        j = np.broadcast_to(j, self.count.shape)
        chosen = self.place == j[self.vertex]
        out = np.zeros((len(self.count), 3))
        out[self.vertex[chosen]] = p[self.neighbour[chosen]]
        return out


def _limit_normals(p: np.ndarray, rings: _Rings, e: _Edges) -> np.ndarray:
    """Each vertex's normal S x T from its limit tangents, as pbrt-v4 computes them: about an
    interior vertex S and T are its ring weighted by cos and sin of 2 pi j / n; on the boundary S
    runs between its two boundary neighbours and T has weights by its count of neighbours."""
    n, count = len(p), rings.count
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
    on = e.boundary & (count >= 2)
    s = np.where(on[:, None], last - r0, s)
    t = np.where(on[:, None], t_boundary, t)
    normal = np.cross(s, t)
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return normal / np.where(length > 0, length, 1.0)
