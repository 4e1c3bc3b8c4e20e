#!/usr/bin/env python3
"""Checks that no function in Lucent's code is longer than 120 lines (from the line of its opening
brace to the line of its closing one; the lambdas in it count as its lines): a function that long
does several things, each of which deserves a name. Prints each one that is longer and exits 1 if
there is one. Tests, benchmarks and fuzz targets are left out.

    scripts/check-function-length.py [--limit N] [PATH...]   (default: src python backends/opencl/host)
    scripts/check-function-length.py --self-test
"""
import argparse
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_PATHS = ["src", "python", "backends/opencl/host"]
CONTROL = re.compile(r"\b(if|for|while|switch|catch|do|else|try)\s*(\(.*)?$", re.S)
# A function's header ends with its parameter list, then qualifiers, a trailing return type or a
# constructor's initializers.
FUNCTION_HEADER = re.compile(r"\)\s*(const|noexcept|override|final|mutable|&|&&|\s)*(->[^{;]*)?$", re.S)


def code_only(text):
    """The text with comments, string and character literals and preprocessor lines blanked, line
    breaks kept, so that braces in them do not count and line numbers stay."""
    out, i, n = [], 0, len(text)
    at_line_start = True
    while i < n:
        c = text[i]
        if at_line_start and c in " \t":
            out.append(c)
            i += 1
            continue
        if at_line_start and c == "#":  # a preprocessor line, with its continuations
            while i < n and text[i] != "\n":
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out.append("\n")
                    i += 2
                    continue
                i += 1
            continue
        at_line_start = c == "\n"
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
            continue
        if text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            out.append("\n" * text.count("\n", i, end))
            i = end
            continue
        raw = re.match(r'R"([^(\s]*)\(', text[i:i + 20]) if c == "R" and (i == 0 or not text[i - 1].isalnum()) else None
        if raw:
            close = ")" + raw.group(1) + '"'
            end = text.find(close, i + raw.end())
            end = n if end < 0 else end + len(close)
            out.append('""' + "\n" * text.count("\n", i, end))
            i = end
            continue
        if c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(c)  # a digit separator: 1'000'000
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def long_functions(text, limit):
    """(first line, lines, header) of each outermost function body longer than `limit` lines."""
    code = code_only(text)
    found, stack, header_start = [], [], 0
    for pos, c in enumerate(code):
        if c == "{":
            header = code[header_start:pos].strip()
            last_line = header.split("\n")[-1].strip()
            in_function = any(kind == "function" for kind, _ in stack)
            is_function = (not in_function and FUNCTION_HEADER.search(header) is not None and
                           not CONTROL.match(last_line) and not header.endswith("="))
            stack.append(("function" if is_function else "block", pos))
            header_start = pos + 1
        elif c == "}":
            if stack:
                kind, start = stack.pop()
                if kind == "function":
                    first, last = code.count("\n", 0, start) + 1, code.count("\n", 0, pos) + 1
                    if last - first + 1 > limit:
                        name = " ".join(code[:start].rstrip().split("\n")[-1].split())
                        found.append((first, last - first + 1, name))
            header_start = pos + 1
        elif c == ";":
            header_start = pos + 1
    return found


def self_test():
    body = "\n".join("  x += %d;" % i for i in range(130))
    text = ('// a comment { with a brace\nnamespace a {\nstruct S {\n  int f() const {\n%s\n    return 1;\n  }\n};\n'
            'int g(int x) {\n  if (x) {\n%s\n  }\n  auto l = [&](int y) {\n    return "}";\n  };\n  return x;\n}\n'
            'int h() { return 0; }\n}  // namespace a\n') % (body, body)
    found = long_functions(text, 120)
    assert [(n, name) for _, n, name in found] == [(133, "int f() const"), (138, "int g(int x)")], found
    assert long_functions(text, 140) == [], long_functions(text, 140)
    print("check-function-length: self-test passed")
    return 0


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("paths", nargs="*", default=DEFAULT_PATHS)
    parser.add_argument("--limit", type=int, default=120)
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    files = []
    for path in args.paths:
        full = os.path.join(ROOT, path)
        files += [full] if os.path.isfile(full) else sorted(
            f for ext in ("cpp", "h") for f in glob.glob(os.path.join(full, "**", "*." + ext), recursive=True))
    problems = 0
    for f in files:
        with open(f, encoding="utf-8") as source:
            for first, lines, name in long_functions(source.read(), args.limit):
                print(f"{os.path.relpath(f, ROOT)}:{first}: {lines} lines, over {args.limit}: {name}")
                problems += 1
    print(f"check-function-length: {len(files)} files, {problems} functions over {args.limit} lines")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
