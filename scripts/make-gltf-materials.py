#!/usr/bin/env python3
"""Writes two procedural glTF scenes, spheres in a row on a ground and before a wall, lit by a spot
light and the sun (KHR_lights_punctual); materials-sky.json and extensions-sky.json add a sky.

scenes/gltf/materials.glb: glTF's metallic-roughness material on five spheres: a rough gold and a
polished copper metal, a rough white and a shiny blue dielectric (KHR_materials_ior 1.5), and a
half-metallic sphere with a tinted specular colour (KHR_materials_specular). Metal colours are the
measured F0 of gold and copper that the glTF specification's examples use.

scenes/gltf/extensions.glb: the material extensions GPU path tracers render, one sphere each: a
velvet (KHR_materials_sheen over a dark base), a car paint (KHR_materials_clearcoat over a
half-metallic red), a frosted and a tinted thin-walled shell (KHR_materials_transmission, rough and
smooth), and an amber glass ball (KHR_materials_volume: refracting at index 1.5, KHR_materials_ior,
and absorbing inside).

The ground and wall are rough grey dielectrics. Procedural, so the scenes need no third-party data;
rerun to regenerate."""
import json
import math
import pathlib
import struct

from procedural_mesh import Mesh

out = pathlib.Path(__file__).resolve().parent.parent / "scenes" / "gltf"

# (name, base colour, metallic, roughness, extensions): the ground and the wall, then one per sphere.
ROOM = [
    ("ground", (0.5, 0.5, 0.5), 0.0, 0.8, {}),
    ("wall", (0.6, 0.6, 0.6), 0.0, 0.9, {}),
]
METALLIC_ROUGHNESS = ROOM + [
    ("gold", (1.0, 0.766, 0.336), 1.0, 0.35, {}),
    ("copper", (0.955, 0.638, 0.538), 1.0, 0.25, {}),
    ("rough white", (0.8, 0.8, 0.8), 0.0, 0.6, {"KHR_materials_ior": {"ior": 1.5}}),
    ("shiny blue", (0.1, 0.2, 0.6), 0.0, 0.2, {"KHR_materials_ior": {"ior": 1.5}}),
    ("tinted", (0.7, 0.3, 0.2), 0.5, 0.4,
     {"KHR_materials_specular": {"specularFactor": 0.8, "specularColorFactor": [1.0, 0.8, 0.6]}}),
]
EXTENSIONS = ROOM + [
    ("velvet", (0.05, 0.04, 0.2), 0.0, 0.8,
     {"KHR_materials_sheen": {"sheenColorFactor": [0.8, 0.5, 0.9], "sheenRoughnessFactor": 0.4}}),
    ("car paint", (0.6, 0.05, 0.05), 0.4, 0.5,
     {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatRoughnessFactor": 0.1}}),
    ("frosted shell", (0.95, 0.95, 0.95), 0.0, 0.3, {"KHR_materials_transmission": {"transmissionFactor": 1.0}}),
    ("tinted shell", (0.9, 0.6, 0.3), 0.0, 0.05, {"KHR_materials_transmission": {"transmissionFactor": 0.9}}),
    ("amber glass", (1.0, 1.0, 1.0), 0.0, 0.05,
     {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5},
      "KHR_materials_volume": {"thicknessFactor": 1.6, "attenuationDistance": 0.8,
                               "attenuationColor": [0.9, 0.5, 0.15]}}),
]


def scene_glb(materials_table, spheres, extensions_used):
    """The glb bytes and triangle count of the room with one sphere per entry of `spheres` (its
    material's name, centre and radius)."""
    index = {name: i for i, (name, *_) in enumerate(materials_table)}
    mesh = Mesh()
    vertex, quad = mesh.vertex, mesh.quad
    up, forward = (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    # Ground y = 0 over [-6, 6] x [-4, 4]; wall z = -4, up to y = 5; normals given, as an exporter
    # writes.
    quad(index["ground"], *(vertex(p, up) for p in [(-6, 0, -4), (-6, 0, 4), (6, 0, 4), (6, 0, -4)]))
    quad(index["wall"], *(vertex(p, forward) for p in [(-6, 0, -4), (6, 0, -4), (6, 5, -4), (-6, 5, -4)]))
    for name, centre, radius in spheres:
        mesh.sphere(index[name], centre, radius, 24, 48)
    return glb_bytes(mesh, materials_table, extensions_used), sum(1 for _ in mesh.faces)


def glb_bytes(mesh, materials_table, extensions_used):
    """The scene as one glb: one primitive per material, its vertices its own (positions and normals
    float32, indices uint32), the camera, the spot and the sun."""
    binary = bytearray()
    views, accessors, primitives = [], [], []

    def add_view(data, target):
        while len(binary) % 4:
            binary.append(0)
        views.append({"buffer": 0, "byteOffset": len(binary), "byteLength": len(data), "target": target})
        binary.extend(data)
        return len(views) - 1

    for m in range(len(materials_table)):
        corners = [c for material, face in mesh.faces if material == m for c in face]
        remap, positions, normals, indices = {}, [], [], []
        for v, n in corners:
            if (v, n) not in remap:
                remap[v, n] = len(positions)
                positions.append(mesh.vertices[v - 1])
                normals.append(mesh.normals[n - 1])
            indices.append(remap[v, n])
        lo = [min(p[i] for p in positions) for i in range(3)]
        hi = [max(p[i] for p in positions) for i in range(3)]
        position_view = add_view(b"".join(struct.pack("<3f", *p) for p in positions), 34962)
        normal_view = add_view(b"".join(struct.pack("<3f", *n) for n in normals), 34962)
        index_view = add_view(struct.pack(f"<{len(indices)}I", *indices), 34963)
        accessors += [{"bufferView": position_view, "componentType": 5126, "count": len(positions), "type": "VEC3",
                       "min": lo, "max": hi},
                      {"bufferView": normal_view, "componentType": 5126, "count": len(normals), "type": "VEC3"},
                      {"bufferView": index_view, "componentType": 5125, "count": len(indices), "type": "SCALAR"}]
        primitives.append({"attributes": {"POSITION": len(accessors) - 3, "NORMAL": len(accessors) - 2},
                           "indices": len(accessors) - 1, "material": m})

    # The camera at (0, 2.5, 9) looking at (0, 1, 0): a rotation about x by -atan(1.5 / 9).
    pitch = -math.atan2(1.5, 9.0)
    camera_rotation = [math.sin(pitch / 2), 0.0, 0.0, math.cos(pitch / 2)]
    # The spot at (1, 6, 3) aimed at (0, 0.8, 0); the sun from above and to the left.
    spot_from, spot_to = (1.0, 6.0, 3.0), (0.0, 0.8, 0.0)
    spot_rotation = turning_minus_z_onto(unit([b - a for a, b in zip(spot_from, spot_to)]))
    sun_rotation = turning_minus_z_onto(unit((0.4, -1.0, -0.3)))

    materials = []
    for name, base, metallic, roughness, extensions in materials_table:
        material = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": list(base) + [1.0],
                                                           "metallicFactor": metallic, "roughnessFactor": roughness}}
        if extensions:
            material["extensions"] = extensions
        materials.append(material)

    document = {
        "asset": {"version": "2.0", "generator": "Lucent scripts/make-gltf-materials.py"},
        "extensionsUsed": extensions_used,
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "spot", "type": "spot", "color": [1.0, 0.95, 0.85], "intensity": 683 * 60.0,
             "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.45}},
            {"name": "sun", "type": "directional", "color": [1.0, 0.97, 0.9], "intensity": 683 * 1.5}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [{"name": "objects", "mesh": 0},
                  {"name": "camera", "camera": 0, "translation": [0.0, 2.5, 9.0], "rotation": camera_rotation},
                  {"name": "spot", "translation": list(spot_from), "rotation": spot_rotation,
                   "extensions": {"KHR_lights_punctual": {"light": 0}}},
                  {"name": "sun", "rotation": sun_rotation, "extensions": {"KHR_lights_punctual": {"light": 1}}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "aspectRatio": 2.0, "znear": 0.1}}],
        "meshes": [{"name": "objects", "primitives": primitives}],
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(binary)}],
    }

    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    while len(binary) % 4:
        binary.append(0)
    glb = struct.pack("<3I", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary))
    glb += struct.pack("<2I", len(text), 0x4E4F534A) + text
    glb += struct.pack("<2I", len(binary), 0x004E4942) + bytes(binary)
    return glb


def turning_minus_z_onto(d):
    """The unit quaternion (x, y, z, w) turning (0, 0, -1), where glTF's lights shine, onto the unit
    direction d: about the axis (0, 0, -1) x d by the angle acos(-d.z)."""
    axis = (d[1], -d[0], 0.0)
    axis_length = math.sqrt(sum(x * x for x in axis))
    angle = math.acos(-d[2])
    return [x / axis_length * math.sin(angle / 2) for x in axis] + [math.cos(angle / 2)]


def unit(v):
    length = math.sqrt(sum(x * x for x in v))
    return [x / length for x in v]


for file, table, spheres, used in [
        ("materials.glb", METALLIC_ROUGHNESS,
         [(name, (-4.0 + 2.0 * k, 0.8, 0.0), 0.8)
          for k, name in enumerate(["gold", "copper", "rough white", "shiny blue", "tinted"])],
         ["KHR_lights_punctual", "KHR_materials_ior", "KHR_materials_specular"]),
        ("extensions.glb", EXTENSIONS,
         [(name, (-4.0 + 2.0 * k, 0.8, 0.0), 0.8)
          for k, name in enumerate(["velvet", "car paint", "frosted shell", "tinted shell", "amber glass"])],
         ["KHR_lights_punctual", "KHR_materials_sheen", "KHR_materials_clearcoat", "KHR_materials_transmission",
          "KHR_materials_ior", "KHR_materials_volume"])]:
    glb, triangles = scene_glb(table, spheres, used)
    (out / file).write_bytes(glb)
    print(f"{out / file}: {triangles} triangles, {len(glb)} bytes")
