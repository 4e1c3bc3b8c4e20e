#!/usr/bin/env python3
"""Reads a Lucent dump file (docs/dump-format.md) as a NumPy structured array.

  scripts/read-dump.py FILE.bin [--head N]   prints the header and the first N records

As a module: `records, header = read_dump(path)`. Needs NumPy (Debian: python3-numpy; run with
/usr/bin/python3 where `python3` is another interpreter).
"""
import argparse
import struct
import sys

import numpy as np

HEADER = struct.Struct("<8sIIQ40s")  # magic, version, record_bytes, count, type
assert HEADER.size == 64

F3 = ("<f4", (3,))
DTYPES = {
    "uint32": np.dtype("<u4"),
    "uint64": np.dtype("<u8"),
    "Rgb": np.dtype([("rgb",) + F3]),
    "Photon": np.dtype([("position",) + F3, ("power",) + F3, ("direction", "<u4"), ("flags", "<u4")]),
    "PhotonDistance": np.dtype([("d2", "<f4"), ("index", "<u4")]),
    "UniformGrid": np.dtype([("lo",) + F3, ("hi",) + F3, ("cell_size",) + F3, ("inv_cell_size",) + F3,
                             ("res", "<i4", (3,)), ("slack", "<f4")]),
    "float": np.dtype("<f4"),
    "HalfRgb": np.dtype([("rgb", "<f2", (3,))]),
    "DirectionalRadiance": np.dtype([("shown", "<f4", (6, 3)), ("area", "<f4", (6,))]),
    "PointSample": np.dtype([("triangle", "<u4"), ("b1", "<f4"), ("b2", "<f4")]),
    "FloatNode": np.dtype([("center",) + F3, ("radius", "<f4"), ("cone_axis",) + F3, ("cone_angle", "<f4"),
                           ("albedo",) + F3]),
    "PackedNode": np.dtype([("position", "<u2", (3,)), ("radius", "<u2"), ("normal_albedo", "<u4"), ("cone_free", "<u4")]),
    "NodeQuantization": np.dtype([("origin",) + F3, ("step",) + F3, ("radius_step", "<f4")]),
    "EnvPointNode": np.dtype([("position",) + F3, ("radius", "<f4"), ("normal",) + F3, ("cone_angle", "<f4"),
                              ("child", "<u4", (2,)), ("skip", "<u4"), ("selection", "<u4")]),
    "Surfel": np.dtype([("position",) + F3, ("normal",) + F3]),
    "RadianceCache": np.dtype([("position",) + F3, ("normal",) + F3, ("radius", "<f4"),
                               ("environment", "<f4", (25, 3)), ("indirect", "<f4", (25, 3))]),
    # The lobe's parameters are a union: each kind's fields from byte 64.
    "ShadingPoint": np.dtype({
        "names": ["position", "geometric_normal", "normal", "wo", "weight", "material", "lambertian_kd", "phong_kd",
                  "phong_ks", "phong_ns", "gltf_kd", "gltf_ks", "gltf_alpha", "gltf_f90", "gltf_dielectric_f0",
                  "gltf_dielectric_f90", "gltf_masking", "gltf_sheen_colour", "gltf_sheen_roughness", "gltf_coat",
                  "gltf_coat_alpha", "gltf_coat_normal", "gltf_transmission", "gltf_volume_ior", "pixel", "sample", "branch", "triangle",
                  "medium"],
        "formats": ["(3,)<f4"] * 5 + ["<u4", "(3,)<f4", "(3,)<f4", "(3,)<f4", "<f4", "(3,)<f4", "(3,)<f4"] + ["<f4"] * 4
                   + ["<u4", "(3,)<f4", "<f4", "<f4", "<f4", "(3,)<f4", "<f4", "<f4"] + ["<u4"] * 5,
        "offsets": [0, 12, 24, 36, 48, 60, 64, 64, 76, 88, 64, 76, 88, 92, 96, 100, 104, 108, 120, 124, 128, 132, 144,
                    148, 152, 156, 160, 164, 168],
        "itemsize": 172}),
    "AreaParticle": np.dtype([("position",) + F3, ("normal",) + F3, ("area", "<f4"), ("reflectance",) + F3,
                              ("triangle", "<u4")]),
    "TriangleTessellation": np.dtype([("first", "<u4"), ("segments", "<u4")]),
}


def read_dump(path):
    with open(path, "rb") as f:
        raw = f.read(HEADER.size)
        if len(raw) < HEADER.size:
            raise ValueError(f"{path}: not a Lucent dump (shorter than its header)")
        magic, version, record_bytes, count, type_name = HEADER.unpack(raw)
        if magic != b"LCNTDUMP":
            raise ValueError(f"{path}: not a Lucent dump")
        if version != 1:
            raise ValueError(f"{path}: format version {version}; this reader reads version 1")
        type_name = type_name.rstrip(b"\0").decode("ascii")
        header = {"version": version, "record_bytes": record_bytes, "count": count, "type": type_name}
        dtype = DTYPES.get(type_name)
        if dtype is None:
            raise ValueError(f"{path}: unknown record type '{type_name}'")
        if dtype.itemsize != record_bytes:
            raise ValueError(f"{path}: {type_name} records of {record_bytes} bytes, expected {dtype.itemsize}")
        records = np.fromfile(f, dtype=dtype, count=count)
        if len(records) != count:
            raise ValueError(f"{path}: truncated ({len(records)} of {count} records)")
        trailing = len(f.read())
        if trailing:
            raise ValueError(f"{path}: {trailing} bytes after its {count} records")
        return records, header


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("file")
    parser.add_argument("--head", type=int, default=5, help="records to print")
    args = parser.parse_args()
    try:
        records, header = read_dump(args.file)
    except (OSError, ValueError) as e:
        print(f"read-dump: {e}", file=sys.stderr)
        return 1
    print(header)
    for r in records[: args.head]:
        print(r)
    return 0


if __name__ == "__main__":
    sys.exit(main())
