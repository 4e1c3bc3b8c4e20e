#!/usr/bin/env python3
"""Writes a fuzz target's seed corpus (scripts/fuzz.sh).

scene_loader: one input per scene of tests/data (good and bad), its files joined by NUL bytes in the
fuzzer's order (fuzz/scene_loader_fuzzer.cpp: scene.json, mesh.obj, mesh.mtl, then one image read as
texture.png and as sky.hdr) and renamed to the fuzzer's names, plus scenes with a texture and with an
environment map written here. film_reader and merge: film files of whole renders, parts, checkpoints
and layered films, in fuzz/film_fuzz_input.h's two forms; merge's joined as parts. image_header:
pairs of small EXR, PNG, Radiance and PFM (colour and grey) images (and a TGA, which Lucent refuses), of equal and of
different sizes. gltf_loader: the exported Cornell box (scenes/gltf/cornell-box.glb) and small
.gltf files with embedded buffers: a quad as a triangle strip with interleaved attributes and a
point light, the same with a sparse accessor, with node transforms, with a base colour texture, and
with every material feature (textures on both sets, texture transforms, normal, emissive and specular
textures, a doubleSided emitter, alpha masking) and a spot light; and files that claim more than they
hold (counts of 2^28 and 3e9, accessors without a bufferView, a node DAG, repeated roots). dump:
reference and candidate dump files of each rule check-dump applies. command_line: the arguments of
every command and method.

Usage: scripts/fuzz-corpus.py TARGET OUT_DIR
"""
import json
import pathlib
import re
import struct
import sys
import zlib

ROOT = pathlib.Path(__file__).resolve().parent.parent
NAMES = {"obj": "mesh.obj", "mtl": "mesh.mtl", "texture": "texture.png", "sky": "sky.hdr"}  # the fuzzer's


def read(path):
    try:
        return path.read_bytes() if path and path.is_file() else None
    except OSError:
        return None


def png(width, height, rgb):
    """An 8-bit RGB PNG of one colour."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    rows = b"".join(b"\0" + bytes(rgb) * width for _ in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


def radiance_hdr(width, height, rgbe):
    """A Radiance .hdr of one colour, flat (not run-length encoded) scanlines."""
    header = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width)
    return header + bytes(rgbe) * (width * height)


def pack(parts):
    """Joins the files in the fuzzer's order; a trailing run of missing files is left out."""
    while parts and parts[-1] is None:
        parts.pop()
    return b"\0".join(p if p is not None else b"" for p in parts)


def seed_from(scene_path):
    scene_text = scene_path.read_text()
    obj = mtl = None
    try:
        scene = json.loads(scene_text)
    except ValueError:
        return pack([scene_text.encode()])
    if not isinstance(scene, dict):
        return pack([scene_text.encode()])
    base = scene_path.parent
    for mesh in scene.get("meshes", []) if isinstance(scene.get("meshes"), list) else []:
        if isinstance(mesh, dict) and isinstance(mesh.get("obj"), str):
            obj_path = base / mesh["obj"]
            obj = obj if obj is not None else read(obj_path)
            mesh["obj"] = NAMES["obj"]
            if obj is not None and mtl is None:
                match = re.search(rb"^mtllib\s+(\S+)", obj, re.M)
                if match:
                    mtl = read(obj_path.parent / match.group(1).decode())
    if obj is not None:
        obj = re.sub(rb"^mtllib\s+\S+", b"mtllib " + NAMES["mtl"].encode(), obj, flags=re.M)
    if mtl is not None:
        mtl = re.sub(rb"^map_Kd\s+\S+", b"map_Kd " + NAMES["texture"].encode(), mtl, flags=re.M)
    for material in (scene.get("materials") or {}).values() if isinstance(scene.get("materials"), dict) else []:
        if isinstance(material, dict) and "map_Kd" in material:
            material["map_Kd"] = NAMES["texture"]
    for light in scene.get("lights", []) if isinstance(scene.get("lights"), list) else []:
        if isinstance(light, dict) and "map" in light:
            light["map"] = NAMES["sky"]
    return pack([json.dumps(scene, indent=1).encode(), obj, mtl])


def film_header(width=4, height=4, crop=None, first=0, count=2, spp=2, complete=True, sums="per_part",
                features=False, caustic=False, variance=False):
    """A film file's header (docs/film-format.md) with its sums_per_pixel."""
    per_pixel = (3 if sums == "per_sample" or not features else 0) + (3 if variance else 0) + \
        (3 + 3 + (3 if sums == "per_part" else 0) + 7 if features else 0)
    header = {"method": "pt", "options": {"spp": spp, "seed": 0}, "derived": {}, "scene": "scene.json",
              "scene_hash": "0123456789abcdef", "version": "0.1.0", "embree_isa": "avx2", "lane_isa": "avx2",
              "width": width, "height": height, "crop": crop or [0, 0, width, height], "spp": spp,
              "first_sample": first, "sample_count": count, "complete": complete, "sums": sums,
              "layers": {"features": features, "caustic": caustic, "variance": variance},
              "sums_per_pixel": per_pixel, "counters": {"rays": 100}}
    if features:
        header["materials"] = ["white", "light"]
    return header


def film_input(header, taken=None):
    """fuzz/film_fuzz_input.h's structured form: an odd byte, the header, NUL, the arrays."""
    crop = header["crop"]
    pixels = (crop[2] - crop[0]) * (crop[3] - crop[1])
    count = header["sample_count"] if taken is None else taken
    sums = b"".join(struct.pack("<QQq", 1 << 90 >> 64 if k % 3 == 0 else 0, 0, 0) for k in range(pixels * header["sums_per_pixel"]))
    counts = struct.pack("<%dI" % pixels, *([count] * pixels))
    # With features, what each pixel shows: the first material, the second (an emitter), the background.
    codes = [2, 3 | 1 << 31, 1]
    surfaces = struct.pack("<%dI" % pixels, *(codes[k % 3] for k in range(pixels))) if header["layers"]["features"] else b""
    return b"\x01" + json.dumps(header).encode() + b"\0" + sums + counts + counts + surfaces


def film_seeds():
    seeds = {
        "whole": film_input(film_header()),
        "checkpoint": film_input(film_header(complete=False), taken=1),
        "layers": film_input(film_header(features=True)),
        "variance": film_input(film_header(sums="per_sample", variance=True)),
        "crop": film_input(film_header(crop=[1, 1, 3, 4])),
        "samples": film_input(film_header(first=1, count=1)),
        "lying-first-sample": film_input(film_header(first=2147483647, count=1)),
    }
    seeds["raw"] = b"\0" + seeds["whole"][1:]  # the even form: the bytes as they are (a wrong hash)
    return seeds


def merge_seeds():
    join = b"\n--part--\n".join
    return {
        "rows": join([film_input(film_header(crop=[0, 0, 4, 2])), film_input(film_header(crop=[0, 2, 4, 4]))]),
        "samples": join([film_input(film_header(first=0, count=1)), film_input(film_header(first=1, count=1))]),
        "overlap": join([film_input(film_header(crop=[0, 0, 4, 3])), film_input(film_header(crop=[0, 2, 4, 4]))]),
        "four": join([film_input(film_header(crop=[x, y, x + 2, y + 2])) for x in (0, 2) for y in (0, 2)]),
        "layers": join([film_input(film_header(crop=[0, 0, 4, 2], features=True)),
                        film_input(film_header(crop=[0, 2, 4, 4], features=True))]),
    }


def exr(width, height, channels):
    """An uncompressed scanline EXR of half-float zeros."""
    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data
    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iBBBBii", 1, 0, 0, 0, 0, 1, 1) for c in sorted(channels)) + b"\0"
    header = b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
    header += attr("channels", "chlist", chlist) + attr("compression", "compression", b"\0")
    header += attr("dataWindow", "box2i", struct.pack("<iiii", 0, 0, width - 1, height - 1))
    header += attr("displayWindow", "box2i", struct.pack("<iiii", 0, 0, width - 1, height - 1))
    header += attr("lineOrder", "lineOrder", b"\0") + attr("pixelAspectRatio", "float", struct.pack("<f", 1))
    header += attr("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0)) + attr("screenWindowWidth", "float", struct.pack("<f", 1))
    header += b"\0"
    line = 2 * width * len(channels)
    start = len(header) + 8 * height
    table = b"".join(struct.pack("<Q", start + k * (8 + line)) for k in range(height))
    rows = b"".join(struct.pack("<ii", k, line) + b"\0" * line for k in range(height))
    return header + table + rows


def image_seeds():
    images = {
        "exr": (0, exr(4, 4, ["R", "G", "B"])),
        "png": (1, png(4, 4, (200, 120, 40))),
        "hdr": (2, radiance_hdr(4, 4, (128, 128, 160, 129))),
        "pfm": (6, b"PF\n4 4\n-1.0\n" + struct.pack("<48f", *([0.5] * 48))),
        "pfm-grey": (6, b"Pf\n4 4\n1.0\n" + struct.pack(">16f", *([2.0] * 16))),
        "tga": (7, b"\0\0\2" + bytes(9) + struct.pack("<HHBB", 4, 4, 24, 0) + bytes(48)),
    }
    seeds = {}
    for a, (ka, da) in images.items():
        for b, (kb, db) in images.items():
            seeds[f"{a}-{b}"] = bytes([ka + 8 * kb]) + struct.pack("<H", len(da)) + da + db
    seeds["exr-sizes"] = bytes([0]) + struct.pack("<H", len(images["exr"][1])) + images["exr"][1] + exr(8, 2, ["R", "G", "B"])
    seeds["exr-variance"] = bytes([0]) + struct.pack("<H", len(images["exr"][1])) + images["exr"][1] + \
        exr(4, 4, ["R", "G", "B", "variance.R", "variance.G", "variance.B"])
    return seeds


def scene_loader_seeds():
    seeds = {}
    for scene_path in sorted((ROOT / "tests" / "data").glob("*/*/scene.json")):
        seeds[f"{scene_path.parent.parent.name}-{scene_path.parent.name}"] = seed_from(scene_path)

    # The base scene with a textured floor and an environment light: images reach the loader.
    base = ROOT / "tests" / "data" / "good" / "base"
    scene = json.loads((base / "scene.json").read_text())
    obj = (base / "base.obj").read_bytes()
    obj = re.sub(rb"^mtllib\s+\S+", b"mtllib mesh.mtl", obj, flags=re.M)
    mtl = (base / "base.mtl").read_bytes()
    textured_mtl = re.sub(rb"^(newmtl floor\s*\n)", rb"\1map_Kd texture.png\n", mtl, count=1, flags=re.M)
    for m in scene.get("meshes", []):
        m["obj"] = "mesh.obj"
    scene_text = json.dumps(scene, indent=1).encode()
    seeds["textured"] = pack([scene_text, obj, textured_mtl, png(4, 4, (200, 120, 40))])
    scene["lights"] = scene.get("lights", []) + [{"type": "environment", "map": "sky.hdr"}]
    seeds["environment"] = pack([json.dumps(scene, indent=1).encode(), obj, mtl, radiance_hdr(8, 4, (128, 128, 160, 129))])
    return seeds


def gltf_seeds():
    import base64
    root = pathlib.Path(__file__).resolve().parent.parent
    seeds = {"cornell-box.glb": (root / "scenes" / "gltf" / "cornell-box.glb").read_bytes()}
    corners = [(0, 0), (1, 0), (0, 1), (1, 1)]
    data = b"".join(struct.pack("<6f", x, y, 0, 0, 0, 1) for x, y in corners)
    data += bytes(v for x, y in corners for v in (x * 255, y * 255)) + struct.pack("<4H", 0, 1, 2, 3)
    sparse = struct.pack("<B3f", 3, 2.0, 2.0, 0.0)
    image = png(2, 2, (200, 120, 40))

    def uri(raw):
        return "data:application/octet-stream;base64," + base64.b64encode(raw).decode()

    quad = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "translation": [1, 2, 3], "camera": 0},
                  {"translation": [0, 5, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.1}}],
        "buffers": [{"byteLength": len(data), "uri": uri(data)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 24},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 8},
                        {"buffer": 0, "byteOffset": 104, "byteLength": 8}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 0, "byteOffset": 12, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 1, "componentType": 5121, "normalized": True, "count": 4, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5123, "count": 4, "type": "SCALAR"}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
                                    "material": 0, "mode": 5}]}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 683}]}},
    }
    seeds["quad.gltf"] = json.dumps(quad).encode()
    with_sparse = json.loads(json.dumps(quad))
    with_sparse["buffers"].append({"byteLength": len(sparse), "uri": uri(sparse)})
    with_sparse["bufferViews"] += [{"buffer": 1, "byteOffset": 0, "byteLength": 1},
                                   {"buffer": 1, "byteOffset": 1, "byteLength": 12}]
    with_sparse["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 3, "componentType": 5121},
                                             "values": {"bufferView": 4}}
    seeds["sparse.gltf"] = json.dumps(with_sparse).encode()
    moved = json.loads(json.dumps(quad))
    moved["nodes"][0] = {"rotation": [0, 0, 0.7071068, 0.7071068], "scale": [-2, 1, 1], "children": [2], "camera": 0}
    moved["nodes"].append({"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1]})
    seeds["nodes.gltf"] = json.dumps(moved).encode()
    textured = json.loads(json.dumps(quad))
    textured["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    textured["textures"] = [{"source": 0, "sampler": 0}]
    textured["samplers"] = [{"wrapS": 33071}]
    textured["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(image).decode()}]
    seeds["textured.gltf"] = json.dumps(textured).encode()
    # Every material feature at once: base colour, metallic-roughness (on TEXCOORD_1, moved by
    # KHR_texture_transform), normal (tangents computed), emissive and specular textures, a
    # doubleSided emitter, alpha masking; a mirrored, nearest sampler; and a spot light.
    materials = json.loads(json.dumps(textured))
    materials["buffers"].append({"byteLength": 8, "uri": uri(bytes([255, 0, 0, 0, 255, 255, 0, 255]))})
    materials["bufferViews"].append({"buffer": 1, "byteOffset": 0, "byteLength": 8})
    materials["accessors"].append({"bufferView": 3, "componentType": 5121, "normalized": True, "count": 4,
                                   "type": "VEC2"})
    materials["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = 4
    materials["samplers"].append({"wrapS": 33648, "wrapT": 33071, "magFilter": 9728})
    materials["textures"].append({"source": 0, "sampler": 1})
    materials["materials"][0].update({
        "normalTexture": {"index": 1, "scale": 0.8},
        "emissiveTexture": {"index": 0},
        "emissiveFactor": [1, 0.5, 0.25],
        "doubleSided": True,
        "alphaMode": "MASK", "alphaCutoff": 0.3,
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4},
                       "KHR_materials_ior": {"ior": 1.4},
                       "KHR_materials_specular": {"specularFactor": 0.7, "specularColorFactor": [1, 0.9, 0.8],
                                                  "specularTexture": {"index": 1},
                                                  "specularColorTexture": {"index": 0, "texCoord": 1}}}})
    materials["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {
        "index": 1, "texCoord": 1,
        "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 0.3, "scale": [2, 2]}}}
    materials["extensionsUsed"] += ["KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_specular",
                                    "KHR_texture_transform"]
    materials["extensions"]["KHR_lights_punctual"]["lights"].append(
        {"type": "spot", "intensity": 2000, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}})
    materials["nodes"].append({"translation": [0, 0, 3], "extensions": {"KHR_lights_punctual": {"light": 1}}})
    materials["scenes"][0]["nodes"].append(2)
    seeds["materials.gltf"] = json.dumps(materials).encode()
    # What a file may claim beyond what it holds: counts far above its bytes, an accessor without a
    # bufferView (zeros, or a sparse one over zeros), and instancing: a node DAG that names its
    # children twice, and a mesh under many roots.
    large = json.loads(json.dumps(quad))
    large["accessors"][0]["count"] = 1 << 28
    large["accessors"][3]["count"] = 3000000000
    seeds["large-counts.gltf"] = json.dumps(large).encode()
    viewless = json.loads(json.dumps(with_sparse))
    del viewless["accessors"][1]["bufferView"]
    del viewless["accessors"][0]["bufferView"]
    viewless["accessors"][0]["count"] = 1 << 20
    seeds["no-buffer-view.gltf"] = json.dumps(viewless).encode()
    dag = json.loads(json.dumps(quad))
    first = len(dag["nodes"])
    dag["nodes"] += [{"children": [first + k + 1] * 2} for k in range(8)] + [{"mesh": 0}]
    dag["scenes"][0]["nodes"].append(first)
    seeds["node-dag.gltf"] = json.dumps(dag).encode()
    roots = json.loads(json.dumps(quad))
    roots["scenes"][0]["nodes"] += [0] * 16
    seeds["repeated-roots.gltf"] = json.dumps(roots).encode()
    return seeds


def dump_file(type_name, record_bytes, records, count=None):
    """A dump (docs/dump-format.md): its 64-byte header, then the records."""
    count = len(records) // record_bytes if count is None else count
    return b"LCNTDUMP" + struct.pack("<IIQ", 1, record_bytes, count) + type_name.encode().ljust(40, b"\0") + records


def dump_seeds():
    """Reference and candidate files in turn (fuzz/dump_fuzzer.cpp), after 8 bytes of tolerances:
    a plain array (a.bin), the neighbour sets and their offsets."""
    tolerances = struct.pack("<fI", 1e-5, 4)
    separator = b"\n--file--\n"
    floats = dump_file("float", 4, struct.pack("<4f", 1, 2, 3, float("inf")))
    rgb = dump_file("Rgb", 12, struct.pack("<6f", 0.1, 0.2, 0.3, 0.4, 0.5, 0.6))
    photons = dump_file("Photon", 32, struct.pack("<6f2I", 1, 2, 3, 0.5, 0.5, 0.5, 7, 9) +
                        struct.pack("<6f2I", 0, 0, 0, 1, 1, 1, 3, 4))
    nodes = dump_file("EnvPointNode", 48, struct.pack("<8f4I", 0, 0, 0, 1, 0, 0, 1, 0.5, 1, 2, 3, 0) +
                      struct.pack("<8f4I", 0, 0, 0, 1, 0, 0, 1, 0.5, 0xFFFFFFFF, 0xFFFFFFFF, 3, 1) * 2)
    neighbours = dump_file("PhotonDistance", 8, struct.pack("<fIfI", 0.25, 0, 0.5, 1))
    offsets = dump_file("uint64", 8, struct.pack("<3Q", 0, 1, 2))
    seeds = {}
    for name, array in (("float", floats), ("rgb", rgb), ("photons", photons), ("tree", nodes)):
        seeds[name] = tolerances + separator.join([array, array])
    seeds["neighbours"] = tolerances + separator.join([floats, floats, neighbours, neighbours, offsets, offsets])
    seeds["differing"] = tolerances + separator.join([rgb, dump_file("Rgb", 12, struct.pack("<6f", 0.1, 0.2, 0.3, 0.4,
                                                                                            0.5, 0.7))])
    seeds["huge-count"] = tolerances + separator.join([dump_file("uint32", 4, b"\0" * 8, count=1 << 40), floats])
    return seeds


def command_line_seeds():
    """Arguments after `lucent`, NUL-separated (fuzz/command_line_fuzzer.cpp): every command, every
    method with its options, the render flags with their values."""
    lines = [
        ["render", "scene.json", "-o", "out.exr", "--spp", "16", "--png", "out.png", "--threads", "2"],
        ["render", "scene.json", "-o", "out.exr", "--resolution", "64x48", "--crop", "0,0,8,8", "--samples", "0:4"],
        ["render", "scene.json", "-o", "out.exr", "--part", "rows:1/4", "--memory-limit", "512M", "--isa", "avx2"],
        ["render", "scene.json", "-o=out.exr", "--checkpoint=30", "--resume", "--strict", "--gltf-masking",
         "height-correlated", "--lumens-per-watt", "683", "--gltf-camera", "Camera", "-q", "--log-stages"],
        ["render", "scene.json", "-o", "out.exr", "--target-error", "0.01", "--time-budget", "10", "--variance",
         "--layers", "--no-layers", "--sampler", "independent", "--strategy", "bsdf"],
        ["compare", "a.exr", "b.exr", "--metric", "relmse", "--threshold", "0.01", "--test", "--within", "0.05"],
        ["merge", "a.film", "b.film", "-o", "m.exr", "--png", "m.png"],
        ["report", "a.exr", "b.exr", "-o", "report.html"],
        ["check-dump", "ref", "cand", "--relative", "1e-5", "--ulps", "4", "--report", "3"],
        ["methods"], ["methods", "--json"], ["render", "--help"], ["--help"],
    ]
    for method, options in (("purcell", ["--photons", "100000", "--k", "50", "--map", "stencil", "--shells", "3"]),
                            ("pmfg", ["--photons", "10000", "--gather-rays", "64", "--caustic-k", "20"]),
                            ("micro", ["--points", "4096", "--lighting", "radiosity", "--buffer-side", "8"]),
                            ("envpbgi", ["--points", "65536", "--mapping", "nusselt", "--splat-reach", "1"]),
                            ("particles", ["--area-particles", "4000", "--sides", "front"])):
        lines.append(["render", "scene.json", "--method", method, "-o", "out.exr", *options])
    return {"args-%02d" % i: b"\0".join(a.encode() for a in line) for i, line in enumerate(lines)}


def main():
    targets = {"scene_loader": scene_loader_seeds, "gltf_loader": gltf_seeds, "film_reader": film_seeds,
               "merge": merge_seeds, "image_header": image_seeds, "dump": dump_seeds,
               "command_line": command_line_seeds}
    if len(sys.argv) != 3 or sys.argv[1] not in targets:
        sys.exit(__doc__)
    out = pathlib.Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    seeds = targets[sys.argv[1]]()
    for name, data in seeds.items():
        (out / name).write_bytes(data)
    print(f"fuzz-corpus: {len(seeds)} {sys.argv[1]} seeds in {out}")


if __name__ == "__main__":
    main()
