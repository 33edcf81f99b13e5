"""The level families of the hard-level suite (README.md): each builder takes its variant's
parameters and a seeded random.Random and returns a Level. Plain Python 3, deterministic."""
import geom

LAMP_CD = 30.0               # point lamp, candela
SUN_LUX, SUN_SKY = 10.0, 0.25  # sun-lit levels: a directional light plus a dim sky (nits)
SUN_DIR = geom.norm((0.35, -0.55, -1.0))  # travel direction: down and into the front (z = D) window


class Level:
    """Objects (name, material, polygons), lights, sky, and per object the thinnest box extent."""

    def __init__(self, lighting):
        self.lighting = lighting
        self.objects = []
        self.thin = {}
        self.lights = []
        self.sky = (0.0, 0.0, 0.0)
        self.extras = {}

    def add(self, name, material, polys, thin=None, extras=None):
        self.objects.append((name, material, polys))
        if thin is not None:
            self.thin[name] = round(thin, 4)
        if extras:
            self.extras[name] = extras

    def shell(self, W, H, D, openings=(), skip=(), box_openings=()):
        """The room (geom.room_shell) and its outside (geom.hull): a black, unlit closed box 40 cm
        out, tunnels at the openings. box_openings: openings of walls the family builds of boxes
        (wall, a0, a1, y0, y1, thickness)."""
        for name, mat, polys in geom.room_shell(W, H, D, openings, skip):
            self.add(name, mat, polys)
        hull_openings = [tuple(o) + (0.0,) for o in openings] + list(box_openings)
        self.add("exterior", "exterior", geom.hull(W, H, D, hull_openings), extras={"lbk_lighting": "none"})

    def add_boxes(self, name, material, boxes, skip=()):
        """boxes: (lo, hi) or (lo, hi, faces to skip on this box besides skip); thin: the smallest
        extent of any of them."""
        polys = []
        for b in boxes:
            polys += geom.box(b[0], b[1], tuple(skip) + tuple(b[2] if len(b) > 2 else ()))
        self.add(name, material, polys, min(min(b[1][k] - b[0][k] for k in range(3)) for b in boxes))

    def light(self, W, H, D, lamp_at=None):
        """The level's light: sky through its openings, a point lamp, or the sun plus a dim sky."""
        if self.lighting == "sky":
            self.sky = (1.0, 1.0, 1.0)
        elif self.lighting == "lamp":
            self.lights.append(("lamp", "point", LAMP_CD, lamp_at or (W / 2, H - 0.35, D / 2), None))
        else:
            self.sky = (SUN_SKY, SUN_SKY, SUN_SKY)
            self.lights.append(("sun", "directional", SUN_LUX, None, geom.look_rotation(SUN_DIR)))


def _room(rng, W=4.0, D=4.0):
    """A room size jittered by the seed (centimetre steps, so the files stay short)."""
    return W + rng.randint(-20, 20) / 100.0, 2.6 + rng.randint(0, 20) / 100.0, D + rng.randint(-20, 20) / 100.0


def _window(W, H, wide):
    """A window in the front wall: (wall, x0, x1, y0, y1); wide = a window wall."""
    return ("front", 0.3, W - 0.3, 0.45, H - 0.25) if wide else ("front", W / 2 - 1.0, W / 2 + 0.9, 0.9, 2.2)


def table_slab(p, rng):
    """A table whose top is a 1-10 cm slab (rectangular on legs, or round on a pedestal) in a room
    lit through a window wall, by a lamp, or by the sun."""
    t, shape, lighting = p["thick"], p["shape"], p["lighting"]
    W, H, D = _room(rng)
    lv = Level(lighting)
    lv.shell(W, H, D, [_window(W, H, True)])
    cx, cz = W / 2 + rng.randint(-30, 30) / 100.0, D / 2 + rng.randint(-30, 30) / 100.0
    top = 0.74
    if shape == "round":
        r = 0.55 + rng.randint(0, 10) / 100.0
        lv.add("table_top", "oak", geom.prism(cx, cz, r, top - t, top), thin=t)
        lv.add("table_pedestal", "oak", geom.prism(cx, cz, 0.06, 0.02, top - t, n=12, skip=("top", "bottom")),
               thin=0.12)
        lv.add("table_foot", "oak", geom.prism(cx, cz, 0.28, 0.0, 0.02, n=16, skip=("bottom",)), thin=0.02)
    else:
        hx, hz = 0.7 + rng.randint(0, 10) / 100.0, 0.4 + rng.randint(0, 5) / 100.0
        lv.add_boxes("table_top", "oak", [((cx - hx, top - t, cz - hz), (cx + hx, top, cz + hz))])
        legs = [((x - 0.025, 0.0, z - 0.025), (x + 0.025, top - t, z + 0.025))
                for x in (cx - hx + 0.06, cx + hx - 0.06) for z in (cz - hz + 0.06, cz + hz - 0.06)]
        lv.add_boxes("table_legs", "oak", legs, skip=("top", "bottom"))
    # a chair-height slab beside it (a bench seat, same thickness) and a box on the floor
    bx = cx + (1.0 if cx < W / 2 else -1.0)
    lv.add_boxes("bench_seat", "fabric", [((bx - 0.2, 0.45 - t, cz - 0.5), (bx + 0.2, 0.45, cz + 0.5))])
    lv.add_boxes("cabinet", "white", [((0.05, 0.0, 0.4), (0.55, 0.9, 1.3))], skip=("bottom",))
    lv.light(W, H, D)
    return lv


def shelf_slab(p, rng):
    """A shelving unit of 1-5 cm shelves against the back wall, books on them, and a floating
    wall shelf of the same slab."""
    t, n, lighting = p["thick"], p["shelves"], p["lighting"]
    W, H, D = _room(rng)
    lv = Level(lighting)
    lv.shell(W, H, D, [_window(W, H, False)])
    x0 = 0.6 + rng.randint(0, 40) / 100.0
    x1, z0, z1, sh = x0 + 1.6, 0.02, 0.4, 2.0
    boxes = [((x0, 0.0, z0), (x0 + 0.02, sh, z1)), ((x1 - 0.02, 0.0, z0), (x1, sh, z1)),
             ((x0 + 0.02, sh - t, z0), (x1 - 0.02, sh, z1))]
    ys = [0.08 + k * (sh - 0.2) / n for k in range(n)]
    boxes += [((x0 + 0.02, y, z0), (x1 - 0.02, y + t, z1)) for y in ys]
    lv.add_boxes("shelf_unit", "oak", boxes)
    k = 0
    for y in ys:
        x = x0 + 0.06
        while x < x1 - 0.3:
            h, w = 0.18 + rng.randint(0, 10) / 100.0, 0.03 + rng.randint(0, 3) / 100.0
            lv.add_boxes("book_%02d" % k, ("red", "blue", "paper")[k % 3],
                         [((x, y + t, z0 + 0.08), (x + w, y + t + h, z1 - 0.04))], skip=("bottom",))
            x += w + 0.02 + rng.randint(0, 8) / 100.0
            k += 1
            if k % 4 == 0:
                x += 0.25
    lv.add_boxes("wall_shelf", "white", [((W - 0.3, 1.5, 1.0), (W, 1.5 + t, 2.2))])
    lv.light(W, H, D)
    return lv


def thin_wall(p, rng):
    """A lit room and a dark room side by side, parted by a 2-20 cm wall with a doorway at the
    back: the dark room's light comes only through the door (any more is a leak)."""
    t, lighting = p["thick"], p["lighting"]
    _, H, D = _room(rng)
    W, xm = 7.0, 3.5
    lv = Level(lighting)
    win = ("front", 0.8, 2.7, 0.9, 2.2)
    lv.shell(W, H, D, [win])
    a, b, door_z0, door_z1, door_h = xm - t / 2, xm + t / 2, 0.3, 1.1, 2.0
    # the end faces against the (zero-thickness) front and back walls would lie outside, in the sky
    lv.add_boxes("partition", "plaster", [((a, 0.0, door_z1), (b, H, D), ("front",)),
                                          ((a, 0.0, 0.0), (b, H, door_z0), ("back",)),
                                          ((a, door_h, door_z0), (b, H, door_z1))], skip=("bottom", "top"))
    lv.add_boxes("cabinet_dark", "white", [((b, 0.0, 2.0), (b + 0.45, 0.9, 3.0))], skip=("bottom",))
    lv.add_boxes("cabinet_lit", "white", [((a - 0.45, 0.0, 2.0), (a, 0.9, 3.0))], skip=("bottom",))
    lv.light(xm, H, D, lamp_at=(xm / 2, H - 0.35, D / 2))
    return lv


def overlap(p, rng):
    """A window wall and two pillars built as artists export them: interpenetrating boxes, boxes
    poking through the floor, a wainscot panel whose back face duplicates the wall's plane, and
    stacked blocks with coplanar touching faces."""
    lighting = p["lighting"]
    W, H, D = _room(rng)
    lv = Level(lighting)
    wx0, wx1, wy0, wy1, th = W / 2 - 1.0, W / 2 + 0.9, 0.9, 2.2, 0.25
    o = 0.1 + rng.randint(0, 10) / 100.0  # how far the wall's boxes run into each other
    # the side boxes reach o into the window: the clear opening is wx0 + o .. wx1 - o
    lv.shell(W, H, D, skip=("wall_front",), box_openings=[("front", wx0 + o, wx1 - o, wy0, wy1, th)])
    lv.add_boxes("window_wall", "plaster", [((-0.05, -0.05, D), (wx0 + o, H + 0.05, D + th)),
                                            ((wx1 - o, -0.05, D), (W + 0.05, H + 0.05, D + th)),
                                            ((wx0 - o, -0.05, D - 0.001), (wx1 + o, wy0, D + th)),
                                            ((wx0 - o, wy1, D), (wx1 + o, H + 0.05, D + th + 0.002))])
    for i, px in enumerate((W * 0.25, W * 0.75)):
        pz = D * 0.45 + rng.randint(-20, 20) / 100.0
        lv.add_boxes("pillar_%d" % i, "stone", [((px - 0.15, -0.05, pz - 0.15), (px + 0.15, H + 0.05, pz + 0.15)),
                                                 ((px - 0.22, 0.0, pz - 0.22), (px + 0.22, 0.3, pz + 0.22)),
                                                 ((px - 0.2, H - 0.25, pz - 0.2), (px + 0.2, H, pz + 0.2))])
    lv.add_boxes("wainscot", "oak", [((0.3, 0.0, 0.0), (W - 0.3, 0.9, 0.02))])
    lv.add_boxes("plinth_dup", "oak", [((0.3, 0.0, 0.0), (W - 0.3, 0.12, 0.02))])  # coplanar copy of its base
    y = 0.0
    for k, e in enumerate((0.5, 0.4, 0.3)):
        lv.add_boxes("block_%d" % k, "crate", [((W - 1.0, y, 1.0), (W - 1.0 + e, y + e, 1.0 + e))])
        y += e
    lv.light(W, H, D)
    return lv


def resting(p, rng):
    """Props touching and resting on the floor and on each other, bottoms included (coplanar
    with what they stand on), a crate flush against a wall, a 1 cm rug, a low bench."""
    lighting, bottoms = p["lighting"], p["bottoms"]
    W, H, D = _room(rng)
    lv = Level(lighting)
    lv.shell(W, H, D, [_window(W, H, False)])
    skip = () if bottoms else ("bottom",)
    for k in range(3):
        x, z, e = 0.6 + 1.1 * k + rng.randint(0, 20) / 100.0, 1.2 + rng.randint(0, 80) / 100.0, 0.3 + 0.1 * k
        lv.add_boxes("crate_%d" % k, "crate", [((x, 0.0, z), (x + e, e, z + e))], skip)
    lv.add_boxes("stack_low", "crate", [((W - 1.2, 0.0, 0.6), (W - 0.6, 0.5, 1.2))], skip)
    lv.add_boxes("stack_high", "crate", [((W - 1.1, 0.5, 0.7), (W - 0.7, 0.9, 1.1))], skip)
    lv.add_boxes("crate_wall", "crate", [((0.0, 0.0, D - 1.6), (0.5, 0.6, D - 1.0))], skip)
    lv.add_boxes("rug", "fabric_red", [((1.0, 0.0, 2.4), (3.0, 0.01, 3.4))], skip)
    lv.add_boxes("bench", "oak", [((1.2, 0.1, 0.3), (2.6, 0.14, 0.7)), ((1.25, 0.0, 0.35), (1.3, 0.1, 0.65)),
                                  ((2.5, 0.0, 0.35), (2.55, 0.1, 0.65))], skip)
    lv.light(W, H, D)
    return lv


def _wall_boxes(W, H, z0, z1, holes):
    """A thick wall (z0..z1) of boxes around its holes ((x0, x1, y0, y1)); boxes touch exactly."""
    return [((a[0], b[0], z0), (a[1], b[1], z1)) for a, b in geom.cells_around((0.0, W), (0.0, H), holes)]


def sill_niche(p, rng):
    """A deep window reveal with a sill slab, a niche in a thick back wall, and a cubby unit of
    30 cm compartments with 2 cm dividers."""
    lighting, st = p["lighting"], p["sill"]
    W, H, D = _room(rng)
    lv = Level(lighting)
    win = (W / 2 - 0.9, W / 2 + 0.9, 0.9, 2.2)
    lv.shell(W, H, D, skip=("wall_front", "wall_back"), box_openings=[("front",) + win + (0.3,)])
    lv.add_boxes("front_wall", "plaster", _wall_boxes(W, H, D, D + 0.3, [win]), skip=("bottom", "top"))
    lv.add_boxes("sill", "white", [((win[0] - 0.05, win[2] - st, D - 0.06), (win[1] + 0.05, win[2], D + 0.3))])
    nx = 0.8 + rng.randint(0, 60) / 100.0
    niche = (nx, nx + 0.6, 1.0, 1.8)
    lv.add_boxes("back_wall", "plaster", _wall_boxes(W, H, -0.3, 0.0, [niche]), skip=("bottom", "top"))
    lv.add_boxes("niche_back", "plaster", [((niche[0], niche[2], -0.3), (niche[1], niche[3], -0.25))])
    cx, d = W - 1.3, 0.02
    cub = [((cx + 0.32 * i, 0.0, 0.05), (cx + 0.32 * i + d, 0.98, 0.4)) for i in range(4)]
    cub += [((cx, 0.32 * j, 0.05), (cx + 0.98, 0.32 * j + d, 0.4)) for j in range(4)]
    cub.append(((cx, 0.0, 0.05), (cx + 0.98, 0.98, 0.05 + d)))
    lv.add_boxes("cubby", "oak", cub)
    lv.light(W, H, D)
    return lv


def tiny(p, rng):
    """Tiny objects (1-8 cm cubes, 5 mm coins, 1 cm pencils) on a table and on the floor."""
    lighting = p["lighting"]
    W, H, D = _room(rng)
    lv = Level(lighting)
    lv.shell(W, H, D, [_window(W, H, False)])
    cx, cz, top = W / 2, D / 2, 0.74
    lv.add_boxes("table", "oak", [((cx - 0.6, top - 0.04, cz - 0.4), (cx + 0.6, top, cz + 0.4))] +
                 [((x - 0.025, 0.0, z - 0.025), (x + 0.025, top - 0.04, z + 0.025))
                  for x in (cx - 0.54, cx + 0.54) for z in (cz - 0.34, cz + 0.34)])
    for k in range(6):
        e = (0.01, 0.02, 0.03, 0.05, 0.08, 0.04)[k]
        x, z = cx - 0.5 + 0.17 * k, cz - 0.2 + rng.randint(0, 40) / 100.0
        lv.add_boxes("cube_%d" % k, ("red", "blue", "paper")[k % 3], [((x, top, z), (x + e, top + e, z + e))],
                     skip=("bottom",))
    for k in range(3):
        x = cx - 0.3 + 0.2 * k
        lv.add("coin_%d" % k, "metal_dull", geom.prism(x, cz + 0.3, 0.012, top, top + 0.005, n=8, skip=("bottom",)),
               thin=0.005)
    lv.add_boxes("pencil", "blue", [((cx + 0.2, top, cz - 0.3), (cx + 0.35, top + 0.01, cz - 0.29))],
                 skip=("bottom",))
    for k in range(5):
        x, z = 0.5 + 0.6 * k, 0.5 + rng.randint(0, 250) / 100.0
        e = 0.02 + 0.01 * k
        lv.add_boxes("pebble_%d" % k, "stone", [((x, 0.0, z), (x + e, e, z + e))], skip=("bottom",))
    lv.light(W, H, D)
    return lv


MATERIALS = {
    "floor": (0.45, 0.30, 0.18), "ceiling": (0.85, 0.85, 0.85), "plaster": (0.78, 0.76, 0.72),
    "oak": (0.55, 0.40, 0.25), "fabric": (0.25, 0.35, 0.5), "red": (0.6, 0.1, 0.08), "blue": (0.1, 0.15, 0.5),
    "paper": (0.8, 0.78, 0.7), "white": (0.85, 0.85, 0.82), "crate": (0.6, 0.5, 0.3), "fabric_red": (0.5, 0.12, 0.1),
    "stone": (0.5, 0.5, 0.48), "metal_dull": (0.6, 0.6, 0.6),
    "exterior": (0.0, 0.0, 0.0),  # the hull: reflects nothing, so lbk and Cycles agree on it
}

S, L, U = "sky", "lamp", "sun"
# family -> (builder, variants); variant v's set is "validation" when v % 3 == 2, else "dev"
FAMILIES = [
    ("table_slab", table_slab, [
        dict(thick=0.01, shape="rect", lighting=S, density="coarse"),
        dict(thick=0.07, shape="round", lighting=S, density="coarse"),
        dict(thick=0.07, shape="round", lighting=S, density="fine"),
        dict(thick=0.02, shape="rect", lighting=L, density="fine"),
        dict(thick=0.03, shape="round", lighting=U, density="coarse"),
        dict(thick=0.01, shape="rect", lighting=U, density="fine"),
        dict(thick=0.05, shape="rect", lighting=S, density="fine"),
        dict(thick=0.10, shape="round", lighting=L, density="coarse"),
        dict(thick=0.015, shape="rect", lighting=S, density="coarse"),
        dict(thick=0.04, shape="rect", lighting=L, density="coarse")]),
    ("shelf_slab", shelf_slab, [
        dict(thick=0.02, shelves=4, lighting=S, density="coarse"),
        dict(thick=0.01, shelves=5, lighting=L, density="coarse"),
        dict(thick=0.03, shelves=4, lighting=U, density="fine"),
        dict(thick=0.05, shelves=3, lighting=S, density="fine"),
        dict(thick=0.015, shelves=6, lighting=L, density="fine"),
        dict(thick=0.04, shelves=4, lighting=S, density="coarse")]),
    ("thin_wall", thin_wall, [
        dict(thick=0.02, lighting=S, density="coarse"),
        dict(thick=0.05, lighting=L, density="coarse"),
        dict(thick=0.10, lighting=S, density="fine"),
        dict(thick=0.20, lighting=U, density="coarse"),
        dict(thick=0.03, lighting=L, density="fine"),
        dict(thick=0.08, lighting=S, density="coarse")]),
    ("overlap", overlap, [
        dict(lighting=S, density="coarse"), dict(lighting=U, density="coarse"), dict(lighting=L, density="fine"),
        dict(lighting=S, density="fine"), dict(lighting=U, density="fine"), dict(lighting=L, density="coarse")]),
    ("resting", resting, [
        dict(lighting=S, density="coarse", bottoms=True), dict(lighting=L, density="coarse", bottoms=True),
        dict(lighting=U, density="fine", bottoms=True), dict(lighting=S, density="fine", bottoms=False),
        dict(lighting=L, density="fine", bottoms=True)]),
    ("sill_niche", sill_niche, [
        dict(lighting=S, density="coarse", sill=0.03), dict(lighting=U, density="coarse", sill=0.02),
        dict(lighting=L, density="fine", sill=0.05), dict(lighting=S, density="fine", sill=0.04),
        dict(lighting=U, density="fine", sill=0.02), dict(lighting=L, density="coarse", sill=0.03)]),
    ("tiny", tiny, [
        dict(lighting=L, density="coarse"), dict(lighting=S, density="fine"), dict(lighting=U, density="coarse"),
        dict(lighting=L, density="fine"), dict(lighting=S, density="coarse")]),
]
DENSITY = {"coarse": 8.0, "fine": 24.0}  # texels per metre (--texel-density; 8 = the fast preset's)


def level_set(v):
    return "validation" if v % 3 == 2 else "dev"

