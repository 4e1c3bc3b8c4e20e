#!/usr/bin/env python3
"""Makes the image that opens each method's README (docs/images/METHOD.png): the method's render of
a scene that shows where it fails, beside the converged reference of references/ and the per-pixel
relative squared error (`lucent compare --heatmap`: viridis, scaled to its 99th percentile), all at
the reference's resolution; prints each image's relMSE for the README's caption. Takes about two
minutes on 2 cores.

  scripts/make-readme-images.py [--methods NAME ...]
"""
import argparse
import json
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
OUT = os.path.join(ROOT, "docs", "images")

# Per method: the scene, and the options beyond the method's defaults. Sixteen camera rays per
# pixel, so that edges are averaged over the pixel as in the reference and the error shown is the
# method's own. Each README's opening says what the image shows.
RENDERS = {
    "pt": ("cornell-box", ["--spp", "16"]),
    "purcell": ("cornell-box", ["--spp", "16"]),
    "pmfg": ("glass-ball", ["--spp", "16", "--gather-rays", "256"]),
    "micro": ("cornell-box", ["--spp", "16"]),
    "envpbgi": ("primitives-courtyard", ["--spp", "16"]),
    "particles": ("cornell-box", ["--spp", "16"]),
}


def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--methods", nargs="+", default=list(RENDERS))
    args = parser.parse_args()
    os.makedirs(OUT, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for method in args.methods:
            scene, options = RENDERS[method]
            reference = os.path.join(ROOT, "references", scene + ".exr")
            with open(os.path.join(ROOT, "references", scene + ".json")) as f:
                resolution = json.load(f)["resolution"]
            image, shown, truth, heat = (os.path.join(tmp, method + suffix)
                                         for suffix in (".exr", ".png", "-reference.png", "-error.png"))
            run([LUCENT, "render", os.path.join(ROOT, "scenes", scene + ".json"), "--method", method,
                 "--resolution", resolution, "--quiet", "-o", image, "--png", shown] + options)
            run(["oiiotool", reference, "--ch", "R,G,B", "--colorconvert", "linear", "sRGB", "-d", "uint8",
                 "-o", truth])
            compared = subprocess.run([LUCENT, "compare", image, reference, "--heatmap", heat], check=True,
                                      capture_output=True, text=True)
            relmse = json.loads(compared.stdout)["overall"]["relmse"]
            target = os.path.join(OUT, method + ".png")
            run(["oiiotool", shown, truth, heat, "--mosaic", "3x1", "-d", "uint8", "-o", target])
            print(f"{target}: {method} on {scene} {' '.join(options)} | reference | relative squared error "
                  f"(viridis to its 99th percentile); relMSE {relmse:.2e}")


if __name__ == "__main__":
    main()
