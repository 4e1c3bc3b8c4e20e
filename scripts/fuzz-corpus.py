#!/usr/bin/env python3
"""Writes the scene loader fuzzer's seed corpus: one input per scene of tests/data (good and bad),
its files joined by NUL bytes in the fuzzer's order (fuzz/scene_loader_fuzzer.cpp: scene.json,
mesh.obj, mesh.mtl, then one image read as texture.png and as sky.hdr) and renamed to the fuzzer's
names, plus scenes with a texture and with an environment map written here.

Usage: scripts/fuzz-corpus.py OUT_DIR
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


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
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
    for name, data in seeds.items():
        (out / name).write_bytes(data)
    print(f"fuzz-corpus: {len(seeds)} seeds in {out}")


if __name__ == "__main__":
    main()
