#!/usr/bin/env python3
"""Diffuse GI in particle spaces (--method particles) measured as the paper's Tables 1 and 2:

  Table 1  the geometry stage (--geometry all: every particle's links, every radiance particle's
           list) with the paper's particle counts (CBOX 50,000, SPONZA 150,000, MAZE 150,000):
           time per substep, links' and lists' memory, radiance particles generated; target
           (issue 27): SPONZA's in at most the paper's 3.24 s (GTX 680) on 2 threads;
  Table 2  a frame at 1024 x 1024 with single sampling: the lighting and ray tracing stages
           (emission, scattering, preliminary ray tracing, gathering, radiance estimation, the
           final ray tracing and the image), with the found radiance particles and the used area
           particles; target: at most 0.5 s for CBOX and SPONZA;
  and the whole render as a batch user runs it (--geometry frame: links and lists only where the
  frame needs them).

The Cornell box is measured twice: with its area light (32 shadow rays per shading point) and lit
by a point light as the paper's CBOX is (one; `cornell-box-point`, made in a temporary directory).

Run on an otherwise idle machine: scripts/bench-particles.py [--threads 2] [--scenes cornell-box
cornell-box-point sponza maze] [--resolution 1024x1024]
"""
import argparse
import json
import math
import os
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
PAPER = {"cornell-box": ("CBOX", 50000, 8), "cornell-box-point": ("CBOX, point light", 50000, 8),
         "sponza": ("SPONZA", 150000, 8), "maze": ("MAZE", 150000, 13)}
GEOMETRY = ("area_particles", "particle_grid", "particle_areas", "scatter_links", "gather_links", "tessellation",
            "list_grid", "estimation_lists")
FRAME = ("light_emission", "scattering", "preliminary_ray_tracing", "mark_radiance_particles", "collect_area_particles",
         "gathering", "radiance_estimation",
         "ray_tracing", "image")
COUNTS = ("area_particles", "scatter_link_bytes", "gather_link_bytes", "radiance_particles", "estimation_list_bytes",
          "lit_particles", "found_radiance_particles", "used_area_particles", "empty_estimation_lists")


def point_lit_cornell_box(directory):
    """The Cornell box lit as the paper's CBOX is, by a point light: just below the centre of the
    ceiling light (which stays, black), with twice the ceiling light's power (half of it goes up)."""
    with open(os.path.join(ROOT, "scenes", "cornell-box.json")) as f:
        scene = json.load(f)
    for mesh in scene["meshes"]:
        mesh["obj"] = os.path.join(ROOT, "scenes", mesh["obj"])
    ke = scene["materials"]["light"].pop("Ke")
    area = 130.0 * 105.0  # the light's quad, 343-213 x 332-227
    scene["lights"] = [{"type": "point", "position": [278.0, 547.8, 279.5],
                        "power": [2 * math.pi * area * k for k in ke]}]
    path = os.path.join(directory, "cornell-box-point.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    return path


def render(scene, out, args, extra):
    _, particles, bounces = PAPER[scene]
    path = (point_lit_cornell_box(os.path.dirname(out)) if scene == "cornell-box-point"
            else os.path.join(ROOT, "scenes", scene + ".json"))
    command = [LUCENT, "render", path, "--method", "particles",
               "--resolution", args.resolution, "--area-particles", str(particles), "--bounces", str(bounces),
               "--threads", str(args.threads), "--quiet", "-o", out] + extra
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--scenes", nargs="+", default=list(PAPER))
    parser.add_argument("--resolution", default="1024x1024")
    args = parser.parse_args()
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            name = PAPER[scene][0]
            full = render(scene, os.path.join(tmp, "all.exr"), args, ["--geometry", "all"])
            batch = render(scene, os.path.join(tmp, "frame.exr"), args, ["--geometry", "frame"])
            stages = full["stages"]
            geometry = {s: stages.get(s, 0.0) for s in GEOMETRY}
            frame = {s: stages.get(s, 0.0) for s in FRAME}
            result = {
                "geometry_stage_seconds": round(sum(geometry.values()), 3),
                "geometry": {k: round(v, 3) for k, v in geometry.items()},
                "frame_seconds": round(sum(frame.values()), 3),
                "frame": {k: round(v, 3) for k, v in frame.items()},
                "counts": {k: full["counters"].get(k, 0) for k in COUNTS},
                "batch_render_seconds": round(batch["seconds"], 3),
                "batch_stages": {k: round(v, 3) for k, v in batch["stages"].items() if v >= 0.01},
            }
            results[name] = result
            print(json.dumps({name: result}), flush=True)
    print(json.dumps({"threads": args.threads, "resolution": args.resolution,
                      "geometry_stage_seconds": {k: v["geometry_stage_seconds"] for k, v in results.items()},
                      "frame_seconds": {k: v["frame_seconds"] for k, v in results.items()}}))


if __name__ == "__main__":
    main()
