#!/usr/bin/env python3
"""Where a path tracer's variance comes from, by bounce, for any sampler: the relMSE of one render
against the converged image, estimated from two seeds' renders (mean over pixels and channels of
(A - B)^2 / (r + 0.01)^2, halved), at --max-depth 1 (direct light), 2 (and the first indirect
bounce), 3 (and the second) and in full, each the mean of two pairs of seeds (1 and 2, 3 and 4).
The difference between two depths is what the bounce adds. Unlike `path-variance.py`'s
`--variance` layers, which assume independent samples, this holds for the Sobol sampler too, and
for builds without `--paths`.

  scripts/variance-by-depth.py LUCENT SCENE.json WxH SPP REFERENCE.exr [RENDER OPTION...]

LUCENT is the renderer to measure (e.g. build/lucent, or another commit's build); REFERENCE a
converged image of the scene at WxH (e.g. references/charts/), which only weighs the pixels.
Prints per depth the relMSE, the median seconds of `trace_paths`, and their product. Uses oiiotool
(Debian: openimageio-tools).
"""
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile


def path_variance():
    """path-variance.py (its name is no module name) as a module, for its oiiotool average."""
    spec = importlib.util.spec_from_file_location(
        "path_variance", os.path.join(os.path.dirname(os.path.abspath(__file__)), "path-variance.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


DEPTHS = [1, 2, 3, 1024]
SEED_PAIRS = [(1, 2), (3, 4)]


def render(lucent, scene, size, spp, seed, depth, extra, out):
    """Renders one image; returns trace_paths' seconds."""
    args = [lucent, "render", scene, "--method", "pt", "--resolution", size, "--spp", spp, "--seed", str(seed),
            "--max-depth", str(depth), "-o", out] + extra
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit("variance-by-depth: %s failed:\n%s" % (" ".join(args), done.stderr))
    summary = json.loads(done.stdout.strip().splitlines()[-1])
    return summary["stages"]["trace_paths"]


def half_relative_square_difference(a, b, reference):
    """mean((a - b)^2 / (reference + 0.01)^2) / 2 over pixels and channels (scaled up before
    averaging: oiiotool prints six decimals)."""
    return path_variance().average([a, "--ch", "R,G,B", b, "--ch", "R,G,B", "--sub", "--dup", "--mul",
                                    reference, "--ch", "R,G,B", "--addc", "0.01", "--dup", "--mul", "--div",
                                    "--mulc", "1e6"]) / 1e6 / 2


def main():
    if len(sys.argv) < 6:
        sys.exit(__doc__)
    lucent, scene, size, spp, reference = sys.argv[1:6]
    extra = sys.argv[6:]
    reference_size = subprocess.run(["oiiotool", reference, "--echo", "{TOP.width}x{TOP.height}"],
                                    capture_output=True, text=True).stdout.strip()
    if reference_size != size:
        sys.exit("variance-by-depth: %s is %s, not %s" % (reference, reference_size or "unreadable", size))
    with tempfile.TemporaryDirectory() as tmp:
        print("| depth | relMSE (pairs) | seconds | relMSE x s |")
        print("| ---: | --- | ---: | ---: |")
        for depth in DEPTHS:
            errors, seconds = [], []
            for pair in SEED_PAIRS:
                images = []
                for seed in pair:
                    images.append(os.path.join(tmp, "d%d-s%d.exr" % (depth, seed)))
                    seconds.append(render(lucent, scene, size, spp, seed, depth, extra, images[-1]))
                errors.append(half_relative_square_difference(images[0], images[1], reference))
            error, time = statistics.mean(errors), statistics.median(seconds)
            print("| %s | %.3g (%s) | %.2f | %.3g |" % ("full" if depth == DEPTHS[-1] else depth, error,
                                                       " / ".join("%.3g" % e for e in errors), time, error * time))


if __name__ == "__main__":
    main()
