#!/usr/bin/env bash
# Measures the approximate visibility and writes results/visibility/ (numbers in
# results/visibility/numbers.md; the discussion is results/visibility.md):
# - sg with variance shadow maps for the light (--visibility vsm) against sg with shadow rays
#   (--visibility exact), on ring, bunny and dragon at 64 px wide, 16 spp: the indirect light
#   alone and the whole image (direct + indirect), with error maps;
# - the indirect light of both against the path-traced reference of results/sg-cpu/ (rendered
#   by scripts/sg-cpu-results.sh; skipped when missing);
# - --visibility approx (VSM + VPLs with imperfect shadow maps; experimental) against exact,
#   indirect light;
# - the time the shadow maps and VPLs take.
#
#   scripts/visibility-results.sh     (about 18 min)
#
# Shadow maps are the CPU twin's (--device cpu, a ray per texel), as when these results were
# first made; the GPU's rasterised maps agree texel for texel except on silhouettes
# (tests/gpu_vsm.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
out=results/visibility
refs=results/sg-cpu
bin="${INTERREFLECT:-target/release/interreflect}"
mkdir -p "$out"
if [ -z "${INTERREFLECT:-}" ]; then cargo build --release --quiet; fi
for scene in ring bunny dragon; do
  for vis in exact vsm; do
    echo "== $scene, --visibility $vis"
    "$bin" render "scenes/$scene.toml" --method sg --visibility "$vis" --device cpu --indirect-only \
      --width 64 --spp 16 --output "$out/$scene-indirect-$vis.exr" --quiet
    "$bin" render "scenes/$scene.toml" --method sg --visibility "$vis" --device cpu \
      --width 64 --spp 16 --output "$out/$scene-full-$vis.exr" --quiet
    if [ -f "$refs/$scene-reference-s1.exr" ]; then
      "$bin" compare "$out/$scene-indirect-$vis.exr" "$refs/$scene-reference-s1.exr" --json \
        > "$out/$scene-indirect-$vis-vs-reference.json" 2>/dev/null
    fi
  done
  echo "== $scene, --visibility approx (indirect)"
  "$bin" render "scenes/$scene.toml" --method sg --visibility approx --device cpu --indirect-only \
    --width 64 --spp 16 --output "$out/$scene-indirect-approx.exr" --quiet
  "$bin" compare "$out/$scene-indirect-approx.exr" "$out/$scene-indirect-exact.exr" --json \
    --error-map "$out/$scene-indirect-approx-error.png" > "$out/$scene-indirect-approx-vs-exact.json" 2>/dev/null
  for part in indirect full; do
    "$bin" compare "$out/$scene-$part-vsm.exr" "$out/$scene-$part-exact.exr" --json \
      --error-map "$out/$scene-$part-vsm-error.png" > "$out/$scene-$part-vsm-vs-exact.json" 2>/dev/null
  done
done
python3 - "$out" <<'PY'
import json, os, sys
out = sys.argv[1]
def j(name):
    with open(os.path.join(out, name)) as f:
        return json.load(f)
approx = ["| scene | indirect: approx vs exact | VPLs + maps (s) | render (s) |", "|---|---|---|---|"]
for scene in ["ring", "bunny", "dragon"]:
    a, la = j(f"{scene}-indirect-approx-vs-exact.json"), j(f"{scene}-indirect-approx.json")
    approx.append(f"| {scene} | {a['rel_rmse']*100:.1f} % | {la['sg']['seconds']['vpls']:.2f} | {la['seconds']['render']:.1f} |")
rows = ["| scene | indirect: vsm vs exact | whole image: vsm vs exact | indirect vs reference: exact / vsm | shadow maps (s) | render exact / vsm (s) |",
        "|---|---|---|---|---|---|"]
for scene in ["ring", "bunny", "dragon"]:
    ind, full = j(f"{scene}-indirect-vsm-vs-exact.json"), j(f"{scene}-full-vsm-vs-exact.json")
    le, lv = j(f"{scene}-full-exact.json"), j(f"{scene}-full-vsm.json")
    ref = "—"
    if os.path.exists(os.path.join(out, f"{scene}-indirect-exact-vs-reference.json")):
        re_, rv = j(f"{scene}-indirect-exact-vs-reference.json"), j(f"{scene}-indirect-vsm-vs-reference.json")
        ref = f"{re_['rel_rmse']*100:.1f} % / {rv['rel_rmse']*100:.1f} %"
    rows.append(f"| {scene} | {ind['rel_rmse']*100:.1f} % | {full['rel_rmse']*100:.1f} % | {ref} | "
                f"{lv['sg']['seconds']['shadow_maps']:.2f} | {le['seconds']['render']:.1f} / {lv['seconds']['render']:.1f} |")
with open(os.path.join(out, "numbers.md"), "w") as f:
    f.write("# Approximate visibility: measured numbers\n\nWritten by `scripts/visibility-results.sh`; discussion in `results/visibility.md`. "
            "sg at 64 px wide, 16 spp, default settings; rel_rmse.\n\n")
    f.write("\n".join(rows) + "\n\n## --visibility approx (VSM + VPLs with imperfect shadow maps; experimental)\n\n")
    f.write("\n".join(approx) + "\n")
print(open(os.path.join(out, "numbers.md")).read())
PY
