#!/usr/bin/env python3
"""Renders references/: a converged path-traced reference of every scene in scenes/, at a quarter
of the scene's resolution (a side at least 96), with the variance of each pixel's mean (independent
samples, --variance), and beside each EXR a JSON sidecar saying how it was made. Takes about ten
minutes on 2 cores.

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
# Samples per pixel: more where the light is harder to find (caustics through glass from an area
# light), fewer where a sample costs more (Sponza).
SPP = {"glass-ball": 16384, "ring-area": 16384, "sponza": 4096, "sponza-courtyard": 4096, "sponza-white": 4096}
DEFAULT_SPP = 8192


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
        spp = SPP.get(scene, DEFAULT_SPP)
        image = os.path.join(OUT, scene + ".exr")
        command = ["render", os.path.join("scenes", scene + ".json"), "--method", "pt", "--sampler", "independent",
                   "--variance", "--spp", str(spp), "--seed", str(SEED), "--resolution", resolution(scene),
                   "--threads", str(args.threads), "--quiet", "-o", os.path.join("references", scene + ".exr")]
        start = time.time()
        done = subprocess.run([LUCENT] + command, cwd=ROOT, check=True, capture_output=True, text=True)
        summary = json.loads(done.stdout.strip().splitlines()[-1])
        sidecar = {"scene": f"scenes/{scene}.json", "command": "build/lucent " + " ".join(command),
                   "method": "pt", "sampler": "independent", "spp": spp, "seed": SEED,
                   "resolution": resolution(scene), "version": version, "scene_hash": summary["scene_hash"],
                   "seconds": round(time.time() - start, 1), "threads": args.threads,
                   "date": datetime.date.today().isoformat()}
        with open(os.path.join(OUT, scene + ".json"), "w") as f:
            json.dump(sidecar, f, indent=2)
            f.write("\n")
        print(f"{scene}: {sidecar['resolution']}, {spp} spp, {sidecar['seconds']} s, {os.path.getsize(image)} bytes",
              flush=True)


if __name__ == "__main__":
    main()
