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
    consistently) subdivided `levels` times and pushed to the limit surface. Raises ValueError
    where an edge is shared by more than two faces or by two that run it the same way (pbrt-v4's
    mesh walk needs a consistently wound manifold; nor can it walk a vertex where two fans of
    triangles meet), or where the result would pass MAX_TRIANGLES."""
    p, f = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    if len(f) << (2 * levels) > MAX_TRIANGLES:
        raise ValueError(f"levels: {levels} levels make {len(f) << (2 * levels):,} triangles of {len(f):,}, "
                         f"more than {MAX_TRIANGLES:,}")
    for _ in range(levels):
        p, f = _refine(p, f, _Edges(p, f))
    edges = _Edges(p, f)
    p = _limit_positions(p, edges)
    return p, f, _limit_normals(p, f, edges)


class _Edges:
    """The half-edges of a mesh: their origins, ends and twins (-1 on the boundary), each one's
    undirected edge, and per vertex its neighbours' count and sum and its boundary neighbours' sum."""

    def __init__(self, p: np.ndarray, f: np.ndarray):
        n = len(p)
        self.origin, self.end = f.reshape(-1), np.roll(f, -1, axis=1).reshape(-1)
        key = np.minimum(self.origin, self.end) * n + np.maximum(self.origin, self.end)
        unique, self.edge, count = np.unique(key, return_inverse=True, return_counts=True)
        if np.any(count > 2):
            raise ValueError("indices: an edge is shared by more than two triangles, which Loop subdivision cannot "
                             "walk")
        directed = self.origin * n + self.end
        order = np.argsort(directed)
        if np.any(np.diff(directed[order]) == 0):
            raise ValueError("indices: two triangles that share an edge run it the same way (wound inconsistently)")
        back = self.end * n + self.origin
        at = np.minimum(np.searchsorted(directed[order], back), len(order) - 1)
        self.twin = np.where(directed[order][at] == back, order[at], -1)
        self.ends = unique                                  # each edge's a * n + b, a < b
        a, b = unique // n, unique % n
        self.boundary_edge = count == 1
        self.valence = np.bincount(np.concatenate([a, b]), minlength=n)
        self.ring_sum = np.zeros((n, 3))
        np.add.at(self.ring_sum, a, p[b])
        np.add.at(self.ring_sum, b, p[a])
        ba, bb = a[self.boundary_edge], b[self.boundary_edge]
        if np.any(np.bincount(np.concatenate([ba, bb]), minlength=n) > 2):
            raise ValueError("indices: a vertex joins fans of triangles that share no edge (a bow tie), which Loop "
                             "subdivision cannot walk")
        self.boundary = np.zeros(n, bool)
        self.boundary[ba] = self.boundary[bb] = True
        self.boundary_sum = np.zeros((n, 3))
        np.add.at(self.boundary_sum, ba, p[bb])
        np.add.at(self.boundary_sum, bb, p[ba])


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
    facing = np.zeros((len(e.ends), 3))
    np.add.at(facing, e.edge, p[np.roll(f, -2, axis=1).reshape(-1)])     # each half-edge's opposite corner
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


def _rings(f: np.ndarray, e: _Edges, n: int) -> tuple:
    """Each vertex's neighbours in pbrt-v4's order (SDVertex::oneRing): about an interior vertex
    face after face (h -> next(twin(h))) from any; about a boundary vertex from the last face one
    way, its first neighbour that face's next vertex and then each face's previous one going back
    (h -> twin(prev(h))). (V, the most neighbours) indices, padded with -1, and their counts."""
    m = len(e.origin)
    nxt = np.arange(m) - np.arange(m) % 3 + (np.arange(m) + 1) % 3
    prev = np.arange(m) - np.arange(m) % 3 + (np.arange(m) + 2) % 3
    h = np.full(n, -1)
    h[e.origin] = np.arange(m)                  # an outgoing half-edge of each vertex (the last named)
    used = h >= 0
    width = int(e.valence.max()) if n else 0
    ring = np.full((n, width), -1)
    for _ in range(width):                      # a boundary vertex's to the last face one way
        on = used & e.boundary & (e.twin[h] >= 0)
        h = np.where(on, nxt[e.twin[h]], h)
    interior, boundary = used & ~e.boundary, used & e.boundary
    start = h.copy()
    ring[interior, 0] = e.end[h[interior]]
    ring[boundary, 0] = e.end[h[boundary]]
    going = used.copy()
    for j in range(1, width):
        h_int = np.where(interior & going, nxt[e.twin[np.maximum(h, 0)]], h)
        going &= ~(interior & (h_int == start))
        h = np.where(interior & going, h_int, h)
        ring[interior & going, j] = e.end[h[interior & going]]
        ring[boundary & going, j] = e.origin[prev[h[boundary & going]]]
        h_bnd = e.twin[prev[np.maximum(h, 0)]]
        going &= ~(boundary & (h_bnd < 0))
        h = np.where(boundary & going, h_bnd, h)
    return ring, np.count_nonzero(ring >= 0, axis=1)


def _limit_normals(p: np.ndarray, f: np.ndarray, e: _Edges) -> np.ndarray:
    """Each vertex's normal S x T from its limit tangents, as pbrt-v4 computes them: about an
    interior vertex S and T are its ring weighted by cos and sin of 2 pi j / n; on the boundary S
    runs between its two boundary neighbours and T has weights by its count of neighbours."""
    n = len(p)
    ring, count = _rings(f, e, n)
    r = np.where((ring >= 0)[..., None], p[np.maximum(ring, 0)], 0.0)
    r = np.pad(r, ((0, 0), (0, max(0, 4 - r.shape[1])), (0, 0)))      # r[:, :4] for the short rings' rules
    j = np.arange(r.shape[1])[None, :]
    inside = j < count[:, None]
    angle = 2 * np.pi * j / np.maximum(count, 1)[:, None]
    s = np.einsum("vj,vjc->vc", np.cos(angle) * inside, r)
    t = np.einsum("vj,vjc->vc", np.sin(angle) * inside, r)
    last = r[np.arange(n), np.maximum(count - 1, 0)]
    theta = np.pi / np.maximum(count - 1, 1)[:, None]
    weight = (2 * np.cos(theta) - 2) * np.sin(j * theta) * ((j >= 1) & (j < (count - 1)[:, None]))
    t_boundary = -(np.sin(theta) * (r[:, 0] + last) + np.einsum("vj,vjc->vc", weight, r))
    for c, value in ((2, r[:, 0] + r[:, 1] - 2 * p), (3, r[:, 1] - p),
                     (4, -r[:, 0] + 2 * r[:, 1] + 2 * r[:, 2] - r[:, 3] - 2 * p)):
        t_boundary = np.where((count == c)[:, None], value, t_boundary)
    on = e.boundary & (count >= 2)
    s = np.where(on[:, None], last - r[:, 0], s)
    t = np.where(on[:, None], t_boundary, t)
    normal = np.cross(s, t)
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    return normal / np.where(length > 0, length, 1.0)
