#!/usr/bin/env python3
"""Writes bowl.obj: a hemispherical bowl (a closed shell of revolution about z).

Inner radius 0.08 m, wall 0.015 m, rim at the sphere's equator, centred at the
origin (the bowl opens upwards; its outer bottom is at z = -0.095 m). The
triangles are wound counter-clockwise seen from outside (normals point out of
the solid), as a `mesh` shape needs (docs/scenes.md).

    python3 make_bowl.py > bowl.obj
"""
import math

INNER, WALL = 0.08, 0.015
OUTER = INNER + WALL
ARC, AROUND = 24, 48  # profile segments from the pole to the rim; segments around z

# Closed profile in the (r, z) half-plane, counter-clockwise: the outer arc
# from the bottom pole up to the rim, across the rim, the inner arc back down.
profile = []
for i in range(ARC + 1):
    t = 0.5 * math.pi * i / ARC
    profile.append((OUTER * math.sin(t), -OUTER * math.cos(t)))
for i in range(ARC, -1, -1):
    t = 0.5 * math.pi * i / ARC
    profile.append((INNER * math.sin(t), -INNER * math.cos(t)))

vertices, faces = [], []
ring = {}  # profile index -> first vertex index of its ring (or the pole vertex)
for p, (r, z) in enumerate(profile):
    ring[p] = len(vertices) + 1
    if r < 1e-12:
        vertices.append((0.0, 0.0, z))
    else:
        for k in range(AROUND):
            a = 2 * math.pi * k / AROUND
            vertices.append((r * math.cos(a), r * math.sin(a), z))


def vid(p, k):
    r = profile[p][0]
    return ring[p] if r < 1e-12 else ring[p] + k % AROUND


for p in range(len(profile) - 1):
    for k in range(AROUND):
        a, b = vid(p, k), vid(p, k + 1)
        c, d = vid(p + 1, k + 1), vid(p + 1, k)
        # The profile runs counter-clockwise in (r, z); with the angle
        # increasing this winding puts the normal outside the solid.
        quad = [a, b, c, d]
        tri = [v for i, v in enumerate(quad) if v not in quad[:i]]
        if len(tri) == 3:
            faces.append(tri)
        elif len(tri) == 4:
            faces.append(tri[:3])
            faces.append([tri[0], tri[2], tri[3]])
# The two poles lie on the axis: the profile's closing edge (inner pole to
# outer pole) is the axis itself, so the surface is closed.

print("# Hemispherical bowl: inner radius %g m, wall %g m (examples/scenes/meshes/make_bowl.py)" % (INNER, WALL))
for v in vertices:
    print("v %.6f %.6f %.6f" % v)
for f in faces:
    print("f %d %d %d" % tuple(f))
