#!/usr/bin/env python3
"""Writes dragon.obj: a stylised dragon (one closed shell, a tube swept along a spine).

The body is a tube swept along a gently S-curved spine in the x-z plane: a
thin tail at -x (closed by a pole vertex), a thick body (radius 12 mm, a
little wider than tall), a neck rising towards +x, and a head (radius about
10 mm) whose snout tapers to a closed end (a pole vertex) at +x. The rings are
oriented by a fixed frame (the spine stays in the x-z plane, so the side axis
is always -y) and do not twist. A row of seven dorsal spines, two horns on the
head and two folded wings on the flanks are made by pushing ring vertices
outwards, so the whole dragon stays a single closed 2-manifold; the spines,
horns and wings are at least about 3 mm thick at half their height, and only
the tail tip is thinner than that.

Size about 0.12 m long (x), 0.05 m high (z), 0.04 m wide (y): the bounding box
is about [-0.060, 0.060] x [-0.021, 0.021] x [0, 0.049] m. The dragon rests with
its lowest point at z = 0 and is centred at x = y = 0; the head looks along +x.
The triangles are wound counter-clockwise seen from outside (normals point out
of the solid), as a `mesh` shape needs (docs/scenes.md). Before writing, the
script checks that every edge is shared by exactly two triangles in opposite
directions and that the enclosed volume is positive.

    python3 make_dragon.py > dragon.obj
    python3 make_dragon.py --mirror > dragon_mirrored.obj

`--mirror` writes the dragon mirrored in x (the head looks along -x), wound
the same way (outward normals), for a scene that needs a second dragon
facing the first: a `mesh` shape's `axis` turns the file's z axis, not about
it.
"""
import math
import sys

RINGS, AROUND = 88, 20  # rings along the spine (tail to snout); vertices per ring
LENGTH = 0.130  # arc length of the spine from the first to the last ring (m)


def smooth(knots, u):
    """Piecewise smoothstep through (u, value) knots (flat at every knot)."""
    if u <= knots[0][0]:
        return knots[0][1]
    for (u0, v0), (u1, v1) in zip(knots, knots[1:]):
        if u <= u1:
            t = (u - u0) / (u1 - u0)
            return v0 + (v1 - v0) * t * t * (3 - 2 * t)
    return knots[-1][1]


# Along the spine, u runs from 0 (tail tip) to 1 (snout tip).
HEADING = [(0.0, -12.0), (0.30, 0.0), (0.49, 0.0), (0.67, 75.0), (0.86, 6.0), (1.0, -8.0)]  # degrees up from +x
RADIUS = [(0.0, 0.0020), (0.42, 0.0120), (0.70, 0.0066), (0.83, 0.0098), (1.0, 0.0030)]  # vertical half-size (m)
WIDTH = [(0.0, 1.0), (0.42, 1.25), (0.70, 1.05), (0.83, 1.18), (1.0, 1.0)]  # side half-size / vertical half-size

# Dorsal spines: SPIKES spikes of SPIKE_RINGS rings each, starting at ring SPIKE_START;
# the profile along one spike leans back towards the tail.
SPIKES, SPIKE_RINGS, SPIKE_START = 7, 5, 12
SPIKE_PROFILE = [0.0, 0.55, 1.0, 0.65, 0.3]
SPIKE_HEIGHT = 0.0075
# Horns: from ring HORN_START, on the back of the head either side of the top.
HORN_START, HORN_PROFILE, HORN_HEIGHT, HORN_ANGLE = 68, [0.0, 0.5, 1.0, 0.55, 0.2], 0.007, math.radians(50)
# Folded wings: ridges along the upper flanks of the body, highest at the
# shoulder and tapering towards the tail.
WING_START, WING_END, WING_HEIGHT, WING_ANGLE = 0.28, 0.54, 0.009, math.radians(68)


def bump(theta, centre, width):
    """Angular falloff around a ring: 1 at centre, 0 beyond width (radians)."""
    d = abs((theta - centre + math.pi) % (2 * math.pi) - math.pi)
    return max(0.0, 1.0 - d / width)


# Spine: integrate the heading along the arc length.
STEPS = 20 * (RINGS - 1)
spine, x, z = [], 0.0, 0.0
for j in range(STEPS + 1):
    u = j / STEPS
    phi = math.radians(smooth(HEADING, u))
    if j % 20 == 0:
        spine.append((u, x, z, phi))
    ds = LENGTH / STEPS
    phi_mid = math.radians(smooth(HEADING, (j + 0.5) / STEPS))
    x += ds * math.cos(phi_mid)
    z += ds * math.sin(phi_mid)

vertices, faces = [], []
ring_start = []
for i, (u, px, pz, phi) in enumerate(spine):
    # Frame: T along the spine, N up (in the x-z plane), B = T x N = -y.
    tx, tz = math.cos(phi), math.sin(phi)
    nx, nz = -tz, tx
    rz = smooth(RADIUS, u)
    ry = rz * smooth(WIDTH, u)
    spike = 0.0
    k = i - SPIKE_START
    if 0 <= k < SPIKES * SPIKE_RINGS:
        s = (k // SPIKE_RINGS + 0.5) / SPIKES
        spike = SPIKE_HEIGHT * (0.6 + 0.4 * math.sin(math.pi * s)) * SPIKE_PROFILE[k % SPIKE_RINGS]
    horn = 0.0
    if 0 <= i - HORN_START < len(HORN_PROFILE):
        horn = HORN_HEIGHT * HORN_PROFILE[i - HORN_START]
    wing = 0.0
    if WING_START <= u <= WING_END:
        w = (u - WING_START) / (WING_END - WING_START)
        wing = WING_HEIGHT * (w / 0.75 if w < 0.75 else (1 - w) / 0.25) ** 0.8
    spread = min(1.2, max(0.6, 0.004 / rz))  # angular half-width of a ridge
    ring_start.append(len(vertices))
    for a in range(AROUND):
        theta = 2 * math.pi * a / AROUND  # from the top (N) towards B
        c, s = math.cos(theta), math.sin(theta)
        # Outward normal of the ellipse (N rz cos, B ry sin) at theta.
        en, eb = c / rz, s / ry
        norm = math.hypot(en, eb)
        en, eb = en / norm, eb / norm
        push = (spike * bump(theta, 0.0, spread)
                + horn * (bump(theta, HORN_ANGLE, 0.5) + bump(theta, -HORN_ANGLE, 0.5))
                + wing * (bump(theta, WING_ANGLE, 0.55) + bump(theta, -WING_ANGLE, 0.55)))
        dn = rz * c + push * en
        db = ry * s + push * eb
        vertices.append((px + dn * nx, -db, pz + dn * nz))

# Poles closing the tail tip and the snout, one end radius beyond the end rings.
u, px, pz, phi = spine[0]
r = smooth(RADIUS, 0.0)
tail_pole = len(vertices)
vertices.append((px - r * math.cos(phi), 0.0, pz - r * math.sin(phi)))
u, px, pz, phi = spine[-1]
r = smooth(RADIUS, 1.0)
snout_pole = len(vertices)
vertices.append((px + r * math.cos(phi), 0.0, pz + r * math.sin(phi)))


def vid(i, a):
    return ring_start[i] + a % AROUND


# The ring angle turns counter-clockwise about T (N towards B, N x B = T), so
# (ring i, a) -> (ring i, a+1) -> (ring i+1, a+1) has its normal outwards.
for i in range(RINGS - 1):
    for a in range(AROUND):
        p, q, r_, s_ = vid(i, a), vid(i, a + 1), vid(i + 1, a + 1), vid(i + 1, a)
        faces.append((p, q, r_))
        faces.append((p, r_, s_))
for a in range(AROUND):
    faces.append((tail_pole, vid(0, a + 1), vid(0, a)))
    faces.append((snout_pole, vid(RINGS - 1, a), vid(RINGS - 1, a + 1)))

# Rest on z = 0, centred at x = y = 0.
lo = [min(v[d] for v in vertices) for d in range(3)]
hi = [max(v[d] for v in vertices) for d in range(3)]
shift = (-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2])
vertices = [(v[0] + shift[0], v[1] + shift[1], v[2] + shift[2]) for v in vertices]
if "--mirror" in sys.argv[1:]:
    vertices = [(-v[0], v[1], v[2]) for v in vertices]
    faces = [(f[0], f[2], f[1]) for f in faces]  # a mirror turns the winding; turn it back

# Checks: a closed, consistently oriented 2-manifold enclosing a positive volume.
directed = {}
for f in faces:
    for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0])):
        assert e not in directed, "edge %s used twice in the same direction" % (e,)
        directed[e] = True
assert all((b, a) in directed for (a, b) in directed), "open edge"
volume = 0.0
for f in faces:
    (ax, ay, az), (bx, by, bz), (cx, cy, cz) = (vertices[j] for j in f)
    volume += (ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)) / 6
assert volume > 0, "inward winding"

lo = [min(v[d] for v in vertices) for d in range(3)]
hi = [max(v[d] for v in vertices) for d in range(3)]
print("# Stylised dragon: %d triangles, volume %.4g m^3, bounding box [%.4f, %.4f] x [%.4f, %.4f] x [%.4f, %.4f] m"
      " (examples/scenes/meshes/make_dragon.py)" % (len(faces), volume, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]))
for v in vertices:
    print("v %.6f %.6f %.6f" % v)
for f in faces:
    print("f %d %d %d" % (f[0] + 1, f[1] + 1, f[2] + 1))
