"""Triangle meshes built in code, for the procedural scenes (make-primitives.py, make-maze.py):
vertices with or without an exact shading normal, and faces by material, each a list of
(vertex number, normal number or None), numbered from 1 as in OBJ."""
import math


class Mesh:
    def __init__(self):
        self.vertices, self.normals, self.faces = [], [], []

    def vertex(self, p, n=None):
        self.vertices.append(p)
        if n is None:
            return (len(self.vertices), None)
        self.normals.append(n)
        return (len(self.vertices), len(self.normals))

    def quad(self, material, a, b, c, d):
        """Two triangles, counter-clockwise as a, b, c, d are."""
        self.faces.append((material, [a, b, c]))
        self.faces.append((material, [a, c, d]))

    def sphere(self, material, centre, radius, rings, segments):
        """A UV sphere with exact normals, wound counter-clockwise seen from outside."""
        grid = []
        for i in range(rings + 1):
            theta = math.pi * i / rings
            row = []
            for j in range(segments):
                phi = 2 * math.pi * j / segments
                n = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
                row.append(self.vertex(tuple(c + radius * d for c, d in zip(centre, n)), n))
            grid.append(row)
        for i in range(rings):
            for j in range(segments):
                a, b = grid[i][j], grid[i][(j + 1) % segments]
                c, d = grid[i + 1][(j + 1) % segments], grid[i + 1][j]
                if i > 0:
                    self.faces.append((material, [a, b, c]))
                if i < rings - 1:
                    self.faces.append((material, [a, c, d]))
