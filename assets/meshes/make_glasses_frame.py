#!/usr/bin/env python3
"""Writes glasses_frame.obj: the front of a pair of glasses (two rims and a
bridge, no lenses, no temples), 396 triangles, for scenes that put a frame
in front of the eyes (assets/scenes/remote_glasses.json).

Units: millimetres. Frame: origin at the middle of the bridge, +x to the
right as seen from the front, +y up, +z out of the front (toward whoever
looks at the wearer), the frame's depth centred on z = 0. Each rim is a
ring of rectangular cross-section around an elliptical lens opening.

Run from anywhere: python3 assets/meshes/make_glasses_frame.py
"""

import math
import pathlib

LENS_CENTER_X = 32.0          # half the distance between the lens centres
OPENING = (23.0, 17.5)        # semi-axes of the lens opening (x, y)
RIM_WIDTH = 4.0               # in the frame's plane
DEPTH = 3.0                   # front to back
SEGMENTS = 24                 # around each rim
BRIDGE = ((-9.0, 9.0), (8.0, 12.0))  # x and y extent; it reaches into both rims

vertices = []
faces = []


def vertex(x, y, z):
    vertices.append((x, y, z))
    return len(vertices)  # OBJ counts from 1


def newell(points):
    n = [0.0, 0.0, 0.0]
    for i, p in enumerate(points):
        q = points[(i + 1) % len(points)]
        n[0] += (p[1] - q[1]) * (p[2] + q[2])
        n[1] += (p[2] - q[2]) * (p[0] + q[0])
        n[2] += (p[0] - q[0]) * (p[1] + q[1])
    return n


def quad(indices, outward):
    """Adds a quad, wound counter-clockwise seen from `outward`'s side."""
    points = [vertices[i - 1] for i in indices]
    n = newell(points)
    if sum(a * b for a, b in zip(n, outward)) < 0:
        indices = list(reversed(indices))
    faces.append(indices)


def rim(cx):
    a, b = OPENING
    ring = []
    for k in range(SEGMENTS):
        phi = 2 * math.pi * k / SEGMENTS
        c, s = math.cos(phi), math.sin(phi)
        inner = (cx + a * c, b * s)
        outer = (cx + (a + RIM_WIDTH) * c, (b + RIM_WIDTH) * s)
        ring.append({
            "if": vertex(*inner, DEPTH / 2), "ib": vertex(*inner, -DEPTH / 2),
            "of": vertex(*outer, DEPTH / 2), "ob": vertex(*outer, -DEPTH / 2),
            "radial": (c / a, s / b, 0.0),  # the ellipse's outward normal, unnormalized
        })
    for k in range(SEGMENTS):
        p, q = ring[k], ring[(k + 1) % SEGMENTS]
        mid = [(u + v) / 2 for u, v in zip(p["radial"], q["radial"])]
        quad([p["if"], p["of"], q["of"], q["if"]], (0, 0, 1))                # front
        quad([p["ib"], p["ob"], q["ob"], q["ib"]], (0, 0, -1))               # back
        quad([p["of"], p["ob"], q["ob"], q["of"]], mid)                      # outer wall
        quad([p["if"], p["ib"], q["ib"], q["if"]], [-m for m in mid])        # opening's wall


def box(xs, ys, zs):
    corner = {(i, j, k): vertex(xs[i], ys[j], zs[k]) for i in (0, 1) for j in (0, 1) for k in (0, 1)}
    for axis in range(3):
        for side in (0, 1):
            face = [key for key in corner if key[axis] == side]
            # Around the face: order the four corners by angle in its plane.
            u, v = [d for d in range(3) if d != axis]
            face.sort(key=lambda key: math.atan2(key[v] - 0.5, key[u] - 0.5))
            outward = [0, 0, 0]
            outward[axis] = 1 if side else -1
            quad([corner[key] for key in face], outward)


rim(-LENS_CENTER_X)
rim(LENS_CENTER_X)
box(BRIDGE[0], BRIDGE[1], (-DEPTH / 2, DEPTH / 2))

out = pathlib.Path(__file__).with_name("glasses_frame.obj")
with out.open("w") as f:
    f.write("# A glasses frame: two rims and a bridge; written by make_glasses_frame.py.\n")
    f.write("# Millimetres; +x right, +y up, +z out of the front; origin at the bridge.\n")
    f.write(f"# {len(vertices)} vertices, {len(faces)} quads ({2 * len(faces)} triangles).\n")
    f.write("o glasses_frame\n")
    for x, y, z in vertices:
        f.write(f"v {x:.4f} {y:.4f} {z:.4f}\n")
    for face in faces:
        f.write("f " + " ".join(str(i) for i in face) + "\n")
print(f"wrote {out}: {len(vertices)} vertices, {len(faces)} quads")
