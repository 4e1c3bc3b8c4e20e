#!/usr/bin/env python3
"""Writes scenes/maze/maze.{obj,mtl}: a closed maze of 12 x 12 cells under a ceiling, with two
standing figures, of exactly 241,080 triangles (the MAZE of Chang, Park and Ihm's "Diffuse Global
Illumination in Particle Spaces", whose own is not public: 241,080 triangles, two lights, a scene
whose corridors only light reaches after many diffuse bounces). scenes/maze.json puts two point
lights in it. The maze is a depth-first spanning tree of the cells from a fixed seed; walls are
0.2 m thick boxes between posts, their visible faces cut into a grid so that the triangle count is
the paper's. Every face is wound counter-clockwise seen from the open side. Procedural, so the
scene needs no third-party data; the output is the same every time, so the repository keeps only
the MTL and scripts/build.sh writes the OBJ when it is missing."""
import math
import pathlib

from procedural_mesh import Mesh
import random

CELLS, CELL, THICK, HEIGHT = 12, 2.0, 0.2, 2.5
TARGET = 241080
out = pathlib.Path(__file__).resolve().parent.parent / "scenes" / "maze"
mesh = Mesh()
vertices, normals, faces = mesh.vertices, mesh.normals, mesh.faces
vertex, quad, sphere = mesh.vertex, mesh.quad, mesh.sphere


def grid_face(material, origin, u, v, nu, nv):
    """The parallelogram origin + s u + t v, cut into nu x nv quads, facing u x v."""
    ids = [[vertex(tuple(o + s / nu * a + t / nv * b for o, a, b in zip(origin, u, v))) for s in range(nu + 1)]
           for t in range(nv + 1)]
    for t in range(nv):
        for s in range(nu):
            a, b, c, d = ids[t][s], ids[t][s + 1], ids[t + 1][s + 1], ids[t + 1][s]
            faces.append((material, [a, b, c]))
            faces.append((material, [a, c, d]))


def box_faces(material, lo, hi, skip, cuts):
    """The faces of an axis-aligned box facing out, except those named in `skip` ('-x', '+y', ...);
    cuts(name, width, height) gives a face's grid."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    sides = {
        "-x": ((x0, y0, z1), (0, 0, z0 - z1), (0, y1 - y0, 0)),
        "+x": ((x1, y0, z0), (0, 0, z1 - z0), (0, y1 - y0, 0)),
        "-z": ((x0, y0, z0), (x1 - x0, 0, 0), (0, y1 - y0, 0)),
        "+z": ((x1, y0, z1), (x0 - x1, 0, 0), (0, y1 - y0, 0)),
        "-y": ((x0, y0, z0), (0, 0, z1 - z0), (x1 - x0, 0, 0)),
        "+y": ((x0, y1, z0), (x1 - x0, 0, 0), (0, 0, z1 - z0)),
    }
    for name, (o, u, v) in sides.items():
        if name in skip:
            continue
        nu, nv = cuts(name, math.dist((0, 0, 0), u), math.dist((0, 0, 0), v))
        grid_face(material, o, u, v, nu, nv)


def cylinder(material, base, radius, height, segments, rings, cap_top):
    """An open-bottomed cylinder standing on `base` (exact shading normals), with a flat top."""
    bx, by, bz = base
    rows = []
    for r in range(rings + 1):
        row = []
        for s in range(segments):
            phi = 2 * math.pi * s / segments
            n = (math.cos(phi), 0.0, math.sin(phi))
            row.append(vertex((bx + radius * n[0], by + height * r / rings, bz + radius * n[2]), n))
        rows.append(row)
    for r in range(rings):
        for s in range(segments):
            a, b = rows[r][s], rows[r][(s + 1) % segments]
            c, d = rows[r + 1][(s + 1) % segments], rows[r + 1][s]
            faces.append((material, [a, c, b]))
            faces.append((material, [a, d, c]))
    if cap_top:
        centre = vertex((bx, by + height, bz))
        top = [vertex((bx + radius * math.cos(2 * math.pi * s / segments), by + height,
                       bz + radius * math.sin(2 * math.pi * s / segments))) for s in range(segments)]
        for s in range(segments):
            faces.append((material, [centre, top[(s + 1) % segments], top[s]]))


def figure(material, x, z):
    """A standing figure: two legs, a body, a head; 1.75 m tall."""
    for dx in (-0.1, 0.1):
        cylinder(material, (x + dx, 0.0, z), 0.08, 0.8, 24, 8, False)
    cylinder(material, (x, 0.8, z), 0.22, 0.7, 32, 8, True)
    sphere(material, (x, 1.62, z), 0.13, 16, 24)


def maze_walls():
    """Which walls stand: a depth-first spanning tree of the cells opens the others."""
    rng = random.Random(2015)
    east = [[True] * CELLS for _ in range(CELLS)]   # wall east of cell (i, j), i along x
    south = [[True] * CELLS for _ in range(CELLS)]  # wall towards +z of cell (i, j)
    seen, stack = {(0, 0)}, [(0, 0)]
    while stack:
        i, j = stack[-1]
        options = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                   if 0 <= i + di < CELLS and 0 <= j + dj < CELLS and (i + di, j + dj) not in seen]
        if not options:
            stack.pop()
            continue
        ni, nj = rng.choice(options)
        if ni != i:
            east[min(i, ni)][j] = False
        else:
            south[i][min(j, nj)] = False
        seen.add((ni, nj))
        stack.append((ni, nj))
    return east, south


def build(floor_cuts):
    vertices.clear(), normals.clear(), faces.clear()
    east, south = maze_walls()
    size = CELLS * CELL
    h = THICK / 2
    # Walls along x (between z-neighbours, and the border) and along z, between posts.
    segments_x = [(i, j) for j in range(CELLS + 1) for i in range(CELLS)
                  if j in (0, CELLS) or south[i][j - 1]]
    segments_z = [(i, j) for i in range(CELLS + 1) for j in range(CELLS)
                  if i in (0, CELLS) or east[i - 1][j]]
    long_cuts = lambda name, w, hgt: (max(1, round(w / 0.125)), max(1, round(hgt / 0.125)))
    for i, j in segments_x:
        x0, z = i * CELL + h, j * CELL
        skip = {"-x", "+x", "-y", "+y"} | ({"-z"} if j == 0 else set()) | ({"+z"} if j == CELLS else set())
        box_faces("walls", (x0, 0, z - h), (x0 + CELL - THICK, HEIGHT, z + h), skip, long_cuts)
    for i, j in segments_z:
        x, z0 = i * CELL, j * CELL + h
        skip = {"-z", "+z", "-y", "+y"} | ({"-x"} if i == 0 else set()) | ({"+x"} if i == CELLS else set())
        box_faces("walls", (x - h, 0, z0), (x + h, HEIGHT, z0 + CELL - THICK), skip, long_cuts)
    # Posts: faces against a wall segment, against the floor and ceiling, or outside are hidden.
    xs, zs = set(segments_x), set(segments_z)
    for i in range(CELLS + 1):
        for j in range(CELLS + 1):
            skip = {"-y", "+y"}
            if (i - 1, j) in xs or i == 0: skip.add("-x")
            if (i, j) in xs or i == CELLS: skip.add("+x")
            if (i, j - 1) in zs or j == 0: skip.add("-z")
            if (i, j) in zs or j == CELLS: skip.add("+z")
            if len(skip) == 6:
                continue
            box_faces("walls", (i * CELL - h, 0, j * CELL - h), (i * CELL + h, HEIGHT, j * CELL + h), skip,
                      lambda name, w, hgt: (1, max(1, round(hgt / 0.125))))
    figure("red", 6.0, 1.45)
    figure("blue", 7.0, 9.0)
    # Floor (facing up) and ceiling (facing down) over the inside of the border walls.
    fu, fv = floor_cuts
    grid_face("floor", (h, 0, h), (0, 0, size - THICK), (size - THICK, 0, 0), fu, fv)
    grid_face("ceiling", (h, HEIGHT, h), (size - THICK, 0, 0), (0, 0, size - THICK), fu, fv)
    return len(faces)


def main():
    rest = build((1, 1)) - 4
    remaining = TARGET - rest
    if remaining <= 0 or remaining % 4:
        raise SystemExit(f"make-maze: {rest} triangles besides the floor and ceiling; adjust the cuts")
    quads = remaining // 4  # floor and ceiling: fu * fv quads each, two triangles a quad
    fu = max(d for d in range(1, int(math.isqrt(quads)) + 1) if quads % d == 0)
    count = build((fu, quads // fu))
    assert count == TARGET, count
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "maze.mtl", "w") as f:
        f.write("# Written by scripts/make-maze.py for Lucent.\n")
        for name, kd in (("walls", "0.75 0.73 0.7"), ("floor", "0.55 0.5 0.45"), ("ceiling", "0.8 0.8 0.8"),
                         ("red", "0.7 0.12 0.1"), ("blue", "0.1 0.2 0.65")):
            f.write(f"\nnewmtl {name}\nKd {kd}\n")
    with open(out / "maze.obj", "w") as f:
        f.write(f"# Written by scripts/make-maze.py for Lucent: {count} triangles.\nmtllib maze.mtl\n")
        f.writelines(f"v {x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in vertices)
        f.writelines(f"vn {x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in normals)
        current = None
        for material, face in faces:
            if material != current:
                f.write(f"usemtl {material}\n")
                current = material
            f.write("f " + " ".join(f"{v}//{n}" if n else f"{v}" for v, n in face) + "\n")
    print(f"{out / 'maze.obj'}: {count} triangles, {len(vertices)} vertices, floor and ceiling {fu} x {quads // fu}")


main()
