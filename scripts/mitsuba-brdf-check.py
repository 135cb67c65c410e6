"""Checks the materials of an `interreflect export-mitsuba --brdf-check` export inside Mitsuba 3.

    python mitsuba-brdf-check.py EXPORT_DIR [--samples N] [--json OUT.json]

For every material in EXPORT_DIR/brdf-check.json (written by the exporter from our BRDF models)
it evaluates the Mitsuba BSDF the exporter wrote for it, through Mitsuba's own plugins:

- the directional albedo at each cos θo, as the mean of Mitsuba's sampling weight f·cos/pdf over
  N samples (its standard error alongside), against ours (importance sampled with 2^18 samples);
- f·cos θi at fixed direction pairs (views at 0°, 30°, 60°, 80°; light at the mirror direction
  and 2°, 6°, 20° from it), against ours.

Prints a Markdown table per material and, with --json, writes the numbers. Used by
scripts/mitsuba-check.sh; runs with any Mitsuba 3 variant (scalar_rgb by default).
"""
import argparse
import json
import math
import os
import sys

import mitsuba as mi
import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("export_dir")
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--json")
    a = ap.parse_args()
    mi.set_variant(a.variant)
    with open(os.path.join(a.export_dir, "brdf-check.json")) as f:
        ours = json.load(f)
    scene = mi.load_file(os.path.join(a.export_dir, "scene.xml"), spp=1, width=4, height=4)
    bsdfs = {}
    for shape in scene.shapes():
        name = ours["shapes"].get(shape.id())
        if name is not None and name not in bsdfs:
            bsdfs[name] = shape.bsdf()
    ctx = mi.BSDFContext()
    rng = np.random.default_rng(1)
    out = {}
    for name, m in ours["materials"].items():
        bsdf = bsdfs[name]
        rows = []
        for entry in m["albedo"]:
            c = entry["cos_theta_o"]
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(math.sqrt(max(0.0, 1 - c * c)), 0.0, c)
            u = rng.random((a.samples, 3))
            w = np.zeros((a.samples, 3))
            for k in range(a.samples):
                bs, weight = bsdf.sample(ctx, si, float(u[k, 0]), mi.Point2f(float(u[k, 1]), float(u[k, 2])))
                if bs.pdf > 0:
                    w[k] = [weight[0], weight[1], weight[2]]
            mean = w.mean(axis=0)
            se = w.std(axis=0) / math.sqrt(a.samples)
            rows.append({"cos_theta_o": c, "ours": entry["albedo"], "ours_stderr": entry["stderr"],
                         "mitsuba": mean.tolist(), "mitsuba_stderr": se.tolist()})
        pairs = []
        for p in m["pairs"]:
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(*p["wo"])
            v = bsdf.eval(ctx, si, mi.Vector3f(*p["wi"]))
            pairs.append({"wo": p["wo"], "wi": p["wi"], "ours": p["f_cos"], "mitsuba": [v[0], v[1], v[2]]})
        out[name] = {"mitsuba": m["mitsuba"], "exact": m["exact"], "notes": m["notes"],
                     "albedo": rows, "pairs": pairs}
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    for name, m in out.items():
        print(markdown(name, m))


def angle(w):
    return math.degrees(math.acos(max(-1.0, min(1.0, w[2]))))


def markdown(name, m):
    lines = [f"**{name}** → `{m['mitsuba']}` ({'exact' if m['exact'] else 'approximate'})", "",
             "| cos θo | albedo, ours (R, G, B) | albedo, Mitsuba | Mitsuba / ours − 1 (± 2 s.e.) |",
             "|---|---|---|---|"]
    for r in m["albedo"]:
        o, mt = np.array(r["ours"]), np.array(r["mitsuba"])
        se = np.hypot(np.array(r["ours_stderr"]), np.array(r["mitsuba_stderr"]))
        rel = [f"{(x / y - 1) * 100:+.1f} % (± {2 * s / y * 100:.1f})" if y > 0 else "—"
               for x, y, s in zip(mt, o, se)]
        lines.append(f"| {r['cos_theta_o']:.1f} | {fmt(o)} | {fmt(mt)} | {', '.join(rel)} |")
    lines += ["", "| view θo | light: θi (from mirror) | f·cos θi, ours (G) | Mitsuba (G) | ratio |",
              "|---|---|---|---|---|"]
    for p in m["pairs"]:
        to, ti = angle(p["wo"]), angle(p["wi"])
        o, mt = p["ours"][1], p["mitsuba"][1]
        ratio = f"{mt / o:.3f}" if o > 1e-12 else "—"
        sign = -1 if p["wi"][0] > 0 else 1
        lines.append(f"| {to:.0f}° | {ti:.0f}° ({to - sign * ti:+.0f}°) | {o:.4g} | {mt:.4g} | {ratio} |")
    return "\n".join(lines) + "\n"


def fmt(v):
    return ", ".join(f"{x:.4f}" for x in v)


if __name__ == "__main__":
    sys.exit(main())
