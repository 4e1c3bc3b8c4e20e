#!/usr/bin/env python3
"""Point-based GI under environment lighting (--method envpbgi) measured as the paper's figures:

  Fig. 6   time per stage of a frame at 1280 x 720 with 2^19 points (the paper: 500,000), and the
           frame's total without the point hierarchy's construction (the paper builds it "before the
           rendering loop starts"); target (issue 26): at most 1 s on 2 cores;
  Fig. 5   primary and secondary points through the upward and downward traversals, and the
           micro-buffers rasterized as a share of the points (issue 26: at most 5%);
  Fig. 8   the brute force (direct light by micro-buffer at every leaf, a micro-buffer at every
           pixel): its time (issue 26: the paper's pipeline at least 10x faster) and the relMSE of the
           paper's image against it (the approximations' own error; issue 26: at most 0.01 on the
           primitives scene).

The paper's frame is rendered --runs times (3 by default) and the run of median frame time is
shown, with every run's frame; the brute force, ten to eighty times slower, once.

Run on an otherwise idle machine: scripts/bench-envpbgi.py [--threads 2] [--scenes primitives
sponza-courtyard] [--resolution 1280x720] [--points 524288] [--runs 3]
"""
import argparse
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
FRAME = ("select_primary_points", "select_secondary_points", "select_direct_light_points", "direct_light",
         "propagate_direct_light", "radiance_caches", "pixels", "image")
COUNTS = ("primary_points", "secondary_points", "secondary_after_upward", "secondary_after_downward",
          "secondary_own_buffers", "micro_buffers", "cache_fallbacks")


def render(scene, out, args, extra):
    command = [LUCENT, "render", os.path.join(ROOT, "scenes", scene + ".json"), "--method", "envpbgi",
               "--resolution", args.resolution, "--points", str(args.points), "--threads", str(args.threads),
               "--quiet", "-o", out] + extra
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def frameSeconds(summary):
    return sum(summary["stages"].get(s, 0) for s in FRAME)


def relmse(image, reference):
    out = subprocess.run([LUCENT, "compare", image, reference, "--metric", "relmse"], capture_output=True, text=True)
    return json.loads(out.stdout)["value"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--scenes", nargs="+", default=["primitives", "sponza-courtyard"])
    parser.add_argument("--resolution", default="1280x720")
    parser.add_argument("--points", type=int, default=1 << 19)
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    if args.runs < 1:
        parser.error("--runs must be at least 1")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            runs = []
            for i in range(args.runs):
                summary = render(scene, os.path.join(tmp, "paper.exr"), args, [])
                runs.append((frameSeconds(summary), i, summary))
            runs.sort()
            frame, _, paper = runs[(len(runs) - 1) // 2]
            brute = render(scene, os.path.join(tmp, "brute.exr"), args,
                           ["--direct-light", "every-leaf", "--pixel-irradiance", "every-pixel"])
            stages, counts = paper["stages"], paper["counters"]
            bruteFrame = frameSeconds(brute)
            print(f"{scene}, {args.resolution}, {counts['points']} points, {args.threads} threads")
            print("  frames of the runs " + ", ".join(f"{seconds:.3f} s" for seconds, _, _ in runs) + "; the median's stages:")
            print(f"  hierarchy (before the frame) {stages['hierarchy']:.3f} s")
            for s in FRAME:
                print(f"  {s:28s} {stages.get(s, 0):.3f} s")
            print(f"  frame {frame:.3f} s; brute force {bruteFrame:.3f} s ({bruteFrame / frame:.1f}x)")
            for c in COUNTS:
                print(f"  {c:28s} {counts[c]}")
            print(f"  micro-buffers / points {counts['micro_buffers'] / counts['points']:.2%}")
            print(f"  relMSE of the paper's image against the brute force "
                  f"{relmse(os.path.join(tmp, 'paper.exr'), os.path.join(tmp, 'brute.exr')):.5f}", flush=True)


if __name__ == "__main__":
    main()
