#!/usr/bin/env python3
"""Micro-rendering (Ritschel et al. 2009) measured as the paper's figures, on the Cornell box and Sponza:

  Fig. 12  quality and time against the micro-buffer size (8, 16, 24, 32) at 256 x 256, quality as
           relMSE against the path tracer limited to one indirect bounce (--max-depth 2), of the image
           and of its indirect layer (the gathering's error alone);
  Fig. 13  time against the point count, 2^14 to 2^21 (growth must be sub-linear), and the gather
           samples per second against the total number of gather samples (upsampling 1/16, 1/4, 1);
  targets  (issue 4) 512 x 512 with 24 x 24 buffers at every pixel in under 60 s, at 1/16 of the
           pixels with upsampling in under 5 s, on 2 cores;
  departures indirect error and time with the paper's isotropic node radiance and the directional one,
           each with splats up to one and two pixel spacings wide (--node-radiance, --splat-reach);
  breakdown the paper's time shares (hierarchy update, mappings built and evaluated, rasterizing,
           ray casting, upsampling and the rest) and the share of micro-buffers that needed ray casting.

The one-bounce references are path-traced once and kept in out/bench-micro/. Run on an otherwise
idle machine: scripts/bench-micro.py [--threads 2] [--scenes cornell-box sponza] [--quick]
"""
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LUCENT = os.path.join(ROOT, "build", "lucent")
OUT = os.path.join(ROOT, "out", "bench-micro")
SHARES = ("hierarchy_update", "build_mappings", "evaluate_mappings", "rasterize", "ray_casting", "upsampling")


def scene_path(name):
    return os.path.join(ROOT, "scenes", name + ".json")


def run(args):
    return json.loads(subprocess.run([LUCENT] + args, check=True, capture_output=True, text=True).stdout)


def reference(scene, resolution, spp):
    path = os.path.join(OUT, f"{scene}-{resolution}-pt-depth2-{spp}spp.exr")
    if not os.path.exists(path):
        print(f"  (path-tracing the one-bounce reference {os.path.basename(path)})", flush=True)
        run(["render", scene_path(scene), "--method", "pt", "--max-depth", "2", "--spp", str(spp),
             "--resolution", resolution, "--layers", "--quiet", "-o", path])
    return path


def micro(scene, resolution, threads, extra):
    image = os.path.join(OUT, f"micro-{os.getpid()}.exr")
    summary = run(["render", scene_path(scene), "--method", "micro", "--resolution", resolution, "--threads",
                   str(threads), "--layers", "--quiet", "-o", image] + extra)
    return summary, image


def channels(image, spec, tag):
    """Some of the image's channels, as R, G, B of an image of their own (oiiotool)."""
    out = image[:-4] + f"-{tag}.exr"
    subprocess.run(["oiiotool", image, "--ch", spec, "-o", out], check=True)
    return out


def relmse(image, ref):
    """relMSE of the image (R, G, B) and of its indirect layer, the gathering's part, against the reference's.
    The first includes the noise of direct light and of one camera ray per pixel at edges and in textures."""
    values = []
    for spec, tag in (("R,G,B", "rgb"), ("R=indirect.R,G=indirect.G,B=indirect.B", "indirect")):
        values.append(run(["compare", channels(image, spec, tag), channels(ref, spec, tag), "--metric", "relmse"])["value"])
    return values


def shares(summary):
    """The paper's breakdown: each stage's share of the whole render."""
    st = summary["stages"]
    total = summary["seconds"]
    parts = {k: st.get(k, 0) / total for k in SHARES}
    return parts | {"rest (shading, direct light, lighting the points, I/O)": 1 - sum(parts.values())}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--scenes", nargs="+", default=["cornell-box", "sponza"])
    parser.add_argument("--reference-spp", type=int, default=2048)
    parser.add_argument("--quick", action="store_true", help="fewer points in Fig. 13 (2^14 to 2^18)")
    args = parser.parse_args()
    subprocess.run([os.path.join(ROOT, "scripts", "build.sh")], check=True, stdout=subprocess.DEVNULL)
    os.makedirs(OUT, exist_ok=True)
    results = {}
    for scene in args.scenes:
        print(f"\n== {scene}, {args.threads} threads")
        r = results[scene] = {}
        ref256 = reference(scene, "256x256", args.reference_spp)

        print("Fig. 12: buffer size at 256 x 256 (every pixel, default points)")
        print(f"{'buffer':>8} {'seconds':>8} {'relMSE':>8} {'indirect':>9} {'ray-cast buffers':>17}")
        r["fig12"] = []
        for side in (8, 16, 24, 32):
            s, img = micro(scene, "256x256", args.threads, ["--buffer-size", str(side)])
            e, ei = relmse(img, ref256)
            c = s["counters"]
            share = c["micro_buffers_ray_cast"] / max(1, c["micro_buffers"])
            r["fig12"].append(dict(buffer=side, seconds=s["seconds"], relmse=e, indirect_relmse=ei, ray_cast_share=share))
            print(f"{side:>5}^2 {s['seconds']:8.2f} {e:8.4f} {ei:9.4f} {share:16.0%}", flush=True)

        print("Departures: node radiance and splat reach at 256 x 256 (every pixel, default points)")
        print(f"{'radiance':>12} {'reach':>6} {'seconds':>8} {'gathering':>10} {'relMSE':>8} {'indirect':>9}")
        r["departures"] = []
        for radiance in ("isotropic", "directional"):
            for reach in (1, 2):
                s, img = micro(scene, "256x256", args.threads, ["--node-radiance", radiance, "--splat-reach", str(reach)])
                e, ei = relmse(img, ref256)
                row = dict(node_radiance=radiance, splat_reach=reach, seconds=s["seconds"],
                           gathering=s["stages"]["final_gathering"], relmse=e, indirect_relmse=ei)
                r["departures"].append(row)
                print(f"{radiance:>12} {reach:>6} {row['seconds']:8.2f} {row['gathering']:10.2f} {e:8.4f} {ei:9.4f}",
                      flush=True)

        print("Fig. 13 (left): points at 256 x 256, 24 x 24 buffers")
        print(f"{'points':>8} {'seconds':>8} {'gathering':>10} {'hierarchy update':>17} {'nodes/buffer':>13} {'relMSE':>8} "
              f"{'indirect':>9}")
        r["fig13"] = []
        for log2 in range(14, 19 if args.quick else 22):
            s, img = micro(scene, "256x256", args.threads, ["--points", str(1 << log2)])
            c = s["counters"]
            e, ei = relmse(img, ref256)
            row = dict(points=1 << log2, seconds=s["seconds"], gathering=s["stages"]["final_gathering"],
                       update=s["stages"]["hierarchy_update"], nodes=c["nodes_visited"] / c["micro_buffers"],
                       relmse=e, indirect_relmse=ei)
            r["fig13"].append(row)
            print(f"2^{log2:<6} {row['seconds']:8.2f} {row['gathering']:10.2f} {row['update']:17.3f} {row['nodes']:13.0f} "
                  f"{e:8.4f} {ei:9.4f}", flush=True)
        first, last = r["fig13"][0], r["fig13"][-1]
        growth = last["gathering"] / first["gathering"]
        factor = last["points"] / first["points"]
        print(f"gathering grows {growth:.2f}x for {factor:.0f}x the points: "
              f"{'sub-linear' if growth < factor else 'NOT sub-linear'}")

        print("Fig. 13 (right) and the targets: 512 x 512, 24 x 24 buffers")
        print(f"{'gathered':>9} {'seconds':>8} {'gather samples':>15} {'samples/s':>11} {'target':>8}")
        r["throughput"] = []
        for fraction, target in ((16, 5.0), (4, None), (1, 60.0)):
            s, img = micro(scene, "512x512", args.threads, ["--upsampling", str(fraction)])
            c = s["counters"]
            rate = c["gather_samples"] / s["stages"]["final_gathering"]
            ok = "" if target is None else ("met" if s["seconds"] < target else f"> {target:.0f} s")
            r["throughput"].append(dict(fraction=fraction, seconds=s["seconds"], gather_samples=c["gather_samples"],
                                        samples_per_second=rate, shares=shares(s),
                                        ray_cast_share=c["micro_buffers_ray_cast"] / max(1, c["micro_buffers"])))
            print(f"{'1/' + str(fraction):>9} {s['seconds']:8.2f} {c['gather_samples']:15d} {rate:11.3g} {ok:>8}", flush=True)
        full = r["throughput"][-1]
        print("time shares at every pixel (the paper: 1.5% update, 2% building mappings, 18% evaluating, "
              "60% rasterizing, 8% ray casting, 11% upsampling and the rest):")
        for k, v in full["shares"].items():
            print(f"  {k:55} {v:6.1%}")
        print(f"  micro-buffers that needed ray casting: {full['ray_cast_share']:.0%} (the paper: 10-30%)")
    print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
