#!/usr/bin/env python3
"""Write a unit UV sphere as an OBJ file (v, vn, f v//n), for BRDF Explorer
checkouts that lack src/data/sphere.obj (its "Lit Object" view loads it).
apply.sh runs it for the build copy it patches, never for the checkout; by
hand, write into that copy the same way:

    python3 cpp-plugin/make-sphere-obj.py BUILD_DIR/src/data/sphere.obj
"""
import math
import sys

if len(sys.argv) != 2:
    sys.exit("usage: make-sphere-obj.py OUT.obj")
rings, segments = 48, 96
lines = []
for i in range(rings + 1):
    theta = math.pi * i / rings
    for j in range(segments + 1):
        phi = 2 * math.pi * j / segments
        x, y, z = math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi)
        lines.append(f"v {x:.6f} {y:.6f} {z:.6f}")
        lines.append(f"vn {x:.6f} {y:.6f} {z:.6f}")
row = segments + 1
for i in range(rings):
    for j in range(segments):
        a, b = i * row + j + 1, i * row + j + 2
        c, d = a + row, b + row
        lines.append(f"f {a}//{a} {c}//{c} {b}//{b}")
        lines.append(f"f {b}//{b} {c}//{c} {d}//{d}")
with open(sys.argv[1], "w") as f:
    f.write("\n".join(lines) + "\n")
