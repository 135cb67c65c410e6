#!/usr/bin/env bash
# Measures the CPU SG renderer and writes results/sg-cpu/ (numbers in results/sg-cpu/numbers.md;
# the discussion is results/sg-cpu.md):
# - converged indirect-only references at 256 px wide, REF_SPP spp (default 4096), two seeds,
#   cached as results/sg-cpu/<scene>-reference-s{1,2}.exr (git-ignored; the second seed
#   measures their noise);
# - sg (cut per pixel and per vertex) and sg-brute at 64 px wide, 16 spp, indirect only,
#   compared with the reference box-filtered 4×4 (`interreflect compare` does this);
# - sg against sg-brute on the 202k-triangle dragon at 32 px wide, 1 spp (brute force is slow);
# - frame time and tree build time against triangle count (dragon 11k, 48k, 202k, 871k; the
#   871k model is fetched by scripts/fetch-models.sh and skipped when missing).
#
#   scripts/sg-cpu-results.sh     (about 45 min, plus about 20 min per scene without references;
#                                  KEEP_BRUTE=1 reuses the sg-brute renders: about 5 min)
set -euo pipefail
cd "$(dirname "$0")/.."
ref_spp="${REF_SPP:-4096}"
out=results/sg-cpu
bin="${INTERREFLECT:-target/release/interreflect}"
mkdir -p "$out"
if [ -z "${INTERREFLECT:-}" ]; then cargo build --release --quiet; fi
for scene in ring bunny dragon; do
  for seed in 1 2; do
    ref="$out/$scene-reference-s$seed.exr"
    if [ ! -f "$ref" ]; then
      echo "== $scene reference, seed $seed ($ref_spp spp)"
      "$bin" render "scenes/$scene.toml" --method reference --indirect-only --width 256 \
        --spp "$ref_spp" --seed "$seed" --output "$ref"
    fi
  done
  "$bin" compare "$out/$scene-reference-s2.exr" "$out/$scene-reference-s1.exr" --json \
    > "$out/$scene-reference-noise.json"
  for method in sg sg-vertex sg-brute; do
    case $method in
      sg) args=(--method sg --visibility exact --cut pixel) ;;
      sg-vertex) args=(--method sg --visibility exact --cut vertex) ;;
      sg-brute) args=(--method sg-brute --visibility exact) ;;
    esac
    # Brute force on the 202k dragon at 64 px would take an hour: measured at 32 px below.
    if [ "$scene" = dragon ] && [ "$method" = sg-brute ]; then continue; fi
    # KEEP_BRUTE=1 keeps existing sg-brute renders (15-20 min each; the cut does not change them).
    if [ "$method" = sg-brute ] && [ "${KEEP_BRUTE:-0}" = 1 ] && [ -f "$out/$scene-$method.exr" ]; then
      echo "== $scene $method (kept)"
    else
      echo "== $scene $method"
      "$bin" render "scenes/$scene.toml" "${args[@]}" --indirect-only --width 64 --spp 16 \
        --output "$out/$scene-$method.exr" --quiet
    fi
    "$bin" compare "$out/$scene-$method.exr" "$out/$scene-reference-s1.exr" --json \
      --error-map "$out/$scene-$method-error.png" > "$out/$scene-$method-metrics.json"
  done
done
echo "== dragon sg vs sg-brute (32 px, 1 spp)"
"$bin" render scenes/dragon.toml --method sg --visibility exact --indirect-only --width 32 --spp 1 \
  --output "$out/dragon32-sg.exr" --quiet
if [ "${KEEP_BRUTE:-0}" != 1 ] || [ ! -f "$out/dragon32-sg-brute.exr" ]; then
  "$bin" render scenes/dragon.toml --method sg-brute --visibility exact --indirect-only --width 32 --spp 1 \
    --output "$out/dragon32-sg-brute.exr" --quiet
fi
"$bin" compare "$out/dragon32-sg.exr" "$out/dragon32-sg-brute.exr" --json \
  --error-map "$out/dragon32-error.png" > "$out/dragon32-metrics.json"
for size in 11k 48k 202k 871k; do
  scene=scenes/dragon-$size.toml
  [ "$size" = 202k ] && scene=scenes/dragon.toml
  if [ "$size" = 871k ] && [ ! -f scenes/models/dragon-871k.ply.gz ]; then
    echo "skipping dragon-871k (run scripts/fetch-models.sh)"
    continue
  fi
  echo "== frame time, dragon $size"
  "$bin" render "$scene" --method sg --visibility exact --indirect-only --width 64 --spp 1 \
    --output "$out/scaling-$size.exr" --quiet
done
python3 - "$out" <<'PY'
import json, os, sys
out = sys.argv[1]
def j(name):
    with open(os.path.join(out, name)) as f:
        return json.load(f)
lines = ["| scene | method | rel_rmse | relMSE | SSIM | FLIP | render (s) | cut mean / max | nodes / px | triangle integrations / px |",
         "|---|---|---|---|---|---|---|---|---|---|"]
noise = []
for scene in ["ring", "bunny", "dragon"]:
    noise.append(f"| {scene} | {j(f'{scene}-reference-noise.json')['rel_rmse']*100:.1f} % |")
    for m in ["sg", "sg-vertex", "sg-brute"]:
        if not os.path.exists(os.path.join(out, f"{scene}-{m}.json")):
            continue
        log, met = j(f"{scene}-{m}.json"), j(f"{scene}-{m}-metrics.json")
        sg = log["sg"]
        cut = "—" if m == "sg-brute" else f"{sg['cut_size_mean']:.0f} / {sg['cut_size_max']}"
        lines.append(f"| {scene} | {m} | {met['rel_rmse']*100:.1f} % | {met['relmse']:.2e} | {met['ssim']:.3f} | {met['flip']:.3f} | "
                     f"{log['seconds']['render']:.1f} | {cut} | {sg['nodes_evaluated_per_pixel']:.0f} | {sg['leaves_evaluated_per_pixel']:.0f} |")
a, b, m = j("dragon32-sg.json"), j("dragon32-sg-brute.json"), j("dragon32-metrics.json")
ts, tb = a["sg"]["seconds"]["shading"], b["sg"]["seconds"]["shading"]
scal = ["| model | reflector triangles | pieces | tree nodes | tree build (s) | lighting (s) | shading (s) | render (s) | cut mean |",
        "|---|---|---|---|---|---|---|---|---|"]
for size in ["11k", "48k", "202k", "871k"]:
    p = f"scaling-{size}.json"
    if not os.path.exists(os.path.join(out, p)):
        continue
    s = j(p); g = s["sg"]; t = g["seconds"]
    scal.append(f"| dragon-{size} | {g['reflector_triangles']:,} | {g['reflector_pieces']:,} | {g['tree_nodes']:,} | {t['tree']:.3f} | {t['lighting']:.3f} | {t['shading']:.2f} | {s['seconds']['render']:.2f} | {g['cut_size_mean']:.0f} |")
with open(os.path.join(out, "numbers.md"), "w") as f:
    f.write("# SG renderer on the CPU: measured numbers\n\nWritten by `scripts/sg-cpu-results.sh`; discussion in `results/sg-cpu.md`.\n\n")
    f.write("## Indirect light against the reference (64 px wide, 16 spp; reference 256 px box-filtered)\n\n")
    f.write("\n".join(lines) + "\n\n")
    f.write("Reference noise: rel_rmse between the two seeds at 256 px (one seed's own noise is this / √2, and the 4×4 box filter of the comparison divides it by about 4 more):\n\n| scene | seed 1 vs seed 2 |\n|---|---|\n" + "\n".join(noise) + "\n\n")
    f.write("## sg against sg-brute on the 202k-triangle dragon (32×24, 1 spp, indirect only)\n\n")
    f.write(f"rel_rmse {m['rel_rmse']*100:.2f} %, relMSE {m['relmse']:.2e}; shading {ts:.2f} s (sg) against {tb:.1f} s (sg-brute): "
            f"**{tb/ts:.0f}× faster**; whole render {a['seconds']['render']:.2f} s against {b['seconds']['render']:.1f} s. "
            f"Cut size mean {a['sg']['cut_size_mean']:.0f}, max {a['sg']['cut_size_max']}.\n\n")
    f.write("## Frame time against triangle count (64×48, 1 spp, indirect only, cut per pixel)\n\n")
    f.write("\n".join(scal) + "\n")
print(open(os.path.join(out, "numbers.md")).read())
PY
