#!/usr/bin/env python3
"""Renders every method on every scene at small resolutions with this build (build/lucent) and with
another binary (a build of an earlier commit), and says for each whether the images are
bit-identical: what a change that must not change images is checked with.

    scripts/compare-renders.py OTHER_LUCENT [--out DIR] [--quick]

A case differs when any pixel of any channel differs (`lucent compare` finds an RMSE above 0) or
the two images do not have the same channels. Exit status 1 when any case differs.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")

SCENES = ["cornell-box", "cornell-box-glossy", "cornell-box-spheres", "glass-ball", "ring", "ring-area", "sponza"]
# glTF files, read directly: their metallic-roughness materials in both masking forms.
GLTF_SCENES = ["gltf/cornell-box.glb"]
# envpbgi refuses emitting triangles: its scenes are lit by an environment and a sun.
ENVIRONMENT_SCENES = ["primitives", "primitives-glossy", "sponza-courtyard"]

# Per method: the options every scene is rendered with, extra variants on its first scene, its
# scenes and the two of them --quick renders.
METHODS = {
    "pt": (["--spp", "4"], [["--strategy", "light"], ["--strategy", "bsdf"], ["--max-depth", "2", "--layers"]],
           SCENES, ["cornell-box", "glass-ball"]),
    "purcell": (["--photons", "20000", "--caustic-photons", "20000", "--light-samples", "4"],
                [["--map", "stencil"], ["--map", "hash"], ["--map", "kdtree"], ["--layers"]],
                SCENES, ["cornell-box", "glass-ball"]),
    "pmfg": (["--photons", "20000", "--caustic-photons", "20000", "--gather-rays", "16", "--light-samples", "4"],
             [["--map", "sort"], ["--layers"]], SCENES, ["cornell-box", "glass-ball"]),
    "micro": (["--light-samples", "4"],
              [["--lighting", "vpl"], ["--lighting", "radiosity"], ["--lighting", "photons"], ["--upsampling", "4"],
               ["--encoding", "packed", "--mapping", "nusselt"], ["--layers"]], SCENES, ["cornell-box", "glass-ball"]),
    "envpbgi": (["--points", "16384"],
                [["--spp", "3"], ["--mapping", "nusselt"], ["--point-sampling", "best-candidate"], ["--layers"],
                 ["--direct-light", "every-leaf", "--pixel-irradiance", "every-pixel", "--points", "4096"]],
                ENVIRONMENT_SCENES, ["primitives", "sponza-courtyard"]),
    "particles": (["--area-particles", "4000", "--light-samples", "4"],
                  [["--sides", "front"], ["--particle-area", "uniform"], ["--spp", "3"], ["--layers"]],
                  SCENES + ["primitives"], ["cornell-box", "glass-ball"]),
}


def cases(quick):
    for method, (base, variants, scenes, quick_scenes) in METHODS.items():
        for scene in (quick_scenes if quick else scenes):
            resolution = "64x40" if scene.startswith("sponza") else "48x48"
            yield f"{scene} {method}", scene, method, ["--resolution", resolution] + base
        for variant in variants:
            yield (f"{scenes[0]} {method} {' '.join(variant)}", scenes[0], method,
                   ["--resolution", "48x48"] + base + variant)
        if scenes is not ENVIRONMENT_SCENES:
            for scene in GLTF_SCENES[:1] if quick else GLTF_SCENES:
                for masking in ["separable", "height-correlated"]:
                    yield (f"{scene} {method} --gltf-masking {masking}", scene, method,
                           ["--resolution", "48x48", "--gltf-masking", masking] + base)


def render(binary, scene, method, args, output):
    path = os.path.join(ROOT, "scenes", scene if os.path.splitext(scene)[1] else scene + ".json")
    command = [binary, "render", path, "--method", method, "--threads", "2",
               "--quiet", "-o", output] + args
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(" ".join(command) + ": " + result.stderr.strip())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("other", help="the lucent binary to compare with")
    parser.add_argument("--out", help="keep the images in this directory")
    parser.add_argument("--quick", action="store_true", help="two scenes per method")
    args = parser.parse_args()
    out = args.out or tempfile.mkdtemp(prefix="lucent-compare-")
    os.makedirs(out, exist_ok=True)
    differing = 0
    for i, (name, scene, method, options) in enumerate(cases(args.quick)):
        mine, theirs = os.path.join(out, f"{i}-this.exr"), os.path.join(out, f"{i}-other.exr")
        render(LUCENT, scene, method, options, mine)
        render(args.other, scene, method, options, theirs)
        result = subprocess.run([LUCENT, "compare", mine, theirs], capture_output=True, text=True)
        if result.returncode == 2:
            verdict = "differs: " + result.stderr.strip().split(": ", 2)[-1]
        else:
            rmse = json.loads(result.stdout)["overall"]["rmse"]
            verdict = "identical" if rmse == 0 else f"differs: RMSE {rmse:.3g}"
        differing += verdict != "identical"
        print(f"{name:60s} {verdict}", flush=True)
    print(f"{differing} of {i + 1} cases differ; images in {out}")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
