#!/usr/bin/env python3
"""Renders references/: a converged path-traced reference of every scene in scenes/, at a quarter
of the scene's resolution (a side at least 96), rendered to an error target (--target-error: the
estimated relMSE against the converged image), with the variance of each pixel's mean (independent
samples, --variance), and beside each EXR a JSON sidecar saying how it was made and the error it
reached. Takes about twenty minutes on 2 cores.

  scripts/make-references.py [--scenes NAME ...] [--threads N]
"""
import argparse
import datetime
import json
import os
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
OUT = os.path.join(ROOT, "references")
SEED = 1
# The relMSE each reference is rendered to: higher where a sample costs more or the light is hard
# to find (Sponza's rooms, lit over several bounces; the maze's hidden lights) and where light
# arrives through glass from an area light (whose rare paths the estimate sees late: the path
# tracer's README, "Rendering to an error target"); lower where samples are cheap.
TARGET = {"maze": 1e-2, "sponza": 1e-3, "sponza-courtyard": 1e-3, "sponza-white": 1e-3,
          "glass-ball": 5e-4, "ring-area": 5e-4, "cornell-box-spheres": 5e-4,
          "ring": 2e-5, "primitives": 2e-5, "primitives-courtyard": 2e-5, "primitives-glossy": 2e-5,
          "primitives-white": 2e-5}
DEFAULT_TARGET = 1e-4
MAX_SPP = 1 << 20


def scenes():
    return sorted(f[:-5] for f in os.listdir(os.path.join(ROOT, "scenes")) if f.endswith(".json"))


def resolution(scene):
    with open(os.path.join(ROOT, "scenes", scene + ".json")) as f:
        width, height = json.load(f)["camera"]["resolution"]
    scale = max(0.25, 96 / min(width, height))
    return f"{round(width * scale)}x{round(height * scale)}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=scenes())
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    args = parser.parse_args()
    os.makedirs(OUT, exist_ok=True)
    version = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True,
                             text=True).stdout.strip() or "unknown"
    for scene in args.scenes:
        target = TARGET.get(scene, DEFAULT_TARGET)
        image = os.path.join(OUT, scene + ".exr")
        command = ["render", os.path.join("scenes", scene + ".json"), "--method", "pt", "--sampler", "independent",
                   "--variance", "--target-error", str(target), "--spp", str(MAX_SPP), "--seed", str(SEED),
                   "--resolution", resolution(scene), "--threads", str(args.threads), "--quiet", "-o",
                   os.path.join("references", scene + ".exr")]
        start = time.time()
        done = subprocess.run([LUCENT] + command, cwd=ROOT, check=True, capture_output=True, text=True)
        summary = json.loads(done.stdout.strip().splitlines()[-1])
        if summary["estimated_relmse"] > target:
            raise SystemExit(f"{scene}: the target {target} was not reached: {done.stderr.strip()}")
        width, height = (int(side) for side in resolution(scene).split("x"))
        sidecar = {"scene": f"scenes/{scene}.json", "command": "build/lucent " + " ".join(command),
                   "method": "pt", "sampler": "independent", "target_error": target,
                   "estimated_relmse": summary["estimated_relmse"], "samples_spent": summary["samples_spent"],
                   "spp": round(summary["samples_spent"] / (width * height)), "seed": SEED,
                   "resolution": resolution(scene), "version": version, "scene_hash": summary["scene_hash"],
                   "seconds": round(time.time() - start, 1), "threads": args.threads,
                   "date": datetime.date.today().isoformat()}
        with open(os.path.join(OUT, scene + ".json"), "w") as f:
            json.dump(sidecar, f, indent=2)
            f.write("\n")
        print(f"{scene}: {sidecar['resolution']}, relMSE {summary['estimated_relmse']:.3g} (target {target}), "
              f"{sidecar['spp']} spp on average, {sidecar['seconds']} s, {os.path.getsize(image)} bytes",
              flush=True)


if __name__ == "__main__":
    main()
