#!/usr/bin/env python3
"""Where a path-traced image's variance comes from: per light-path layer, its mean and its share of
the image's expected relMSE, mean over pixels and channels of var / (r + 0.01)^2 (the relMSE the
image's noise alone gives against the converged image).

  scripts/path-variance.py IMAGE.exr...

Each image is a render with `--method pt --sampler independent --variance --paths`. Uses
oiiotool (Debian: openimageio-tools). The layers' shares need not add up to 100%: the parts of one
sample are correlated, and the image's variance is that of their sum.
"""
import os
import re
import subprocess
import sys

LAYERS = ["emission", "direct", "indirect.1", "indirect.2", "indirect.3+", "diffuse", "glossy"]


def average(args):
    """The mean over pixels and channels of the image oiiotool's arguments make."""
    out = subprocess.run(["oiiotool"] + args + ["--printstats"], capture_output=True, text=True).stdout
    found = re.search(r"Avg: ([^\n]*)", out)
    if not found:
        sys.exit("path-variance: oiiotool %s failed" % " ".join(args))
    values = [float(v) for v in found.group(1).split() if v[0] in "-0123456789."]
    return sum(values) / len(values)


def channels(path, prefix):
    return [path, "--ch", ",".join("%s=%s%s" % (c, prefix, c) for c in "RGB")]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for path in sys.argv[1:]:
        weight = channels(path, "") + ["--addc", "0.01", "--dup", "--mul"]  # (r + 0.01)^2
        # Scaled up before averaging: oiiotool prints six decimals.
        relative = lambda prefix: average(channels(path, prefix + "variance.") + weight + ["--div", "--mulc", "1e6"]) / 1e6
        mean = lambda prefix: average(channels(path, prefix) + ["--mulc", "1e3"]) / 1e3
        total = relative("")
        print("%s: mean %.4f, expected relMSE from its variance %.4e" % (os.path.basename(path), mean(""), total))
        for layer in LAYERS:
            v = relative("paths.%s." % layer)
            print("  %-12s mean %.4f  relative variance %.4e  %5.1f%%" %
                  (layer, mean("paths.%s." % layer), v, 100 * v / total if total > 0 else 0))


if __name__ == "__main__":
    main()
