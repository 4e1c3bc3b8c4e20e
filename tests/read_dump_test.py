#!/usr/bin/env python3
"""scripts/read-dump.py against the C++ writer (docs/dump-format.md): every dump that a purcell and
a micro render write loads, with as many records as the header says and the file holds, the photon
maps as many photons as the render's summary counts and the shading points their pixels within the
image; a dump of another version, with bytes after its records or cut short is refused.

  read_dump_test.py LUCENT_BINARY SOURCE_DIR
"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

lucent, root = sys.argv[1], sys.argv[2]
spec = importlib.util.spec_from_file_location("read_dump", os.path.join(root, "scripts", "read-dump.py"))
module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
read_dump = module.read_dump
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def render(directory, args):
    out = subprocess.run([lucent, "render"] + args + ["--resolution", "24x16", "--quiet", "--dump", directory,
                                                     "-o", os.path.join(directory, "image.exr")],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def expect_refused(path, data, words):
    with open(path, "wb") as f:
        f.write(data)
    try:
        read_dump(path)
        failures.append(f"{os.path.basename(path)}: accepted, expected '{words}'")
    except ValueError as e:
        check(words in str(e) and os.path.basename(path) in str(e), f"{path}: '{e}' lacks '{words}'")


with tempfile.TemporaryDirectory() as tmp:
    renders = {
        "purcell": ["scenes/glass-ball.json", "--method", "purcell", "--photons", "500", "--caustic-photons", "500"],
        "micro": ["scenes/cornell-box.json", "--method", "micro", "--points", "1024"],
        "envpbgi": ["scenes/primitives.json", "--method", "envpbgi", "--points", "4096"],
        "particles": ["scenes/cornell-box.json", "--method", "particles", "--area-particles", "2000",
                      "--gather-links", "4"],
    }
    for name, args in renders.items():
        directory = os.path.join(tmp, name)
        os.mkdir(directory)
        summary = render(directory, [os.path.join(root, args[0])] + args[1:])
        dumps = sorted(f for f in os.listdir(directory) if f.endswith(".bin"))
        check(len(dumps) >= 5, f"{name}: only {dumps}")
        for dump in dumps:
            path = os.path.join(directory, dump)
            records, header = read_dump(path)
            check(len(records) == header["count"], f"{dump}: {len(records)} records, header {header['count']}")
            check(os.path.getsize(path) == 64 + header["count"] * header["record_bytes"], f"{dump}: length")
            if dump.endswith(".photons.bin"):
                counted = summary["counters"][dump.split(".")[0] + "_photons"]
                check(len(records) == counted, f"{dump}: {len(records)} photons, the summary counts {counted}")
            if dump.endswith("shading_points.bin"):
                check(len(records) > 0 and int(records["pixel"].max()) < 24 * 16, f"{dump}: pixels")
        # Damaged copies of one dump.
        with open(os.path.join(directory, dumps[0]), "rb") as f:
            good = f.read()
        damaged = os.path.join(tmp, f"{name}-damaged.bin")
        expect_refused(damaged, good + b"\0\0\0\0", "bytes after")
        expect_refused(damaged, good[:8] + (2).to_bytes(4, "little") + good[12:], "format version 2")
        expect_refused(damaged, good[:-1], "truncated")
        expect_refused(damaged, b"LCNTDUMX" + good[8:], "not a Lucent dump")

for f in failures:
    print("FAILED:", f)
print(f"read-dump.py: {len(failures)} failures")
sys.exit(1 if failures else 0)
