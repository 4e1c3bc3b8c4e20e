#!/usr/bin/env python3
"""Checks that every code name in the tables of the method READMEs (src/methods/*/README.md and
src/techniques/*/README.md) exists:
each `backticked` name in a table row that looks like an identifier (`traceEyePaths`,
`PhotonTracingOptions::causticOnly`) must occur as a word in the sources, and each file name
(`photon_columns.h`) must be a file of the repository. A README that maps a paper to code must not
name what is gone.

    scripts/check-readme-identifiers.py [README...]    (default: every method and technique README)

Prints each name that is missing and exits 1 if there is one.
"""
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOURCE_GLOBS = ["include/**/*.h", "src/**/*.h", "src/**/*.cpp", "scripts/*", "bench/*.cpp", "tests/*.cpp", "tests/*.py"]
IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*((::|\.)[A-Za-z_][A-Za-z0-9_]*)*(\(\))?$")
FILE = re.compile(r"^[\w./-]+\.(h|cpp|py|sh|md|json|obj|mtl)$")


def main():
    readmes = sys.argv[1:] or sorted(glob.glob(os.path.join(ROOT, "src", "methods", "*", "README.md")) +
                                     glob.glob(os.path.join(ROOT, "src", "techniques", "*", "README.md")))
    files = [f for pattern in SOURCE_GLOBS for f in glob.glob(os.path.join(ROOT, pattern), recursive=True)
             if os.path.isfile(f)]
    words = set()
    for f in files:
        with open(f, errors="replace") as text:
            words.update(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text.read()))
    paths = [os.path.relpath(f, ROOT) for f in glob.glob(os.path.join(ROOT, "**", "*"), recursive=True)
             if "/build" not in f and "/.git/" not in f]
    missing = 0
    checked = 0
    for readme in readmes:
        with open(readme) as text:
            rows = [line for line in text if line.startswith("|")]
        for row in rows:
            for name in re.findall(r"`([^`]+)`", row):
                if FILE.match(name):
                    checked += 1
                    if not any(p == name or p.endswith("/" + name) for p in paths):
                        print(f"{os.path.relpath(readme, ROOT)}: no file {name}")
                        missing += 1
                elif IDENTIFIER.match(name):
                    checked += 1
                    parts = re.split(r"::|\.", name.rstrip("()"))
                    absent = [p for p in parts if p not in words]
                    if absent:
                        print(f"{os.path.relpath(readme, ROOT)}: no {name} in the code ({', '.join(absent)})")
                        missing += 1
    print(f"{checked} names checked in {len(readmes)} READMEs, {missing} missing")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
