#!/usr/bin/env bash
# Measures the peak memory (maximum resident set size, from /usr/bin/time) of every method on
# the dragon at 11k, 48k, 202k and 871k triangles next to the estimate `render` checks its
# memory budget with (src/memory.rs), and writes results/memory/numbers.csv and
# results/memory.md.
#
# Memory hardly depends on the image size or the sample count, so the renders are small:
# 128×96 at 1 spp (sg-brute at 16×12: it sums every triangle at every pixel), and PRT with 64
# transfer rays per vertex instead of 1024 (an environment-lit copy of the scene, no cache).
# The budget check is switched off (--memory-budget off) so that the estimate can be compared
# with what was measured. The 871k model is fetched by scripts/fetch-models.sh and skipped when
# missing.
#
#   scripts/memory-results.sh        (about 20 min on 2 cores; SIZES="11k 48k" for a subset)
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"
bin="${INTERREFLECT:-target/release/interreflect}"
out=results/memory
mkdir -p "$out"
if [ -z "${INTERREFLECT:-}" ]; then cargo build --release --quiet; fi
command -v /usr/bin/time >/dev/null || { echo "memory-results.sh: needs /usr/bin/time (apt install time)" >&2; exit 1; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$tmp}"
csv="$out/numbers.csv"
echo "model,triangles,method,seconds,peak_rss_mib,estimate_mib" > "$csv.tmp"
for size in ${SIZES:-11k 48k 202k 871k}; do
  scene=scenes/dragon-$size.toml
  [ "$size" = 202k ] && scene=scenes/dragon.toml
  if [ ! -f "scenes/models/dragon-$size.ply.gz" ]; then
    echo "skipping dragon-$size (run scripts/fetch-models.sh)"
    continue
  fi
  # The PRT variant: scenes/prt/dragon-diffuse-env.toml with this model and 64 rays per vertex.
  prt="$tmp/dragon-$size-prt.toml"
  sed -e "s#\.\./models/dragon-202k#$root/scenes/models/dragon-$size#" \
      -e "s#\.\./envmaps/#$root/scenes/envmaps/#" \
      -e "s#^samples = 1024#samples = 64#" scenes/prt/dragon-diffuse-env.toml > "$prt"
  for method in reference direct sg sg-vertex sg-vsm sg-approx sg-brute prt-cpu prt-gpu; do
    s="$scene"
    size_args=(--width 128 --height 96 --spp 1)
    case $method in
      reference | direct) args=(--method "$method") ;;
      sg) args=(--method sg --visibility exact --cut pixel) ;;
      sg-vertex) args=(--method sg --visibility exact --cut vertex) ;;
      sg-vsm) args=(--method sg --visibility vsm --device cpu --cut pixel) ;;
      sg-approx) args=(--method sg --visibility approx --device cpu --cut pixel) ;;
      sg-brute) args=(--method sg-brute --visibility exact); size_args=(--width 16 --height 12 --spp 1) ;;
      prt-cpu) args=(--method prt --device cpu --no-cache); s="$prt" ;;
      prt-gpu) args=(--method prt --device gpu --no-cache); s="$prt" ;;
    esac
    echo "== dragon-$size $method"
    /usr/bin/time -f '%M %e' -o "$tmp/time" "$bin" render "$s" "${args[@]}" "${size_args[@]}" \
      --memory-budget off --output "$tmp/out.exr" --quiet
    read -r kib secs < "$tmp/time"
    tris="$(python3 -c "import json;print(json.load(open('$tmp/out.json'))['triangles'])")"
    est="$(python3 -c "import json;print(json.load(open('$tmp/out.json'))['memory']['estimate_bytes'])")"
    echo "dragon-$size,$tris,$method,$secs,$((kib / 1024)),$((est / 1048576))" >> "$csv.tmp"
    tail -n 1 "$csv.tmp"
  done
done
mv "$csv.tmp" "$csv"
python3 - "$csv" results/memory.md <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
models = list(dict.fromkeys(r["model"] for r in rows))
methods = list(dict.fromkeys(r["method"] for r in rows))
def row(mod, m):
    return next((r for r in rows if r["model"] == mod and r["method"] == m), None)
tris = {mod: next(r["triangles"] for r in rows if r["model"] == mod and not r["method"].startswith("prt")) for mod in models}
out = ["# Peak memory of every method",
       "",
       "Written by `scripts/memory-results.sh`. Peak resident set size (`/usr/bin/time`, maximum RSS) of",
       "`interreflect render` on the dragon scenes, next to the estimate `render` checks against its",
       "memory budget before loading the meshes (`src/memory.rs`; `docs/robustness.md`). Renders are",
       "128×96 at 1 spp (sg-brute 16×12; memory hardly depends on the image at these sizes); prt is",
       "the environment-lit copy of the scene (`scenes/prt/dragon-diffuse-env.toml` with this model,",
       "finer floor and wall) at order 8 with one bounce and 64 rays a vertex, without the cache.",
       "",
       "Each cell: **measured** MiB / estimate MiB.",
       "",
       "| method | " + " | ".join(f"{m} ({int(tris[m]):,} triangles)" for m in models) + " |",
       "|---|" + "---|" * len(models)]
ratios = []
for m in methods:
    cells = []
    for mod in models:
        r = row(mod, m)
        if r is None:
            cells.append("—")
            continue
        meas, est = int(r["peak_rss_mib"]), int(r["estimate_mib"])
        ratios.append((est / max(meas, 1), m, mod))
        cells.append(f"**{meas}** / {est}")
    out.append(f"| {m} | " + " | ".join(cells) + " |")
lo, hi = min(ratios), max(ratios)
under = [r for r in ratios if r[0] < 1.0]
out += ["",
        f"Estimate ÷ measured: from {lo[0]:.2f} ({lo[1]}, {lo[2]}) to {hi[0]:.2f} ({hi[1]}, {hi[2]}).",
        ("Every estimate is above what was measured." if not under else
         "Estimates below what was measured: " + ", ".join(f"{m} on {mod} ({x:.2f})" for x, m, mod in under) + "."),
        "",
        "Wall-clock seconds of these runs are in `results/memory/numbers.csv` (taken at the same",
        "time as the memory, not on an idle machine: not timings to quote).",
        ""]
open(sys.argv[2], "w").write("\n".join(out))
print("\n".join(out))
PY
