#!/usr/bin/env python3
"""Speed against accuracy, every method on every scene: relMSE against a converged path-traced
reference over render time, one curve per method, each point one setting of the method's quality
knob (samples, gather rays, photons, micro-buffer size). A curve that keeps falling converges; one
that flattens has met its bias, and the height of the flat part is the method's failure on that
scene. Each point is the median of --seeds runs (3), with bars spanning them. Writes
docs/charts/<scene>.png, docs/charts/summary.png (seconds to relMSE 0.01 and 0.001, per method and
scene), the tables of docs/speed-accuracy.md (each between a `<!-- SCENE: written by ... -->` line
and `<!-- end -->`, and the summary's) and prints every point.

The path tracer averages its pixels (box filter) and is compared with a reference that does too;
purcell, pmfg, micro and particles take one camera ray through each pixel's centre and are compared with a
reference traced through the centres (`--pixel-centres`), so that their curves measure the
method, not the aliasing of point samples at edges.

  /usr/bin/python3 scripts/chart-speed-accuracy.py [--scenes cornell-box ... sponza]
                                                   [--methods pt pmfg ...] [--seeds 3] [--threads 2]
                                                   [--out DIR] [--redraw]

The references (path tracer, 16,384 samples per pixel, box-filtered and through the pixel centres)
are rendered once per scene content (its `scene_hash`, in their file names) and kept, as half
floats (written by oiiotool, which scripts/setup.sh installs) with a JSON of how they were made, in
references/charts/: a run then renders only its points. `--references` renders the missing ones
and nothing else (they are not timed: another job may run beside it).
Needs matplotlib (Debian: python3-matplotlib); run with /usr/bin/python3. One seed over twelve
scenes took 80 minutes on 2 cores (gltf/extensions-sky alone: 13); run on an otherwise idle machine.
"""
import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
CACHE = os.path.join(ROOT, "out", "charts")
REFERENCES = os.path.join(ROOT, "references", "charts")
CHARTS = os.path.join(ROOT, "docs", "charts")
DOC = os.path.join(ROOT, "docs", "speed-accuracy.md")

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
    return [(f"{n / 1000:g}k {label}", [arg for flag in flags for arg in (flag, str(n))]) for n in counts]


def buffers(*sides):
    return [(f"{n}x{n} buffers", ["--lighting", "vpl", "--buffer-size", str(n)]) for n in sides]


def particle_knobs(particles, counts, bounces=None):
    """The particle-space method's knobs, each swept about the default (`particles` positions, 8
    bounces, 16 x 16 gathering links, subtriangles 3 spacings wide); with `bounces` fixed, the others."""
    fixed = ["--bounces", str(bounces)] if bounces is not None else []
    base = ["--area-particles", str(particles)] + fixed
    knobs = {"particles (area particles)": [(f"{n / 1000:g}k particles", ["--area-particles", str(n)] + fixed)
                                            for n in counts],
             "particles (bounces)": [(f"n_b {b}", base + ["--bounces", str(b)]) for b in (1, 2, 4, 8, 16)],
             "particles (gather links)": [(f"{n}x{n} links", base + ["--gather-links", str(n)]) for n in (4, 8, 16, 24)],
             "particles (tessellation)": [(f"{t} spacings", base + ["--tessellation", str(t)]) for t in (1, 2, 3, 6)]}
    if bounces is not None:
        del knobs["particles (bounces)"]
    return knobs


def scene(resolution, light_samples, rays, purcell, sides, particles=(50000, (12500, 25000, 50000, 100000)),
          targets=(1e-2, 3e-3, 1e-3, 3e-4)):
    methods = {"pt": pt_samples(), "pt (independent)": pt_samples(["--sampler", "independent"]),
               "pt (target error)": pt_targets(targets),
               "pmfg": gather_rays(*rays), "purcell": purcell, "micro (vpl)": buffers(*sides)}
    methods.update(particle_knobs(*particles))
    return {"resolution": resolution, "light_samples": light_samples, "max_depth": None, "methods": methods}


def environment_scene(resolution):
    """A scene of the environment-lighting PBGI paper: one indirect bounce (the paper's transport), so
    the references, the path tracer's curve and micro-rendering's (its points lit directly) stop at
    --max-depth 2. envpbgi's knobs: the point count, the primary points' solid-angle threshold, and
    the primary and secondary buffer sizes. pmfg and purcell are not charted here: their photon maps
    carry every bounce whatever --photon-bounces says (docs/speed-accuracy.md)."""
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
                                           for n in (8, 16, 24)],
                        # n_b 0: the direct light's particles gathered once, one indirect bounce.
                        **particle_knobs(150000, (37500, 75000, 150000, 300000), bounces=0)}}


# Per scene: the resolution, the shadow rays per shading point of purcell, pmfg and micro (many, so
# that the noise of their direct light does not hide the error of their indirect light: on Sponza,
# under the sky, micro's relMSE is 0.14 with the default 32 and 0.034 with 1,024), and the settings.
MILLION = (16000, 65000, 260000, 1040000)
SCENES = {
    "cornell-box": scene("128x128", 256, (16, 64, 256, 1024), photons(["--photons"], "photons", *MILLION),
                         (8, 16, 24, 32)),
    "glass-ball": scene("128x96", 256, (16, 64, 256, 1024),
                        photons(["--caustic-photons"], "caustic photons", 5000, 20000, 80000, 320000), (8, 16, 24)),
    "cornell-box-spheres": scene("128x128", 256, (16, 64, 256, 1024),
                                 photons(["--photons", "--caustic-photons"], "photons", *MILLION), (8, 16, 24)),
    "cornell-box-glossy": scene("128x128", 256, (16, 64, 256, 1024), photons(["--photons"], "photons", *MILLION),
                                (8, 16, 24)),
    # The caustic through the ring comes by rare paths, which the error target's estimate misses (0.078
    # at E = 0.003 after 150 s): its smaller targets would take hours.
    "ring-area": scene("128x96", 256, (16, 64, 256),
                       photons(["--caustic-photons"], "caustic photons", *MILLION), (8, 16, 24), targets=(1e-2, 3e-3)),
    "sponza": scene("160x100", 1024, (16, 64, 256), photons(["--photons"], "photons", 65000, 260000, 1040000),
                    (8, 16, 24), (150000, (37500, 75000, 150000, 300000)), (3e-2, 1e-2, 3e-3)),
    "maze": scene("128x128", 64, (16, 64, 256), photons(["--photons"], "photons", 65000, 260000, 1040000),
                  (8, 16), (150000, (37500, 75000, 150000, 300000)), (1e-1, 3e-2, 1e-2)),
    # glTF scenes (scenes/gltf): Sponza as Blender's exporter wrote it (normal textures, the sun) under
    # the sky, glTF's metals and rough dielectrics with a spot light and the sun, and its material
    # extensions (sheen, clear coat, thin-walled transmission) in the same room.
    "gltf/sponza-sky": scene("160x100", 1024, (16, 64, 256), photons(["--photons"], "photons", 65000, 260000, 1040000),
                             (8, 16, 24), (150000, (37500, 75000, 150000, 300000)), (3e-2, 1e-2, 3e-3)),
    "gltf/materials-sky": scene("160x80", 256, (16, 64, 256), photons(["--photons"], "photons", *MILLION),
                                (8, 16, 24)),
    "gltf/extensions-sky": scene("160x80", 256, (16, 64, 256), photons(["--photons"], "photons", *MILLION),
                                 (8, 16, 24), targets=(1e-2, 3e-3, 1e-3)),
    # The Cornell box as Blender's glTF exporter writes it, rendered from the .glb file itself: glTF
    # dielectrics of F0 0 and F90 1 (a Fresnel-weighted GGX lobe over the diffuse one).
    "gltf/cornell-box.glb": scene("128x128", 256, (16, 64, 256, 1024), photons(["--photons"], "photons", *MILLION),
                                  (8, 16, 24)),
    "primitives": environment_scene("320x180"),
    "primitives-white": environment_scene("320x180"),
    "primitives-glossy": environment_scene("320x180"),
    "primitives-courtyard": environment_scene("320x180"),
    "sponza-courtyard": environment_scene("160x100"),
    "sponza-white": environment_scene("160x100"),
}
# RING under its point light is not charted: no method here renders its caustic without bias (the
# path tracer cannot reach a point light by way of a mirror), so it has no reference; ring-area is
# the same scene under an area light of the same power.
REFERENCE_SPP = 16384


def run(args, lucent=LUCENT):
    done = subprocess.run([lucent] + args, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"chart-speed-accuracy: lucent {' '.join(args)} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def file_name(scene):
    """A scene's name as a file name: gltf/sponza-sky becomes gltf-sponza-sky, gltf/cornell-box.glb
    gltf-cornell-box-glb."""
    return scene.replace("/", "-").replace(".", "-")


def scene_path(name):
    """A scene file under scenes/: NAME.json, or a glTF file named with its extension."""
    return os.path.join(ROOT, "scenes", name if name.endswith((".glb", ".gltf")) else name + ".json")


def scene_hash(scene, hashes={}):
    """The hash Lucent gives the scene's content (its files and what they reference), from a render of
    one pixel: a reference kept under it is never one of an older version of the scene."""
    if scene not in hashes:
        image = os.path.join(CACHE, f"hash-{os.getpid()}.exr")
        hashes[scene] = run(["render", scene_path(scene), "--resolution", "1x1", "--spp", "1", "--quiet", "-o", image])[
            "scene_hash"]
        os.remove(image)
    return hashes[scene]


def commit():
    """The checkout's commit (whose build/lucent renders)."""
    done = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    return done.stdout.strip() or None


def reference(scene, resolution, centres, max_depth):
    kind = "centres" if centres else "box"
    depth = f"-depth{max_depth}" if max_depth else ""
    name = f"{file_name(scene)}-{scene_hash(scene)}-{resolution}-pt{depth}-{REFERENCE_SPP}spp-{kind}.exr"
    path = os.path.join(REFERENCES, name)
    if not os.path.exists(path):
        print(f"  (path-tracing the reference {name})", flush=True)
        rendered = os.path.join(CACHE, f"reference-{os.getpid()}.exr")
        options = (["--method", "pt", "--spp", str(REFERENCE_SPP), "--seed", "1", "--resolution", resolution] +
                   (["--pixel-centres"] if centres else []) + (["--max-depth", str(max_depth)] if max_depth else []))
        summary = run(["render", scene_path(scene), "--quiet", "-o", rendered] + options)
        # Half floats: their rounding (2^-11 of the value, relMSE 8e-8) is far below the charts' errors.
        os.makedirs(REFERENCES, exist_ok=True)
        subprocess.run(["oiiotool", rendered, "-d", "half", "--compression", "zip", "-o", path + ".tmp.exr"], check=True)
        os.replace(path + ".tmp.exr", path)
        os.remove(rendered)
        with open(os.path.splitext(path)[0] + ".json", "w") as f:
            json.dump({"scene": os.path.relpath(scene_path(scene), ROOT),
                       "command": "build/lucent render " + os.path.relpath(scene_path(scene), ROOT) + " " +
                                  " ".join(options) + " -o IMAGE.exr, then oiiotool IMAGE.exr -d half -o REFERENCE",
                       "commit": commit(), "scene_hash": scene_hash(scene),
                       "seconds": summary.get("seconds"), "threads": summary.get("threads")}, f, indent=2)
            f.write("\n")
    return path


def measure(scene, resolution, method, options, threads, ref, seeds, lucent=LUCENT):
    """One setting rendered once per seed: each run's seconds and relMSE."""
    image = os.path.join(CACHE, f"point-{os.getpid()}.exr")
    name = method.split(" ")[0]
    runs = []
    for seed in seeds:
        summary = run(["render", scene_path(scene), "--method", name, "--resolution", resolution, "--threads",
                       str(threads), "--seed", str(seed), "--quiet", "-o", image] + options, lucent)
        error = run(["compare", image, ref, "--metric", "relmse"])["value"]
        runs.append({"seed": seed, "seconds": summary["seconds"], "relmse": error})
    return runs


def summarize(label, options, runs):
    """A chart point: the median of the runs' seconds and of their relMSE, with their ranges."""
    seconds = [r["seconds"] for r in runs]
    errors = [r["relmse"] for r in runs]
    return {"setting": label, "options": options, "seconds": statistics.median(seconds),
            "relmse": statistics.median(errors), "seconds_range": [min(seconds), max(seconds)],
            "relmse_range": [min(errors), max(errors)], "runs": runs}


def spread(points, key):
    """Asymmetric error bars from each point's range over seeds (none for points of one run)."""
    ranges = [p.get(f"{key}_range", [p[key], p[key]]) for p in points]
    return [[p[key] - r[0] for p, r in zip(points, ranges)], [r[1] - p[key] for p, r in zip(points, ranges)]]


# Offsets, in points, tried in turn for a point's label until one overlaps no other label or marker:
# eight around the point, then rings of twelve farther out.
LABEL_OFFSETS = ([(5, 3), (5, -10), (-5, 3), (-5, -10), (0, 8), (0, -14), (9, -3), (-9, -3)] +
                 [(round(r * math.cos(a * math.pi / 6)), round(r * math.sin(a * math.pi / 6)) - 3)
                  for r in (18, 28, 40, 54, 70) for a in range(12)])


def place_labels(fig, ax, labels):
    """Annotates each (x, y, text) where its box overlaps no label placed before it and no marker;
    where every offset overlaps something, the one overlapping least."""
    from matplotlib.transforms import IdentityTransform
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    pixels_per_point = fig.dpi / 72
    markers = [ax.transData.transform((x, y)) for x, y, _ in labels]
    placed = [(mx - 3, my - 3, mx + 3, my + 3) for mx, my in markers]

    def overlap(a, b):
        return max(0, min(a[2], b[2]) - max(a[0], b[0])) * max(0, min(a[3], b[3]) - max(a[1], b[1]))

    for (x, y, text), (mx, my) in zip(labels, markers):
        best = None
        for dx, dy in LABEL_OFFSETS:
            probe = ax.text(mx + dx * pixels_per_point, my + dy * pixels_per_point, text, fontsize=6,
                            ha="left" if dx >= 0 else "right", transform=IdentityTransform())
            b = probe.get_window_extent(renderer)
            probe.remove()
            box = (b.x0, b.y0, b.x1, b.y1)
            outside = box[0] < frame.x0 or box[2] > frame.x1 or box[1] < frame.y0 or box[3] > frame.y1
            cost = sum(overlap(box, other) for other in placed) + (1e6 if outside else 0)
            if best is None or cost < best[0]:
                best = (cost, (dx, dy), box)
            if cost == 0:
                break
        (dx, dy), box = best[1], best[2]
        far = abs(dx) > 9 or abs(dy) > 14  # beyond the first ring: a line leads to the point
        ax.annotate(text, (x, y), fontsize=6, textcoords="offset points", xytext=(dx, dy),
                    ha="left" if dx >= 0 else "right",
                    arrowprops={"arrowstyle": "-", "linewidth": 0.3, "color": "grey"} if far else None)
        placed.append(box)


def chart(scene, results, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9.5, 5.5), dpi=110)
    labels = []
    for method, points in results.items():
        xs = [p["seconds"] for p in points]
        ys = [p["relmse"] for p in points]
        # Another build's curve (--pt-build) dashed in black: the colours cycle after ten curves.
        other = {} if method in SCENES[scene]["methods"] else {"linestyle": "--", "color": "black"}
        ax.errorbar(xs, ys, xerr=spread(points, "seconds"), yerr=spread(points, "relmse"), marker="o", markersize=3,
                    capsize=2, elinewidth=0.6, label=method, **other)
        labels += [(p["seconds"], p["relmse"], p["setting"]) for p in points]
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("render time, seconds (2 threads)")
    depth = SCENES[scene]["max_depth"]
    transport = f", max depth {depth}" if depth else ""
    ax.set_ylabel(f"relMSE against the path tracer at {REFERENCE_SPP} spp{transport}\n(pt: pixel averages; others: pixel centres)")
    seeds = max((len(p.get("runs", [])) for points in results.values() for p in points), default=0)
    each = f"median of {seeds} seeds, bars: their range" if seeds > 1 else "one run per point"
    ax.set_title(f"{scene}: speed against accuracy ({each})")
    ax.grid(True, which="both", linewidth=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.tight_layout()
    place_labels(fig, ax, labels)
    path = os.path.join(out, f"{file_name(scene)}.png")
    fig.savefig(path)
    plt.close(fig)
    return path


def time_to_reach(points, target, unbiased):
    """Seconds a curve takes to reach relMSE `target`, interpolated between its points on log-log
    axes, with how it was found: "at most" where its fastest point is already below it, "extrapolated"
    where an unbiased curve (the path tracer's, whose relMSE falls as 1 / time) ends above it, from
    its last point; None where a biased method's settings never get there."""
    points = sorted(points, key=lambda p: p["seconds"])
    if points and points[0]["relmse"] <= target:
        return points[0]["seconds"], "at most"
    for a, b in zip(points, points[1:]):
        if b["relmse"] <= target < a["relmse"]:
            t = (math.log(target) - math.log(a["relmse"])) / (math.log(b["relmse"]) - math.log(a["relmse"]))
            return math.exp(math.log(a["seconds"]) + t * (math.log(b["seconds"]) - math.log(a["seconds"]))), ""
    if unbiased and points:
        return points[-1]["seconds"] * points[-1]["relmse"] / target, "extrapolated"
    return None


def family(curve):
    """The summary's column for a curve: a method's knob sweeps are one column (its best), the path
    tracer's samplers, error target and other builds one each; depth-2 curves are the plain ones."""
    if curve.startswith("pt"):
        return curve.replace("depth 2, ", "").replace(" (depth 2)", "")
    return curve.split(" ")[0]


def times_to_targets(everything, targets=(1e-2, 1e-3)):
    """Per scene (in SCENES' order) and curve family, the seconds to reach each target: (seconds,
    how) from time_to_reach, "never" where no curve of the family gets there, absent where the family
    is not charted on the scene. Returns the scenes, the families and {scene: {family: {target:
    cell}}}."""
    scenes = [scene for scene in SCENES if scene in everything]
    columns = []
    for scene in scenes:
        for curve in everything[scene]:
            if family(curve) not in columns:
                columns.append(family(curve))
    table = {}
    for scene in scenes:
        for column in columns:
            curves = [points for curve, points in everything[scene].items() if family(curve) == column]
            if not curves:
                continue
            # The error target's curve is not extended: where its estimate is low (caustics), its
            # points stop above their targets and do not fall as 1 / time.
            unbiased = column.startswith("pt") and "target error" not in column
            for target in targets:
                reached = [r for r in (time_to_reach(points, target, unbiased) for points in curves) if r]
                table.setdefault(scene, {}).setdefault(column, {})[f"{target:g}"] = min(reached) if reached else "never"
    return scenes, columns, table


def cell_text(cell):
    """A summary cell as text: "never", or its seconds, marked "≤" where at most that long and "~"
    where extrapolated."""
    if cell == "never":
        return "never"
    seconds, how = cell
    return {"at most": "≤", "extrapolated": "~", "": ""}[how] + (f"{seconds:.2g}" if seconds < 10 else f"{seconds:.0f}")


def summary_chart(everything, out, targets=(1e-2, 1e-3)):
    """Time to reach each target per method and scene: a table of coloured cells; 'never' where no
    setting of the method gets there, blank where the method is not charted on the scene."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    scenes, columns, table = times_to_targets(everything, targets)
    fig, axes = plt.subplots(1, len(targets), figsize=(6.5 * len(targets), 0.42 * len(scenes) + 2.2), dpi=110)
    for ax, target in zip(axes, targets):
        cells = [[table[scene].get(column, {}).get(f"{target:g}") for column in columns] for scene in scenes]
        times = [[c[0] if isinstance(c, tuple) else math.nan for c in row] for row in cells]
        colours, norm = plt.get_cmap("viridis_r"), LogNorm(vmin=0.01, vmax=1000)
        ax.imshow(times, cmap=colours, norm=norm, aspect="auto")
        for i, row in enumerate(cells):
            for j, c in enumerate(row):
                if not c:
                    continue
                text = cell_text(c)
                r, g, b, _ = colours(norm(c[0])) if c != "never" else (1, 1, 1, 1)
                ax.text(j, i, text, ha="center", va="center", fontsize=6.5,
                        color="white" if 0.3 * r + 0.59 * g + 0.11 * b < 0.5 else "black")
        ax.set_xticks(range(len(columns)), columns, rotation=40, ha="right", fontsize=7)
        ax.set_yticks(range(len(scenes)), scenes, fontsize=7)
        ax.set_title(f"seconds to relMSE {target:g}", fontsize=9)
    fig.text(0.01, 0.01, "never: no setting swept reaches it; blank: not charted on the scene; ≤: the fastest "
             "setting is already below it; ~: extrapolated from the path tracer's last point as 1 / time. "
             "2 threads.", fontsize=7)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    path = os.path.join(out, "summary.png")
    fig.savefig(path)
    plt.close(fig)
    return path, table


def compact_settings(labels):
    """A curve's settings in one cell: "4 / 16 / 64 spp" where the labels share all but their first
    word, "n_b 1 / 2 / 4" where all but their last, else the labels joined by " / "."""
    words = [label.split(" ") for label in labels]
    if len(labels) > 1 and len({len(w) for w in words}) == 1 and len(words[0]) > 1:
        if all(w[1:] == words[0][1:] for w in words):
            return " / ".join(w[0] for w in words) + " " + " ".join(words[0][1:])
        if all(w[:-1] == words[0][:-1] for w in words):
            return " ".join(words[0][:-1]) + " " + " / ".join(w[-1] for w in words)
    return " / ".join(labels)


def points_table(curves):
    """A scene's points as a Markdown table: per curve its settings, and the medians of their seconds
    and relMSE (3 and 2 significant digits)."""
    rows = ["| curve | settings | seconds | relMSE |", "| --- | --- | ---: | ---: |"]
    for curve, points in curves.items():
        rows.append(f"| {curve} | {compact_settings([p['setting'] for p in points])} | "
                    + " / ".join(f"{p['seconds']:.3g}" for p in points) + " | "
                    + " / ".join(f"{p['relmse']:.2g}" for p in points) + " |")
    return rows


def summary_table(table):
    """times_to_targets' table in Markdown: per scene and curve family, the seconds to each target."""
    columns = []
    for times in table.values():
        columns += [c for c in times if c not in columns]
    rows = ["| seconds to relMSE 0.01, 0.001 | " + " | ".join(columns) + " |", "| --- |" + " ---: |" * len(columns)]
    for scene, times in table.items():
        rows.append(f"| {scene} | " + " | ".join(", ".join(cell_text(c) for c in times[column].values())
                                                  if column in times else "" for column in columns) + " |")
    return rows


def block(key):
    return f"<!-- {key}: written by scripts/chart-speed-accuracy.py from docs/charts/speed-accuracy.json -->"


END_BLOCK = "<!-- end -->"


def doc_with_tables(doc, everything, table):
    """The document with each of its generated blocks (`block(scene)` ... END_BLOCK, and
    `block("summary")`) holding what the JSON gives; a block whose scene the JSON lacks is an error."""
    def replace(match):
        key = match.group(1)
        if key == "summary":
            rows = summary_table(table)
        elif key in everything:
            rows = points_table(everything[key])
        else:
            sys.exit(f"chart-speed-accuracy: docs/speed-accuracy.md has a table for '{key}', which the JSON lacks")
        return block(key) + "\n" + "\n".join(rows) + "\n" + END_BLOCK
    pattern = re.escape(block("KEY")).replace("KEY", "([^:]+)") + r"\n.*?" + re.escape(END_BLOCK)
    return re.sub(pattern, replace, doc, flags=re.S)


def save(everything, path):
    """Writes the points of every scene, in SCENES' order, replacing the file only once written."""
    with open(path + ".tmp", "w") as f:
        json.dump({scene: everything[scene] for scene in SCENES if scene in everything}, f, indent=1)
    os.replace(path + ".tmp", path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--out", default=CHARTS,
                        help="where the charts and their JSON go; only with the default are the tables of "
                             "docs/speed-accuracy.md rewritten")
    parser.add_argument("--methods", nargs="+", metavar="NAME",
                        help="measure only these methods (pt, pmfg, particles, ...: every curve of the method); "
                             "the others keep the points of the last run")
    parser.add_argument("--seeds", type=int, default=3,
                        help="runs per setting, seeds 2 .. N + 1 (the references use seed 1): a point is their "
                             "median, its bars their range")
    parser.add_argument("--redraw", action="store_true",
                        help="render nothing: draw the charts and the summary again from the JSON")
    parser.add_argument("--references", action="store_true",
                        help="render the scenes' missing references (references/charts/) and nothing else")
    parser.add_argument("--pt-build", nargs=2, metavar=("LABEL", "LUCENT"),
                        help="also draw the path tracer's curve as another build renders it (an older commit's "
                             "build/lucent), labelled 'pt (LABEL)'")
    args = parser.parse_args()
    os.makedirs(CACHE, exist_ok=True)
    if args.references:
        for scene in args.scenes:
            setup = SCENES[scene]
            kinds = {not method.startswith("pt") for method in setup["methods"]}
            for centres in sorted(kinds):
                print(f"  {reference(scene, setup['resolution'], centres, setup['max_depth'])}", flush=True)
        return 0
    try:
        import matplotlib  # noqa: F401 (checked before anything is rendered)
    except ImportError:
        sys.exit("chart-speed-accuracy: needs matplotlib (Debian: apt-get install python3-matplotlib; "
                 "run with /usr/bin/python3)")
    os.makedirs(args.out, exist_ok=True)
    data = os.path.join(args.out, "speed-accuracy.json")
    everything = {}
    if os.path.exists(data):  # the scenes not run this time keep their points
        with open(data) as f:
            everything = json.load(f)
    if args.seeds < 1:
        sys.exit("chart-speed-accuracy: --seeds must be at least 1")
    for scene in args.scenes if not args.redraw else []:
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
                runs = measure(scene, setup["resolution"], method, options, args.threads, ref,
                               range(2, args.seeds + 2), lucent)
                point = summarize(label, options, runs)
                results[method].append(point)
                low, high = point["relmse_range"]
                print(f"  {method:12s} {label:22s} {point['seconds']:8.2f} s  relMSE {point['relmse']:.5f} "
                      f"({low:.5f} - {high:.5f})", flush=True)
        for method, points in everything.get(scene, {}).items():
            results.setdefault(method, points)  # curves of other builds (--pt-build) drawn before
        print(f"  chart: {chart(scene, results, args.out)}", flush=True)
        everything[scene] = results
        save(everything, data)  # after each scene: a long run stopped keeps the scenes it finished
    if args.redraw:
        for scene in args.scenes:
            if scene in everything:
                print(f"  chart: {chart(scene, everything[scene], args.out)}", flush=True)
    path, table = summary_chart(everything, args.out)
    print(f"  summary: {path}")
    if os.path.abspath(args.out) == CHARTS:  # the document shows these charts: its tables too
        with open(DOC) as f:
            doc = f.read()
        with open(DOC + ".tmp", "w") as f:
            f.write(doc_with_tables(doc, everything, table))
        os.replace(DOC + ".tmp", DOC)
        print(f"  tables: {DOC}")
    for scene, columns in table.items():
        print(f"  {scene:22s} " + "  ".join(f"{c}: " + ", ".join(f"{t} {cell_text(v)}" for t, v in times.items())
                                            for c, times in columns.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
