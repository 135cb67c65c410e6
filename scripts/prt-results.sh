#!/usr/bin/env bash
# Measures SH diffuse PRT against the reference and writes results/prt/ (numbers in
# results/prt/numbers.md; the discussion is results/prt.md):
# - the scenes under scenes/prt/: ring, dragon and bunny, with Lambertian ("diffuse") or their
#   original glossy materials, lit by an environment map ("env") or a directional light ("sun");
# - references (direct light alone, and direct light + one bounce) at WIDTH px, REF_SPP spp,
#   cached as results/prt/<scene>-reference{,-direct}.exr (git-ignored);
# - PRT at orders 3, 5 and 8 with 0 and 1 bounces, each against the reference of the same light
#   (0 bounces: direct; 1 bounce: direct + one bounce);
# - the SG method on the directional-light scenes (it does not render environment maps);
# - precompute time and memory per order (the transfer computed afresh, --no-cache), and
#   relighting time on the GPU and on the CPU.
#
#   scripts/prt-results.sh     (about 40 min on 2 cores; REF_SPP=256 for a quick look)
set -euo pipefail
cd "$(dirname "$0")/.."
ref_spp="${REF_SPP:-1024}"
width="${WIDTH:-128}"
out=results/prt
bin="${INTERREFLECT:-target/release/interreflect}"
mkdir -p "$out"
if [ -z "${INTERREFLECT:-}" ]; then cargo build --release --quiet; fi
# Mesa wants a private runtime directory; without one it prints a harmless error.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
  XDG_RUNTIME_DIR="$(mktemp -d)"
  export XDG_RUNTIME_DIR
fi
cache="$(mktemp -d)"
trap 'rm -rf "$cache"' EXIT
timed() { # timed LOG -- command...: runs the command, appends its peak memory (kB) to LOG
  local log="$1"; shift 2
  /usr/bin/time -f '%M' -o "$log.rss" "$@"
}
for scene in ring bunny dragon; do
  for mat in diffuse glossy; do
    for light in env sun; do
      name="$scene-$mat-$light"
      toml="scenes/prt/$name.toml"
      for kind in full direct; do
        ref="$out/$name-reference.exr"
        args=(--method reference)
        if [ "$kind" = direct ]; then ref="$out/$name-reference-direct.exr"; args=(--method direct); fi
        if [ ! -f "$ref" ]; then
          echo "== $name $kind reference ($ref_spp spp)"
          "$bin" render "$toml" "${args[@]}" --width "$width" --spp "$ref_spp" --seed 1 \
            --output "$ref" --quiet
        fi
      done
      for bounces in 1 0; do
        for order in 8 5 3; do
          tag="$name-prt-o$order-b$bounces"
          echo "== $tag"
          "$bin" render "$toml" --method prt --order "$order" --bounces "$bounces" \
            --width "$width" --spp 4 --prt-cache "$cache" --output "$out/$tag.exr" --quiet
          ref="$out/$name-reference.exr"
          [ "$bounces" = 0 ] && ref="$out/$name-reference-direct.exr"
          "$bin" compare "$out/$tag.exr" "$ref" --json --error-map "$out/$tag-error.png" \
            > "$out/$tag-metrics.json"
        done
      done
      if [ "$light" = sun ]; then
        echo "== $name sg"
        "$bin" render "$toml" --method sg --width "$width" --spp 4 --output "$out/$name-sg.exr" \
          --quiet
        "$bin" compare "$out/$name-sg.exr" "$out/$name-reference.exr" --json \
          --error-map "$out/$name-sg-error.png" > "$out/$name-sg-metrics.json"
      fi
    done
  done
  # Precompute time and memory per order: the diffuse transfer with one bounce, computed afresh.
  for order in 3 5 8; do
    echo "== $scene precompute, order $order"
    timed "$out/$scene-precompute-o$order" -- "$bin" render "scenes/prt/$scene-diffuse-env.toml" \
      --method prt --order "$order" --no-cache --width "$width" \
      --output "$out/$scene-precompute-o$order.exr" --quiet
  done
  echo "== $scene relighting on the CPU"
  "$bin" render "scenes/prt/$scene-diffuse-env.toml" --method prt --order 8 --device cpu \
    --prt-cache "$cache" --width "$width" --output "$out/$scene-relight-cpu.exr" --quiet
done
rm -f "$out"/*-precompute-o*.exr "$out"/*-precompute-o*.png "$out"/*-relight-cpu.exr \
  "$out"/*-relight-cpu.png
python3 scripts/prt-numbers.py "$out"
echo "wrote $out/numbers.md"
