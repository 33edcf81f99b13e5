"""Geometry for the generated levels (plain Python 3): convex planar polygons, boxes, prisms,
walls with openings, and a Lightmap-Pack-like TEXCOORD_1 (one chart per polygon, shelf-packed).

A polygon is a list of 3D points, counter-clockwise seen from its front (the side its normal
points to). Every function is deterministic: no sets or dict-order dependence, no randomness.
"""
import math

# faces of an axis-aligned box: (axis, side), side 0 = the low face (normal -axis)
_BOX_FACES = ((1, 0, "bottom"), (1, 1, "top"), (2, 0, "back"), (2, 1, "front"), (0, 0, "left"), (0, 1, "right"))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def poly_normal(p):
    """Newell's normal of a polygon (unit)."""
    n = [0.0, 0.0, 0.0]
    for i in range(len(p)):
        a, b = p[i], p[(i + 1) % len(p)]
        n[0] += (a[1] - b[1]) * (a[2] + b[2])
        n[1] += (a[2] - b[2]) * (a[0] + b[0])
        n[2] += (a[0] - b[0]) * (a[1] + b[1])
    return norm(n)


def rect(axis, c, ra, rb, facing):
    """An axis-aligned rectangle in the plane coordinate[axis] = c spanning ra x rb on the two other
    axes (in increasing axis order), facing +axis (facing > 0) or -axis."""
    a_ax, b_ax = [k for k in range(3) if k != axis]
    pts = []
    for a, b in ((ra[0], rb[0]), (ra[1], rb[0]), (ra[1], rb[1]), (ra[0], rb[1])):
        q = [0.0, 0.0, 0.0]
        q[axis], q[a_ax], q[b_ax] = c, a, b
        pts.append(tuple(q))
    if poly_normal(pts)[axis] * facing < 0:
        pts = pts[::-1]
    return pts


def box(lo, hi, skip=()):
    """The six outward faces of an axis-aligned box, less those named in skip."""
    out = []
    for axis, side, name in _BOX_FACES:
        if name in skip:
            continue
        a_ax, b_ax = [k for k in range(3) if k != axis]
        out.append(rect(axis, hi[axis] if side else lo[axis], (lo[a_ax], hi[a_ax]), (lo[b_ax], hi[b_ax]),
                        1 if side else -1))
    return out


def prism(cx, cz, r, y0, y1, n=24, skip=()):
    """A vertical n-gon prism (a round table top, a pedestal): top, bottom, n side quads."""
    ring = [(cx + r * math.cos(2 * math.pi * k / n), cz - r * math.sin(2 * math.pi * k / n)) for k in range(n)]
    out = []
    if "top" not in skip:
        out.append([(x, y1, z) for x, z in ring])
    if "bottom" not in skip:
        out.append([(x, y0, z) for x, z in ring[::-1]])
    for k in range(n):
        (xa, za), (xb, zb) = ring[k], ring[(k + 1) % n]
        q = [(xa, y0, za), (xb, y0, zb), (xb, y1, zb), (xa, y1, za)]
        mid = ((xa + xb) / 2 - cx, 0.0, (za + zb) / 2 - cz)
        out.append(q if dot(poly_normal(q), mid) > 0 else q[::-1])
    return out


def cells_around(ra, rb, holes):
    """Splits the rectangle ra x rb into grid cells along the holes' edges; returns the cells that
    lie in no hole (holes: (a0, a1, b0, b1) inside the rectangle)."""
    ca = sorted(set([ra[0], ra[1]] + [h[k] for h in holes for k in (0, 1)]))
    cb = sorted(set([rb[0], rb[1]] + [h[k] for h in holes for k in (2, 3)]))
    out = []
    for j in range(len(cb) - 1):
        for i in range(len(ca) - 1):
            ma, mb = (ca[i] + ca[i + 1]) / 2, (cb[j] + cb[j + 1]) / 2
            if any(h[0] < ma < h[1] and h[2] < mb < h[3] for h in holes):
                continue
            out.append(((ca[i], ca[i + 1]), (cb[j], cb[j + 1])))
    return out


def wall(axis, c, ra, rb, facing, holes=()):
    """A one-sided wall (rectangles around the holes) facing +-axis."""
    return [rect(axis, c, a, b, facing) for a, b in cells_around(ra, rb, list(holes))]


def room_shell(W, H, D, openings=(), skip=()):
    """(name, material, polygons) of a closed W x H x D room of one-sided surfaces facing inwards
    (floor y = 0, ceiling y = H, walls x = 0, x = W, z = 0, z = D). openings: (wall, a0, a1, y0, y1)
    with wall in back (z = 0), front (z = D), left (x = 0), right (x = W); a runs along x for back
    and front, along z for left and right."""
    spec = (("wall_back", 2, 0.0, (0, W), 1), ("wall_front", 2, D, (0, W), -1),
            ("wall_left", 0, 0.0, (0, D), 1), ("wall_right", 0, W, (0, D), -1))
    objs = [("floor", "floor", [rect(1, 0.0, (0, W), (0, D), 1)]),
            ("ceiling", "ceiling", [rect(1, H, (0, W), (0, D), -1)])]
    for name, axis, c, ra, facing in spec:
        if name in skip:
            continue
        holes = [o[1:] for o in openings if "wall_" + o[0] == name]
        if axis == 2:  # plane z = c: the rectangle spans x (first) and y (second)
            polys = wall(2, c, ra, (0, H), facing, holes)
        else:  # plane x = c: spans y (first) and z (second)
            polys = wall(0, c, (0, H), ra, facing, [(h[2], h[3], h[0], h[1]) for h in holes])
        objs.append((name, "plaster", polys))
    return objs


# wall name -> (axis of its plane, outward sign, the in-plane axis that an opening's a runs along)
_WALLS = {"back": (2, -1, 0), "front": (2, 1, 0), "left": (0, -1, 2), "right": (0, 1, 2)}


def _rect_axes(axis, c, ranges, facing):
    """rect() with the two other axes' ranges given by axis number."""
    a_ax, b_ax = [k for k in range(3) if k != axis]
    return rect(axis, c, ranges[a_ax], ranges[b_ax], facing)


def hull(W, H, D, openings, T=0.4):
    """The outside of a room: a closed box T outside the room's planes whose faces point outwards
    (seen from between it and the room, every face is a back face), holes at the openings and a
    tunnel (four quads facing into the opening) from each opening's outer face to the hull.
    openings: (wall, a0, a1, y0, y1, d) with d how far outside the wall's plane the opening's
    outer face lies (0 for a one-sided room_shell wall, the thickness for a wall of boxes). Faces
    against a one-sided wall or floor (a crate's bottom, a shelf flush with a wall) then lie in a
    closed cavity, as in a level with thick walls, instead of in the open sky."""
    lo, hi = (-T, -T, -T), (W + T, H + T, D + T)
    planes = {"back": 0.0, "front": D, "left": 0.0, "right": W}
    out = []
    for axis, side, name in _BOX_FACES:
        a_ax, b_ax = [k for k in range(3) if k != axis]
        hs = []
        for o in openings:
            ax, sgn, o_ax = _WALLS[o[0]]
            if ax == axis and (sgn > 0) == bool(side):
                r = {o_ax: (o[1], o[2]), 1: (o[3], o[4])}
                hs.append((r[a_ax][0], r[a_ax][1], r[b_ax][0], r[b_ax][1]))
        out += wall(axis, hi[axis] if side else lo[axis], (lo[a_ax], hi[a_ax]), (lo[b_ax], hi[b_ax]),
                    1 if side else -1, hs)
    for o in openings:
        ax, sgn, a_ax = _WALLS[o[0]]
        c = planes[o[0]]
        depth = tuple(sorted((c + sgn * o[5], c + sgn * T)))
        # the tunnel's sides: planes at a0 and a1 facing inwards, then at y0 and y1
        for k, ra, other, span in ((a_ax, (o[1], o[2]), 1, (o[3], o[4])), (1, (o[3], o[4]), a_ax, (o[1], o[2]))):
            for val, f in ((ra[0], 1), (ra[1], -1)):
                out.append(_rect_axes(k, val, {ax: depth, other: span}, f))
    return out


def triangulate(polys):
    """Flat-shaded triangle lists: (pos, nrm, idx, corner) with corner[i] = (polygon, vertex)."""
    pos, nrm, idx, corner = [], [], [], []
    for pi, p in enumerate(polys):
        n = poly_normal(p)
        base = len(pos) // 3
        for vi, q in enumerate(p):
            pos.extend(q)
            nrm.extend(n)
            corner.append((pi, vi))
        for k in range(1, len(p) - 1):
            idx.extend((base, base + k, base + k + 1))
    return pos, nrm, idx, corner


def _chart_2d(p):
    """The polygon in its own plane, metres, lower corner at 0: list of (x, y), width, height."""
    n = poly_normal(p)
    u = norm(sub(p[1], p[0]))
    v = cross(n, u)
    xy = [(dot(sub(q, p[0]), u), dot(sub(q, p[0]), v)) for q in p]
    mx, my = min(x for x, _ in xy), min(y for _, y in xy)
    xy = [(x - mx, y - my) for x, y in xy]
    return xy, max(x for x, _ in xy), max(y for _, y in xy)


def lightmap_pack(polys, margin):
    """Lightmap-Pack-like authored TEXCOORD_1: one chart per polygon at its world size, charts
    shelf-packed (tallest first) with `margin` metres between them, the whole layout scaled
    uniformly into [0, 1]^2. Returns per polygon vertex a (u, v) in glTF convention (v down)."""
    charts = [_chart_2d(p) for p in polys]
    area = sum((w + margin) * (h + margin) for _, w, h in charts)
    row_w = max(max(w for _, w, _ in charts) + margin, math.sqrt(area) * 1.1)
    order = sorted(range(len(charts)), key=lambda i: (-charts[i][2], i))
    at = [None] * len(charts)
    x = y = shelf = margin
    for i in order:
        _, w, h = charts[i]
        if x + w + margin > row_w and x > margin:
            x, y = margin, y + shelf + margin
            shelf = margin
        at[i] = (x, y)
        x += w + margin
        shelf = max(shelf, h)
    extent = max(row_w, y + shelf + margin)
    out = []
    for (xy, _, _), (ox, oy) in zip(charts, at):
        out.append([((ox + px) / extent, 1.0 - (oy + py) / extent) for px, py in xy])
    return out


def look_rotation(d):
    """Quaternion (x, y, z, w) turning -Z onto the unit direction d (a directional light's node)."""
    a = (0.0, 0.0, -1.0)
    c = dot(a, d)
    if c < -0.999999:
        return (0.0, 1.0, 0.0, 0.0)
    ax = cross(a, d)
    s = math.sqrt((1 + c) * 2)
    return (ax[0] / s, ax[1] / s, ax[2] / s, s / 2)
