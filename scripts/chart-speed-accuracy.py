#!/usr/bin/env python3
"""Speed against accuracy, every method on every scene: relMSE against a converged path-traced
reference over render time, one curve per method, each point one setting of the method's quality
knob (samples, gather rays, photons, micro-buffer size). A curve that keeps falling converges; one
that flattens has met its bias, and the height of the flat part is the method's failure on that
scene. Writes docs/charts/<scene>.png (or --out DIR) and prints every point.

The path tracer averages its pixels (box filter) and is compared with a reference that does too;
purcell, pmfg, micro and particles take one camera ray through each pixel's centre and are compared with a
reference traced through the centres (`--pixel-centres`), so that their curves measure the
method, not the aliasing of point samples at edges.

  /usr/bin/python3 scripts/chart-speed-accuracy.py [--scenes cornell-box ... sponza]
                                                   [--methods pt pmfg ...] [--threads 2] [--out DIR]

The references (path tracer, 16,384 samples per pixel, box-filtered and through the pixel centres)
are rendered once per scene content (its `scene_hash`, in their file names) and kept in out/charts/.
Needs matplotlib (Debian: python3-matplotlib); run with /usr/bin/python3. About 80 minutes on 2
cores with all twelve scenes (gltf/extensions-sky alone: 13); run on an otherwise idle machine.
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
CACHE = os.path.join(ROOT, "out", "charts")

# Each method's knob swept: (label, options) per setting.
def pt_samples(extra=()):
    return [(f"{n} spp", ["--spp", str(n)] + list(extra)) for n in (4, 16, 64, 256, 1024)]


def pt_targets(targets):
    """The path tracer rendering to an error target (adaptive sampling), no pixel capped below 65,536 spp."""
    return [(f"E {e:g}", ["--target-error", str(e), "--spp", "65536"]) for e in targets]


def gather_rays(*counts):
    """pmfg's gather rays, with Purcell's 65,000 photons (pmfg's default before it rose to 130,000)."""
    return [(f"{n} gather rays", ["--gather-rays", str(n), "--photons", "65000"]) for n in counts]


def photons(flags, label, *counts):
    """Photon counts given to every option in `flags` at once (purcell's global and caustic maps)."""
    return [(f"{n // 1000}k {label}", [arg for flag in flags for arg in (flag, str(n))]) for n in counts]


def buffers(*sides):
    return [(f"{n}x{n} buffers", ["--lighting", "vpl", "--buffer-size", str(n)]) for n in sides]


def particle_knobs(particles, counts):
    """The particle-space method's knobs, each swept about the default (`particles` positions, 8
    bounces, 16 x 16 gathering links, subtriangles 3 spacings wide)."""
    base = ["--area-particles", str(particles)]
    return {"particles (area particles)": [(f"{n // 1000}k particles", ["--area-particles", str(n)]) for n in counts],
            "particles (bounces)": [(f"n_b {b}", base + ["--bounces", str(b)]) for b in (1, 2, 4, 8, 16)],
            "particles (gather links)": [(f"{n}x{n} links", base + ["--gather-links", str(n)]) for n in (4, 8, 16, 24)],
            "particles (tessellation)": [(f"{t} spacings", base + ["--tessellation", str(t)]) for t in (1, 2, 3, 6)]}


def scene(resolution, light_samples, rays, purcell, sides, particles=None, targets=(1e-2, 3e-3, 1e-3, 3e-4)):
    methods = {"pt": pt_samples(), "pt (independent)": pt_samples(["--sampler", "independent"]),
               "pt (target error)": pt_targets(targets),
               "pmfg": gather_rays(*rays), "purcell": purcell, "micro (vpl)": buffers(*sides)}
    if particles:
        methods.update(particle_knobs(*particles))
    return {"resolution": resolution, "light_samples": light_samples, "max_depth": None, "methods": methods}


def environment_scene(resolution):
    """A scene of the environment-lighting PBGI paper: one indirect bounce (the paper's transport), so
    the references, the path tracer's curve and micro-rendering's (its points lit directly) stop at
    --max-depth 2. envpbgi's knobs: the point count, the primary points' solid-angle threshold, and
    the primary and secondary buffer sizes."""
    depth = ["--max-depth", "2"]
    return {"resolution": resolution, "light_samples": 1024, "max_depth": 2,
            "methods": {"pt (depth 2)": [(label, options + depth) for label, options in pt_samples()],
                        "pt (depth 2, independent)": [(label, options + depth)
                                                      for label, options in pt_samples(["--sampler", "independent"])],
                        "envpbgi (points)": [(f"2^{k} points", ["--points", str(1 << k)]) for k in (15, 17, 19, 21)],
                        "envpbgi (primary pixels)": [(f"{p} px", ["--primary-pixels", str(p)])
                                                     for p in (80, 320, 1280, 5120)],
                        "envpbgi (buffers)": [(f"{a}x{a}, {b}x{b}", ["--primary-buffer-size", str(a),
                                                                     "--secondary-buffer-size", str(b)])
                                              for a, b in ((8, 4), (16, 8), (24, 12), (32, 16))],
                        "micro (direct)": [(f"{n}x{n} buffers", ["--lighting", "direct", "--buffer-size", str(n)])
                                           for n in (8, 16, 24)]}}


# Per scene: the resolution, the shadow rays per shading point of purcell, pmfg and micro (many, so
# that the noise of their direct light does not hide the error of their indirect light: on Sponza,
# under the sky, micro's relMSE is 0.14 with the default 32 and 0.034 with 1,024), and the settings.
MILLION = (16000, 65000, 260000, 1040000)
SCENES = {
    "cornell-box": scene("128x128", 256, (16, 64, 256, 1024), photons(["--photons"], "photons", *MILLION),
                         (8, 16, 24, 32), (50000, (12500, 25000, 50000, 100000))),
    "glass-ball": scene("128x96", 256, (16, 64, 256, 1024),
                        photons(["--caustic-photons"], "caustic photons", 5000, 20000, 80000, 320000), (8, 16, 24)),
    "cornell-box-spheres": scene("128x128", 256, (16, 64, 256, 1024),
                                 photons(["--photons", "--caustic-photons"], "photons", *MILLION), (8, 16, 24)),
    "cornell-box-glossy": scene("128x128", 256, (16, 64, 256, 1024), photons(["--photons"], "photons", *MILLION),
                                (8, 16, 24)),
    "ring-area": scene("128x96", 256, (16, 64, 256),
                       photons(["--caustic-photons"], "caustic photons", *MILLION), (8, 16, 24)),
    "sponza": scene("160x100", 1024, (16, 64, 256), photons(["--photons"], "photons", 65000, 260000, 1040000),
                    (8, 16, 24), (150000, (37500, 75000, 150000, 300000)), (3e-2, 1e-2, 3e-3)),
    "maze": scene("128x128", 64, (16, 64, 256), photons(["--photons"], "photons", 65000, 260000, 1040000),
                  (8, 16), (150000, (37500, 75000, 150000, 300000)), (1e-1, 3e-2, 1e-2)),
    # glTF scenes (scenes/gltf): Sponza as Blender's exporter wrote it (normal textures, the sun) under
    # the sky, glTF's metals and rough dielectrics with a spot light and the sun, and its material
    # extensions (sheen, clear coat, thin-walled transmission) in the same room.
    "gltf/sponza-sky": scene("160x100", 1024, (16, 64, 256), photons(["--photons"], "photons", 65000, 260000, 1040000),
                             (8, 16, 24), (150000, (37500, 75000, 150000, 300000))),
    "gltf/materials-sky": scene("160x80", 256, (16, 64, 256), photons(["--photons"], "photons", *MILLION),
                                (8, 16, 24), (50000, (12500, 25000, 50000, 100000))),
    "gltf/extensions-sky": scene("160x80", 256, (16, 64, 256), photons(["--photons"], "photons", *MILLION),
                                 (8, 16, 24), (50000, (12500, 25000, 50000, 100000)), (1e-2, 3e-3, 1e-3)),
    "primitives": environment_scene("320x180"),
    "sponza-courtyard": environment_scene("160x100"),
}
REFERENCE_SPP = 16384


def run(args, lucent=LUCENT):
    done = subprocess.run([lucent] + args, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"chart-speed-accuracy: lucent {' '.join(args)} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def file_name(scene):
    """A scene's name as a file name: gltf/sponza-sky becomes gltf-sponza-sky."""
    return scene.replace("/", "-")


def scene_path(name):
    return os.path.join(ROOT, "scenes", name + ".json")


def scene_hash(scene, hashes={}):
    """The hash Lucent gives the scene's content (its files and what they reference), from a render of
    one pixel: a reference kept under it is never one of an older version of the scene."""
    if scene not in hashes:
        image = os.path.join(CACHE, f"hash-{os.getpid()}.exr")
        hashes[scene] = run(["render", scene_path(scene), "--resolution", "1x1", "--spp", "1", "--quiet", "-o", image])[
            "scene_hash"]
        os.remove(image)
    return hashes[scene]


def reference(scene, resolution, centres, max_depth):
    kind = "centres" if centres else "box"
    depth = f"-depth{max_depth}" if max_depth else ""
    path = os.path.join(CACHE, f"{file_name(scene)}-{scene_hash(scene)}-{resolution}-pt{depth}-{REFERENCE_SPP}spp-{kind}.exr")
    if not os.path.exists(path):
        print(f"  (path-tracing the reference {os.path.basename(path)})", flush=True)
        run(["render", scene_path(scene), "--method", "pt", "--spp", str(REFERENCE_SPP), "--seed", "1",
             "--resolution", resolution, "--quiet", "-o", path] + (["--pixel-centres"] if centres else []) +
            (["--max-depth", str(max_depth)] if max_depth else []))
    return path


def measure(scene, resolution, method, options, threads, ref, lucent=LUCENT):
    image = os.path.join(CACHE, f"point-{os.getpid()}.exr")
    name = method.split(" ")[0]
    summary = run(["render", scene_path(scene), "--method", name, "--resolution", resolution, "--threads",
                   str(threads), "--quiet", "-o", image] + options, lucent)
    error = run(["compare", image, ref, "--metric", "relmse"])["value"]
    return summary["seconds"], error


def chart(scene, results, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 5), dpi=110)
    for method, points in results.items():
        xs = [p["seconds"] for p in points]
        ys = [p["relmse"] for p in points]
        # Another build's curve (--pt-build) dashed in black: the colours cycle after ten curves.
        other = {} if method in SCENES[scene]["methods"] else {"linestyle": "--", "color": "black"}
        ax.plot(xs, ys, marker="o", label=method, **other)
        for p in points:
            ax.annotate(p["setting"], (p["seconds"], p["relmse"]), fontsize=6, textcoords="offset points",
                        xytext=(4, 3))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time, seconds (2 threads)")
    depth = SCENES[scene]["max_depth"]
    transport = f", max depth {depth}" if depth else ""
    ax.set_ylabel(f"relMSE against the path tracer at {REFERENCE_SPP} spp{transport}\n(pt: pixel averages; others: pixel centres)")
    ax.set_title(f"{scene}: speed against accuracy")
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = os.path.join(out, f"{file_name(scene)}.png")
    fig.savefig(path)
    plt.close(fig)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "charts"))
    parser.add_argument("--methods", nargs="+", metavar="NAME",
                        help="measure only these methods (pt, pmfg, particles, ...: every curve of the method); "
                             "the others keep the points of the last run")
    parser.add_argument("--pt-build", nargs=2, metavar=("LABEL", "LUCENT"),
                        help="also draw the path tracer's curve as another build renders it (an older commit's "
                             "build/lucent), labelled 'pt (LABEL)'")
    args = parser.parse_args()
    try:
        import matplotlib  # noqa: F401 (checked before anything is rendered)
    except ImportError:
        sys.exit("chart-speed-accuracy: needs matplotlib (Debian: apt-get install python3-matplotlib; "
                 "run with /usr/bin/python3)")
    os.makedirs(CACHE, exist_ok=True)
    os.makedirs(args.out, exist_ok=True)
    data = os.path.join(args.out, "speed-accuracy.json")
    everything = {}
    if os.path.exists(data):  # the scenes not run this time keep their points
        with open(data) as f:
            everything = json.load(f)
    for scene in args.scenes:
        setup = SCENES[scene]
        print(f"== {scene}, {setup['resolution']}, {args.threads} threads", flush=True)
        depth = setup["max_depth"]
        results = {}
        curves = dict(setup["methods"])
        if args.pt_build:
            curves[f"pt ({args.pt_build[0]})"] = pt_samples()
        for method, settings in curves.items():
            if args.methods and method.split(" ")[0] not in args.methods:
                if method in everything.get(scene, {}):
                    results[method] = everything[scene][method]
                continue
            results[method] = []
            ref = reference(scene, setup["resolution"], not method.startswith("pt"), depth)
            # Many shadow rays where the method samples its direct light (envpbgi traces one per light).
            common = (["--light-samples", str(setup["light_samples"])]
                      if method.split(" ")[0] in ("pmfg", "purcell", "micro", "particles") else [])
            for label, options in settings:
                options = options + common
                lucent = args.pt_build[1] if args.pt_build and method == f"pt ({args.pt_build[0]})" else LUCENT
                seconds, error = measure(scene, setup["resolution"], method, options, args.threads, ref, lucent)
                results[method].append({"setting": label, "options": options, "seconds": seconds, "relmse": error})
                print(f"  {method:12s} {label:22s} {seconds:8.2f} s  relMSE {error:.5f}", flush=True)
        for method, points in everything.get(scene, {}).items():
            results.setdefault(method, points)  # curves of other builds (--pt-build) drawn before
        print(f"  chart: {chart(scene, results, args.out)}", flush=True)
        everything[scene] = results
    with open(data, "w") as f:
        json.dump({scene: everything[scene] for scene in SCENES if scene in everything}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
