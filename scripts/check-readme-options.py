#!/usr/bin/env python3
"""Checks the option tables of the method READMEs (src/methods/*/README.md, "## Options") against the
options the methods declare (`lucent methods --json`): every declared flag of the README's methods
has a row, every row's flag is declared, and the default a row states is the declared one. The
tables keep their own words (why a default, what the paper used); their names and defaults cannot
drift from the code.

    scripts/check-readme-options.py LUCENT [README...]

Prints each difference and exits 1 if there is one.
"""
import glob
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def methods_of(text):
    """The methods a README documents: those its opening names as `lucent render --method X`."""
    opening = text.split("\n## ")[0]
    return sorted(set(re.findall(r"--method (\w+)", opening)))


def option_rows(text):
    """(flags, default cell) of each row of the Options section's tables."""
    section = re.search(r"^## Options\n(.*?)(?=^## |\Z)", text, re.S | re.M)
    if not section:
        return []
    rows = []
    for line in section.group(1).splitlines():
        if not line.startswith("| `--"):
            continue
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        flags = re.findall(r"`(--[a-z0-9-]+)", cells[0])
        rows.append((flags, cells[1] if len(cells) > 1 else ""))
    return rows


def stated_value(words):
    """The value a default cell states first: `off`/`on`, a number (with thousands commas, 2^N),
    `none`, or a word."""
    words = words.replace("`", "").strip()
    token = re.split(r"[ (:]", words, maxsplit=1)[0].rstrip(",")
    if token in ("off", "on"):
        return token == "on"
    if token == "none":
        return None
    power = re.fullmatch(r"(\d+)\^(\d+)", token)
    if power:
        return float(int(power.group(1)) ** int(power.group(2)))
    try:
        return float(token.replace(",", ""))
    except ValueError:
        return token


def declared_value(option):
    default = option.get("default")
    if isinstance(default, bool) or default is None:
        return default
    if isinstance(default, (int, float)):
        return float(default)
    return default if default != "" else None


def main():
    lucent = sys.argv[1]
    readmes = sys.argv[2:] or sorted(glob.glob(os.path.join(ROOT, "src", "methods", "*", "README.md")))
    declared = {m["name"]: {o["flag"]: o for o in m["options"]}
                for m in json.loads(subprocess.run([lucent, "methods", "--json"], capture_output=True, text=True,
                                                   check=True).stdout)}
    problems = checked = 0
    for readme in readmes:
        name = os.path.relpath(readme, ROOT)
        with open(readme) as f:
            text = f.read()
        methods = methods_of(text)
        if not methods or any(m not in declared for m in methods):
            print(f"{name}: its opening names no declared method (`lucent render --method X`): {methods}")
            problems += 1
            continue
        rows = option_rows(text)
        documented = {flag for flags, _ in rows for flag in flags}
        for method in methods:
            for flag in declared[method]:
                if flag not in documented:
                    print(f"{name}: {method}'s {flag} has no row in the options table")
                    problems += 1
        for flags, default in rows:
            for flag in flags:
                owners = [m for m in methods if flag in declared[m]]
                if not owners:
                    print(f"{name}: {flag} is in the options table, but {', '.join(methods)} declare no such option")
                    problems += 1
                    continue
                if len(flags) > 1 or not default:
                    continue  # a row of shared options, described elsewhere
                checked += 1
                for method in owners:
                    # Per-method defaults are written "purcell 65,000, pmfg 130,000".
                    own = re.search(rf"\b{method}\s+(\S+?)(?:,\s|$)", default)
                    stated = stated_value(own.group(1) if own and len(methods) > 1 else default)
                    expected = declared_value(declared[method][flag])
                    if stated != expected and not (isinstance(stated, float) and isinstance(expected, float) and
                                                   abs(stated - expected) <= 1e-9 * abs(expected)):
                        print(f"{name}: {flag} default stated as {default!r}, declared {expected!r} for {method}")
                        problems += 1
    print(f"check-readme-options: {len(readmes)} READMEs, {checked} defaults checked, {problems} differences")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
