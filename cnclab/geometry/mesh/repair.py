"""Mesh repair: consistent facet orientation (:func:`orient_facets`: welded vertices, winding parity by
union-find with a breadth-first graph fallback, closed components outward, open ones by ray parity or
upward)."""
from __future__ import annotations

import numpy as np
from numba import njit

from .core import facet_normals  # noqa: F401 (the doctest of orient_facets)

__all__ = ["orient_facets", "orient_with_info", "weld_ids", "first_equal_triple"]


def orient_facets(triangles, rule: str = "auto"):
    """Re-orient facets consistently; returns (triangles, flipped bool mask (F,), info dict).

    Rule (``rule="auto"``): vertices are welded (exact coordinate equality, as written in the STL);
    across every edge shared by exactly two facets the winding must run in opposite directions, so
    each edge-connected component gets one consistent winding (breadth-first propagation); then each
    component is turned **outward** if it is closed (no boundary edge; signed volume > 0). An open
    component (boundary edges) is decided by ray parity when the mesh has several components (a solid
    closed only geometrically: walls meeting a surface at T-junctions, a separate bottom): a ray from
    its largest facet along the normal crossing the mesh an odd number of times, and the opposite
    ray an even number, means the normal points into material (flip); otherwise -- a truly open
    surface -- it is turned **upward** (area-weighted mean normal N_z >= 0; a component with zero N_z
    sum keeps the majority winding of the file). (Ray tests: the 64 largest open components.) Edges shared by more than two facets are ignored and counted
    (``non_manifold_edges``); a non-orientable component keeps the propagated winding and its
    conflicting edges are counted (``winding_conflicts``). ``rule="keep"`` changes nothing.

    >>> tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [0, 1, 0], [1, 1, 0]]], float)
    >>> t, flipped, info = orient_facets(tri)        # second facet wound clockwise (normal -Z)
    >>> flipped.tolist(), facet_normals(t)[:, 2].tolist()
    ([False, True], [1.0, 1.0])
    """
    tri = np.array(triangles, dtype=float, copy=True)
    F = len(tri)
    info = {"components": 0, "non_manifold_edges": 0, "winding_conflicts": 0, "boundary_edges": 0}
    if rule == "keep":
        return tri, np.zeros(F, bool), info
    if rule != "auto":
        raise ValueError(f"orient must be 'auto' or 'keep', got {rule!r}")
    if F == 0:
        return tri, np.zeros(0, bool), info
    return orient_with_info(tri, info)


def orient_with_info(tri, info, vid=None):
    """orient_facets on a float copy ``tri`` (F > 0); ``vid`` (F, 3) welded vertex ids if known.

    Fast path (compiled): weld, group the half-edges by edge, and propagate the winding parity by a
    union-find. When no edge disagrees with the propagated winding (every orientable mesh), the
    parity relative to the lowest-index facet of each component is the one the breadth-first
    propagation gives, and the components are labelled in order of their lowest facet as
    ``scipy.sparse.csgraph.connected_components`` does, so the result is identical. A mesh with
    winding conflicts takes the graph path (:func:`_orient_graph`) unchanged.
    """
    F = len(tri)
    if vid is None:
        vid = weld_ids(tri)
    res = _edge_parity(np.ascontiguousarray(vid, np.int64).reshape(F, 3))
    conflict, n_bnd, n_nm, ncomp, comp, flip, open_fac = res
    if conflict:
        return _orient_graph(tri, info)
    info["boundary_edges"] = int(n_bnd)
    info["non_manifold_edges"] = int(n_nm)
    info["components"] = int(ncomp)
    open_comp = np.zeros(ncomp, bool)
    open_comp[comp[open_fac]] = True
    return _orient_turn(tri, info, comp, ncomp, flip, open_comp)


def weld_ids(tri) -> np.ndarray:
    """Vertex ids (F, 3) welding exactly equal coordinates (-0.0 == 0.0), numbered by first use."""
    flat = np.ascontiguousarray(tri.reshape(-1, 3)) + 0.0
    return _weld(flat.view(np.uint64)).reshape(-1, 3)


@njit(cache=True, nogil=True)
def _mix(x, y, z):
    h = x * np.uint64(0x9E3779B97F4A7C15) ^ y * np.uint64(0xC2B2AE3D27D4EB4F) ^ z * np.uint64(0x165667B19E3779F9)
    h ^= h >> np.uint64(31)
    h *= np.uint64(0xBF58476D1CE4E5B9)
    h ^= h >> np.uint64(29)
    return h


@njit(cache=True, nogil=True)
def _hash_table(n):
    """Empty open-addressing table (-1 = free) of a power-of-two size >= 2 n, and its index mask."""
    size = 16
    while size < 2 * n:
        size *= 2
    return np.full(size, -1, np.int64), np.uint64(size - 1)


@njit(cache=True, nogil=True)
def _weld(bits):
    """Id per row of ``bits`` (N, 3) uint64: rows equal bit for bit share an id (open addressing)."""
    n = bits.shape[0]
    table, mask = _hash_table(n)
    vid = np.empty(n, np.int64)
    nv = 0
    for i in range(n):
        slot = _mix(bits[i, 0], bits[i, 1], bits[i, 2]) & mask
        while True:
            j = table[slot]
            if j < 0:
                table[slot] = i
                vid[i] = nv
                nv += 1
                break
            if bits[j, 0] == bits[i, 0] and bits[j, 1] == bits[i, 1] and bits[j, 2] == bits[i, 2]:
                vid[i] = vid[j]
                break
            slot = (slot + np.uint64(1)) & mask
    return vid


@njit(cache=True, nogil=True)
def first_equal_triple(vid):
    """For each row of ``vid`` (F, 3) the first row with the same three ids in any order."""
    F = vid.shape[0]
    table, mask = _hash_table(F)
    key = np.empty((F, 3), np.int64)
    first = np.empty(F, np.int64)
    for i in range(F):
        a, b, c = vid[i, 0], vid[i, 1], vid[i, 2]
        if a > b:
            a, b = b, a
        if b > c:
            b, c = c, b
        if a > b:
            a, b = b, a
        key[i, 0], key[i, 1], key[i, 2] = a, b, c
        slot = _mix(np.uint64(a), np.uint64(b), np.uint64(c)) & mask
        while True:
            j = table[slot]
            if j < 0:
                table[slot] = i
                first[i] = i
                break
            if key[j, 0] == a and key[j, 1] == b and key[j, 2] == c:
                first[i] = j
                break
            slot = (slot + np.uint64(1)) & mask
    return first


@njit(cache=True)
def _find(parent, par, x):
    """Root of x and the parity of x relative to it (path compression keeps the parities)."""
    p = 0
    r = x
    while parent[r] != r:
        p ^= par[r]
        r = parent[r]
    # compress: point every node of the path at the root with its own parity
    q = p
    y = x
    while parent[y] != y:
        nxt = parent[y]
        py = par[y]
        parent[y] = r
        par[y] = q
        q ^= py
        y = nxt
    return r, p


@njit(cache=True, nogil=True)
def _edge_parity(V):
    """Edges of the facets ``V`` (F, 3) by bucketing half-edges, winding parity by union-find.

    Returns (conflict, boundary edges, non-manifold edges, components, component label per facet
    (in order of the lowest facet), flip parity to that facet, facets of boundary/non-manifold edges).
    """
    F = V.shape[0]
    H = 3 * F
    nv = V.max() + 1
    # half-edges bucketed by their lower vertex (counting sort: h order kept inside a bucket), then
    # grouped by the upper vertex inside each bucket: one group per undirected edge
    start = np.zeros(nv + 1, np.int64)
    for h in range(H):
        f = h // 3
        a = V[f, h % 3]
        b = V[f, (h % 3 + 1) % 3]
        start[min(a, b) + 1] += 1
    for v in range(nv):
        start[v + 1] += start[v]
    fill = start[:-1].copy()
    bucket = np.empty(H, np.int64)
    upper = np.empty(H, np.int64)
    for h in range(H):
        f = h // 3
        a = V[f, h % 3]
        b = V[f, (h % 3 + 1) % 3]
        lo = min(a, b)
        bucket[fill[lo]] = h
        upper[fill[lo]] = max(a, b)
        fill[lo] += 1
    n_edges = 0
    e_first = np.empty(H, np.int64)       # per edge: first and second half-edge, count
    e_second = np.empty(H, np.int64)
    e_cnt = np.zeros(H, np.int64)
    scratch = np.empty(64, np.int64)
    for v in range(nv):
        s0, s1 = start[v], start[v + 1]
        k = s1 - s0
        if k > 64:
            o = np.argsort(upper[s0:s1], kind="mergesort") + s0     # stable: h order among equals
        else:                                                       # stable insertion sort
            o = scratch[:k]
            for i in range(k):
                x = s0 + i
                j = i
                while j > 0 and upper[o[j - 1]] > upper[x]:
                    o[j] = o[j - 1]
                    j -= 1
                o[j] = x
        i = 0
        while i < k:
            j = i + 1
            while j < k and upper[o[j]] == upper[o[i]]:
                j += 1
            e_first[n_edges] = bucket[o[i]]
            e_second[n_edges] = bucket[o[i + 1]] if j - i > 1 else -1
            e_cnt[n_edges] = j - i
            n_edges += 1
            i = j
    parent = np.arange(F)
    par = np.zeros(F, np.uint8)
    rank = np.ones(F, np.int64)
    open_mark = np.zeros(F, np.bool_)
    n_bnd = 0
    n_nm = 0
    conflict = False
    for e in range(n_edges):
        c = e_cnt[e]
        ha = e_first[e]
        fa = ha // 3
        if c == 1:
            n_bnd += 1
            open_mark[fa] = True
        elif c > 2:
            n_nm += 1
            open_mark[fa] = True
        elif fa != e_second[e] // 3:
            hb = e_second[e]
            fb = hb // 3
            da = V[fa, ha % 3] < V[fa, (ha % 3 + 1) % 3]
            db = V[fb, hb % 3] < V[fb, (hb % 3 + 1) % 3]
            same = np.uint8(1) if da == db else np.uint8(0)
            ra, pa = _find(parent, par, fa)
            rb, pb = _find(parent, par, fb)
            if ra == rb:
                if (pa ^ pb) != same:
                    conflict = True
            elif rank[ra] < rank[rb]:       # union by size keeps the trees shallow
                parent[ra] = rb
                par[ra] = pa ^ pb ^ same
                rank[rb] += rank[ra]
            else:
                parent[rb] = ra
                par[rb] = pa ^ pb ^ same
                rank[ra] += rank[rb]
    comp = np.empty(F, np.int64)
    flip = np.zeros(F, np.bool_)
    label = np.full(F, -1, np.int64)
    rootpar = np.zeros(F, np.uint8)
    ncomp = 0
    for f in range(F):
        r, p = _find(parent, par, f)
        if label[r] < 0:
            label[r] = ncomp
            rootpar[ncomp] = p
            ncomp += 1
        comp[f] = label[r]
        flip[f] = (p ^ rootpar[label[r]]) != 0
    return conflict, n_bnd, n_nm, ncomp, comp, flip, np.flatnonzero(open_mark)


def _orient_graph(tri, info):
    """The graph path of orient_facets (scipy breadth-first propagation; any mesh)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    F = len(tri)
    flat = np.ascontiguousarray(tri.reshape(-1, 3)) + 0.0          # + 0.0: -0.0 welds with 0.0
    _, vid = np.unique(flat.view(np.dtype((np.void, 24))).ravel(), return_inverse=True)
    V = vid.reshape(F, 3)
    a = V.ravel()
    b = V[:, [1, 2, 0]].ravel()
    fac = np.repeat(np.arange(F), 3)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    fwd = a < b
    order = np.lexsort((hi, lo))
    lo_s, hi_s = lo[order], hi[order]
    new = np.ones(order.size, bool)
    new[1:] = (lo_s[1:] != lo_s[:-1]) | (hi_s[1:] != hi_s[:-1])
    gid = np.cumsum(new) - 1
    cnt = np.bincount(gid)
    info["boundary_edges"] = int((cnt == 1).sum())
    info["non_manifold_edges"] = int((cnt > 2).sum())
    first = np.flatnonzero(new)
    pair = first[cnt[gid[first]] == 2]
    f1, f2 = fac[order[pair]], fac[order[pair + 1]]
    same = fwd[order[pair]] == fwd[order[pair + 1]]          # same direction -> relative flip
    keep = f1 != f2
    f1, f2, same = f1[keep], f2[keep], same[keep]
    _, u = np.unique(np.minimum(f1, f2) * F + np.maximum(f1, f2), return_index=True)
    f1, f2, same = f1[u], f2[u], same[u]                        # one link per facet pair
    # graph with a virtual root F linked to every facet (weight 1 = no flip) so one BFS covers all
    w = np.concatenate([same + 1, same + 1]).astype(np.int8)   # 1 = consistent, 2 = flip
    rows = np.concatenate([f1, f2])
    cols = np.concatenate([f2, f1])
    G = coo_matrix((w, (rows, cols)), shape=(F, F)).tocsr()
    ncomp, comp = connected_components(G, directed=False)
    info["components"] = int(ncomp)
    root_of = np.full(ncomp, -1)
    root_of[comp[::-1]] = np.arange(F)[::-1]                  # first facet of each component
    R = coo_matrix((np.ones(ncomp, np.int8), (np.full(ncomp, F), root_of)), shape=(F + 1, F + 1))
    Gx = coo_matrix((G.data, (np.repeat(np.arange(F), np.diff(G.indptr)), G.indices)), shape=(F + 1, F + 1))
    H = (Gx + R).tocsr()
    _, pred = breadth_first_order(H, F, directed=True, return_predecessors=True)
    pred = pred[:F]
    par = np.zeros(F, np.int8)
    tree = pred != F
    if tree.any():
        keys = np.concatenate([f1 * F + f2, f2 * F + f1])
        vals = np.concatenate([same, same])
        o = np.argsort(keys)
        pos = np.searchsorted(keys[o], pred[tree].astype(np.int64) * F + np.flatnonzero(tree))
        par[tree] = vals[o][pos].astype(np.int8)
    anc = np.where(tree, pred, np.arange(F))
    while True:       # pointer jumping: parity to the component root = XOR along the tree path
        moving = anc[anc] != anc
        if not moving.any():
            break
        par = np.where(moving, par ^ par[anc], par)
        anc = np.where(moving, anc[anc], anc)
    flip = par.astype(bool)
    info["winding_conflicts"] = int(((flip[f1] ^ flip[f2]) != same).sum())
    bnd_fac = fac[order[first[cnt[gid[first]] == 1]]]
    open_comp = np.zeros(ncomp, bool)
    open_comp[comp[bnd_fac]] = True
    nm_fac = fac[order[first[cnt[gid[first]] > 2]]]
    open_comp[comp[nm_fac]] = True
    return _orient_turn(tri, info, comp, ncomp, flip, open_comp)


def _orient_turn(tri, info, comp, ncomp, flip, open_comp):
    """One sign per component: closed -> outward (signed volume), open -> upward (sum of N_z * area)
    or by ray parity (see :func:`orient_facets`); returns (triangles, flipped, info)."""
    F = len(tri)
    t2 = np.where(flip[:, None, None], tri[:, ::-1], tri) if flip.any() else tri
    cross = np.cross(t2[:, 1] - t2[:, 0], t2[:, 2] - t2[:, 0])
    vol = np.bincount(comp, (t2[:, 0] * cross).sum(axis=1), ncomp)
    upz = np.bincount(comp, cross[:, 2], ncomp)
    agree = np.bincount(comp, (~flip).astype(float), ncomp) - np.bincount(comp, flip.astype(float), ncomp)
    turn = np.where(open_comp, np.where(upz != 0, upz < 0, agree < 0), vol < 0)
    # open components of a solid that is closed only geometrically (walls meeting a surface at
    # T-junctions, separate bottom ...): ray parity from the largest facet of the component decides
    # (odd crossings along the normal -> the normal points into material -> flip). Rays in both
    # directions must disagree in parity, else (a truly open surface) the upward rule above stands.
    areas = np.linalg.norm(cross, axis=1)
    cand = np.flatnonzero(open_comp)
    if cand.size and ncomp > 1:
        cand = cand[np.argsort(-np.bincount(comp, areas, ncomp)[cand])][:64]
        big = np.full(ncomp, -1)
        order_a = np.lexsort((-areas, comp))
        firsts = np.ones(F, bool)
        firsts[1:] = comp[order_a][1:] != comp[order_a][:-1]
        big[comp[order_a][firsts]] = order_a[firsts]
        for c in cand:
            f = big[c]
            n = cross[f] / areas[f]
            o = t2[f].mean(axis=0)                       # independent of the vertex order
            sgn = 1.0 if n @ _RAY_W >= 0 else -1.0       # canonical direction: same rays either winding
            d = sgn * n + 1e-4 * _RAY_W
            along = _ray_hits(o, d, t2, exclude=f)
            against = _ray_hits(o, -d, t2, exclude=f)
            if along % 2 != against % 2:                 # material on exactly one side
                inside = along % 2 == 1 if sgn > 0 else against % 2 == 1
                turn[c] = inside
    flip = flip ^ turn[comp]
    out = np.where(flip[:, None, None], tri[:, ::-1], tri) if flip.any() else tri
    return out, flip, info


_RAY_W = np.array([0.37, 0.59, 0.23]) / np.linalg.norm([0.37, 0.59, 0.23])


def _ray_hits(o, d, tri, exclude=-1) -> int:
    """Number of facets crossed by the ray o + t d, t > 0 (Moller-Trumbore, vectorised)."""
    e1 = tri[:, 1] - tri[:, 0]
    e2 = tri[:, 2] - tri[:, 0]
    p = np.cross(d, e2)
    det = (e1 * p).sum(axis=1)
    ok = np.abs(det) > 1e-300
    inv = np.divide(1.0, det, out=np.zeros_like(det), where=ok)
    s = o - tri[:, 0]
    u = (s * p).sum(axis=1) * inv
    q = np.cross(s, e1)
    v = (q * d).sum(axis=1) * inv
    t = (q * e2).sum(axis=1) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if exclude >= 0:
        hit[exclude] = False
    return int(hit.sum())
