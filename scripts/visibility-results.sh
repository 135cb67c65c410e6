#!/usr/bin/env bash
# Measures the approximate visibility and writes results/visibility/ (numbers in
# results/visibility/numbers.md; the discussion is results/visibility.md):
# - sg with variance shadow maps for the light (--visibility vsm) against sg with shadow rays
#   (--visibility exact), on ring, bunny and dragon at 64 px wide, 16 spp: the indirect light
#   alone and the whole image (direct + indirect), with error maps;
# - the indirect light of both against the path-traced reference of results/sg-cpu/ (rendered
#   by scripts/sg-cpu-results.sh; skipped when missing);
# - --visibility approx (VSM + visibility maps at tree nodes) against exact, indirect light, and
#   the paper's proxy (--node-maps 0: each node interpolates its 3 nearest VPLs' imperfect
#   shadow maps);
# - the time the shadow maps and the visibility maps take.
#
#   scripts/visibility-results.sh                 (about 20 min)
#   APPROX_ONLY=1 scripts/visibility-results.sh   (re-renders the approx runs only, and the
#                                                  exact indirect light where its EXR is missing;
#                                                  the vsm rows come from the committed logs)
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
    if [ -n "${APPROX_ONLY:-}" ]; then
      [ "$vis" = exact ] && [ ! -f "$out/$scene-indirect-exact.exr" ] &&
        "$bin" render "scenes/$scene.toml" --method sg --visibility exact --device cpu --indirect-only \
          --width 64 --spp 16 --output "$out/$scene-indirect-exact.exr" --quiet
      continue
    fi
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
  for maps in default 0; do
    name=approx; extra=()
    if [ "$maps" = 0 ]; then name=approx-vpl; extra=(--node-maps 0); fi
    echo "== $scene, --visibility approx (indirect), node maps: $maps"
    "$bin" render "scenes/$scene.toml" --method sg --visibility approx --device cpu --indirect-only \
      --width 64 --spp 16 "${extra[@]}" --output "$out/$scene-indirect-$name.exr" --quiet
    "$bin" compare "$out/$scene-indirect-$name.exr" "$out/$scene-indirect-exact.exr" --json \
      --error-map "$out/$scene-indirect-$name-error.png" > "$out/$scene-indirect-$name-vs-exact.json" 2>/dev/null
  done
  [ -n "${APPROX_ONLY:-}" ] && continue
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
approx = ["| scene | indirect: approx vs exact | the paper's proxy (--node-maps 0) vs exact | node maps | maps (s) | render: approx / proxy / exact (s) |",
          "|---|---|---|---|---|---|"]
for scene in ["ring", "bunny", "dragon"]:
    a, la = j(f"{scene}-indirect-approx-vs-exact.json"), j(f"{scene}-indirect-approx.json")
    p, lp = j(f"{scene}-indirect-approx-vpl-vs-exact.json"), j(f"{scene}-indirect-approx-vpl.json")
    le = j(f"{scene}-indirect-exact.json")
    approx.append(f"| {scene} | {a['rel_rmse']*100:.1f} % | {p['rel_rmse']*100:.1f} % | {la['sg']['node_maps']} | "
                  f"{la['sg']['seconds']['vpls']:.2f} | {la['seconds']['render']:.1f} / {lp['seconds']['render']:.1f} / "
                  f"{le['seconds']['render']:.1f} |")
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
    f.write("\n".join(rows) + "\n\n## --visibility approx (VSM + visibility maps at tree nodes), and the paper's proxy\n\n")
    f.write("\n".join(approx) + "\n")
print(open(os.path.join(out, "numbers.md")).read())
PY
