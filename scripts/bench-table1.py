#!/usr/bin/env python3
"""Purcell et al. 2003, Table 1, on the CPU: `lucent render --method purcell` on GLASS BALL, RING and
CORNELL BOX at the paper's settings with both map-building methods (bitonic sort, stencil routing),
broken down as the paper's table (trace photons, build map, trace rays, radiance estimate), next to the
paper's GeForce FX 5900 times. Target (issue 3): every scene at least 100x faster end to end on 2 cores.
Then the map benchmark (bench/bench_photon_maps.cpp): bitonic sort against tbb::parallel_sort, and the
kNN-grid against the kd-tree in queries per second at equal k.

Run on an otherwise idle machine: scripts/bench-table1.py [--threads 2] [--repeats 3] [--no-maps]
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")

# Paper's Table 1, seconds: (trace photons, build map, trace rays, radiance estimate).
PAPER = {
    ("glass-ball", "sort"): (1.2, 0.8, 0.5, 14.9),
    ("glass-ball", "stencil"): (1.2, 1.8, 0.5, 7.8),
    ("ring", "sort"): (1.3, 0.8, 0.4, 6.5),
    ("ring", "stencil"): (1.3, 1.8, 0.4, 4.6),
    ("cornell-box", "sort"): (2.1, 1.4, 8.4, 52.4),
    ("cornell-box", "stencil"): (2.1, 1.7, 8.4, 35.0),
}

# The paper's settings (section 3.1): resolution, grid, photons stored, k, shadow rays per pixel.
# The paper stores one map; Lucent's purcell stores indirect photons in the global map and caustic
# photons in the caustic map, so the emitted path counts below are chosen so that the two maps
# together store about the paper's count (printed beside it).
SCENES = {
    "glass-ball": dict(paper_stored=5000, args=["--photons", "5000", "--caustic-photons", "5600",
                                                "--k", "32", "--grid-resolution", "250x1x250",
                                                "--light-samples", "4"]),
    "ring": dict(paper_stored=16000, args=["--photons", "16000", "--caustic-photons", "33500",
                                           "--k", "64", "--grid-resolution", "250x1x250",
                                           "--light-samples", "1"]),
    "cornell-box": dict(paper_stored=65000, args=["--photons", "65000", "--caustic-photons", "0",
                                                  "--k", "500", "--grid-resolution", "25x25x50",
                                                  "--light-samples", "32"]),
}
STAGES = ("trace_photons", "build_map", "trace_rays", "radiance_estimate")


def render(scene, map_name, threads):
    image = os.path.join("/tmp", f"lucent-table1-{os.getpid()}.exr")
    cmd = [LUCENT, "render", os.path.join(ROOT, "scenes", scene + ".json"), "--method", "purcell",
           "--map", map_name, "--threads", str(threads), "--quiet", "-o", image] + SCENES[scene]["args"]
    summary = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
    os.remove(image)
    return summary


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3, help="runs per case; the fastest is reported")
    parser.add_argument("--no-maps", action="store_true", help="skip the map benchmark")
    args = parser.parse_args()
    subprocess.run([os.path.join(ROOT, "scripts", "build.sh")], check=True, stdout=subprocess.DEVNULL)

    print(f"Table 1 (Purcell et al. 2003) with {args.threads} threads, best of {args.repeats}; seconds")
    header = f"{'scene':12} {'map':8} {'stored':>13} " + " ".join(f"{s:>17}" for s in STAGES) + \
        f" {'total':>9} {'paper':>6} {'speedup':>8}"
    print(header)
    rows = []
    for scene in SCENES:
        for map_name in ("sort", "stencil"):
            runs = [render(scene, map_name, args.threads) for _ in range(args.repeats)]
            best = min(runs, key=lambda d: sum(d["stages"][s] for s in STAGES))
            times = [best["stages"][s] for s in STAGES]
            total = sum(times)
            paper = PAPER[(scene, map_name)]
            c = best["counters"]
            stored = f"{c['global_photons'] + c['caustic_photons']}/{SCENES[scene]['paper_stored']}"
            cells = " ".join(f"{t:8.3f} ({p:5.1f})" for t, p in zip(times, paper))
            speedup = sum(paper) / total
            rows.append(dict(scene=scene, map=map_name, seconds=times, paper=paper, speedup=speedup,
                             counters=c))
            print(f"{scene:12} {map_name:8} {stored:>13} {cells} {total:9.3f} {sum(paper):6.1f} "
                  f"{speedup:7.0f}x{'' if speedup >= 100 else ' (< 100x)'}")
    print("stored: photons stored in Lucent's maps / in the paper's; (paper's time per stage)")
    print(json.dumps({"table1": rows}))

    if not args.no_maps:
        print("\nMap benchmark (build/lucent_bench_photon_maps): sorts and kNN queries")
        result = subprocess.run([os.path.join(ROOT, "build", "lucent_bench_photon_maps"),
                                 "--repeats", str(args.repeats)], check=True, capture_output=True, text=True)
        bench = json.loads(result.stdout)
        print(f"{'keys':>9} {'threads':>7} {'bitonic ms':>11} {'tbb::parallel_sort ms':>22} {'ratio':>6}")
        for s in bench["sort"]:
            print(f"{s['keys']:9d} {s['threads']:7d} {s['bitonic_ms']:11.2f} {s['parallel_sort_ms']:22.2f} "
                  f"{s['bitonic_over_parallel_sort']:6.2f}")
        print(f"\nkNN queries per second, {bench['photons']} photons ({'map':>11} {'grid':>9})")
        for q in bench["queries"]:
            for r in q["results"]:
                print(f"k = {q['k']:4d} {q['threads']}t {r['map']:>12} {r.get('grid', ''):>9} {r['queries_per_second']:12.0f} q/s"
                      f"  {r['photons_per_query']:7.1f} photons/query"
                      + (f"  {r['speed_over_kdtree']:.2f}x kd-tree" if 'speed_over_kdtree' in r else ""))
        print(json.dumps(bench))
    return 0


if __name__ == "__main__":
    sys.exit(main())
