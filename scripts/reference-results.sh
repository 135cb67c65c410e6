#!/usr/bin/env bash
# Renders the evaluation scenes with the reference renderer into results/reference/ and writes
# results/reference/README.md (images, spp, time, paths per second, from each render's JSON log).
#
#   scripts/reference-results.sh [SPP]        (default 256)
#
# The EXRs stay local (git-ignored); the PNG previews, JSON logs and the table are committed.
set -euo pipefail
cd "$(dirname "$0")/.."
spp="${1:-256}"
out=results/reference
mkdir -p "$out"
cargo build --release --quiet
for scene in ring dragon bunny; do
  # SKIP_RENDER=1 only rebuilds the table from the existing JSON logs.
  if [ "${SKIP_RENDER:-0}" = 1 ]; then break; fi
  echo "== $scene ($spp spp)"
  target/release/interreflect render "scenes/$scene.toml" --method reference --spp "$spp" \
    --output "$out/$scene.exr"
  target/release/interreflect render "scenes/$scene.toml" --method reference --spp "$spp" \
    --indirect-only --output "$out/$scene-indirect.exr"
done
python3 - "$out" <<'PY'
import json, os, sys, platform
out = sys.argv[1]
rows = []
for scene in ["ring", "dragon", "bunny"]:
    for kind in ["", "-indirect"]:
        p = os.path.join(out, f"{scene}{kind}.json")
        with open(p) as f:
            j = json.load(f)
        rows.append((scene, kind, j))
cpu = "unknown CPU"
try:
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
            break
except OSError:
    pass
with open(os.path.join(out, "README.md"), "w") as f:
    f.write("# Reference renders\n\n")
    f.write("Written by `scripts/reference-results.sh`: the path-traced reference (direct light + exactly one\n")
    f.write("indirect bounce, exact BRDFs and visibility; see `docs/reference.md`) on the three evaluation\n")
    f.write(f"scenes. Machine: {os.cpu_count()} threads, {cpu}. PNGs use the tonemap in each row (linear EXRs are\n")
    f.write("regenerated locally by the script and not committed).\n\n")
    f.write("| scene | part | resolution | spp | triangles | render time (s) | total time (s) | M paths/s | M rays/s |\n")
    f.write("|---|---|---|---|---|---|---|---|---|\n")
    for scene, kind, j in rows:
        part = "indirect only" if kind else "direct + indirect"
        s = j["seconds"]
        f.write(f"| {scene} | {part} | {j['width']}×{j['height']} | {j['spp']} | {j['triangles']:,} | {s['render']:.1f} | {s['total']:.1f} | {j['paths_per_second']/1e6:.3f} | {j['rays_per_second']/1e6:.2f} |\n")
    f.write("\nPaths per second count camera paths and light-tracing paths (one light path per camera path\n")
    f.write("with the scenes' `light_paths = 1`); rays per second count every ray (camera, continuation,\n")
    f.write("connection, shadow). Tonemap: " + rows[0][2]["tonemap"] + ".\n\n")
    for scene, kind, j in rows:
        if kind:
            continue
        f.write(f"## {scene}\n\n| direct + one bounce | one bounce only |\n|---|---|\n")
        f.write(f"| ![{scene}]({scene}.png) | ![{scene} indirect]({scene}-indirect.png) |\n\n")
PY
# The 1/sqrt(spp) measurement of tests/convergence.rs, appended with the command that made it.
conv=$(cargo test --release --quiet --test convergence -- --nocapture 2>&1 | grep -E '^(spp|log-log)')
{
  echo "## Convergence of the one-bounce estimate"
  echo
  echo "The ring's indirect light (48×48, the caustic included) at 4, 16 and 64 spp, 4 seeds each,"
  echo "against 2048 spp with an independent seed (its own variance subtracted), from"
  echo "\`cargo test --release --test convergence -- --nocapture\`. RMSE shrinks as 1/√spp (slope −½):"
  echo
  echo '```'
  echo "$conv"
  echo '```'
} >> "$out/README.md"
echo "wrote $out/README.md"
