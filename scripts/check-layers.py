#!/usr/bin/env python3
"""Checks that Lucent's code stands in its layers (README, Layout): a file may include the headers of
its own layer and of the layers below it, never above; and a method (a folder under src/methods/)
never includes another method's headers, only the registry (src/methods/methods.cpp) names them
all. Prints each include that breaks the order and exits 1 if there is one.

    scripts/check-layers.py
"""
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAYERS = ["core", "image", "scene", "trace", "pipeline", "techniques", "methods", "render", "cli"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
REGISTRY = {"src/methods/methods.cpp"}


def place(path):
    """(layer, folder below the layer) of a repository path or an include path."""
    parts = path.split("/")
    if parts[0] == "include" and parts[1] == "lucent":
        parts = parts[2:]
    elif parts[0] == "lucent":
        parts = parts[1:]
    elif parts[0] == "src":
        parts = parts[1:]
    if not parts or parts[0] not in LAYERS:
        return None, None
    return parts[0], parts[1] if len(parts) > 2 else None


def main():
    files = sorted(glob.glob(os.path.join(ROOT, "include", "lucent", "**", "*.h"), recursive=True) +
                   glob.glob(os.path.join(ROOT, "src", "**", "*.h"), recursive=True) +
                   glob.glob(os.path.join(ROOT, "src", "**", "*.cpp"), recursive=True))
    problems = 0
    for f in files:
        rel = os.path.relpath(f, ROOT)
        layer, folder = place(rel)
        if layer is None:
            print(f"{rel}: not in a layer ({', '.join(LAYERS)})")
            problems += 1
            continue
        with open(f) as text:
            includes = INCLUDE.findall(text.read())
        for included in includes:
            other, other_folder = place(included)
            if other is None:
                continue  # a header of the same folder, named without its path
            if LAYERS.index(other) > LAYERS.index(layer):
                print(f"{rel}: includes {included}, a layer above ({other} over {layer})")
                problems += 1
            elif (layer == other == "methods" and rel not in REGISTRY and other_folder is not None and
                  folder != other_folder):
                print(f"{rel}: includes {included}, another method's header")
                problems += 1
    print(f"check-layers: {len(files)} files, {problems} includes against the layers")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
