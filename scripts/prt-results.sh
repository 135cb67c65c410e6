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
#   scripts/prt-results.sh     (about 30 min on 2 cores; REF_SPP=256 for a quick look;
#                              ONLY_COST=1 measures only the precompute and relighting costs;
#                              SCENES="dragon" limits it to some scenes)
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
for scene in ${SCENES:-ring bunny dragon}; do
  # ONLY_COST=1 skips the accuracy part (the references and the comparisons).
  for mat in diffuse glossy; do
    [ "${ONLY_COST:-0}" = 1 ] && break
    for light in env sun; do
      name="$scene-$mat-$light"
      toml="scenes/prt/$name.toml"
      # The PNG previews' exposure (the metrics use the linear EXRs): the dragon under the
      # courtyard map is bright.
      ev=0
      [ "$scene-$light" = dragon-env ] && ev=-1.5
      for kind in full direct; do
        ref="$out/$name-reference.exr"
        args=(--method reference)
        if [ "$kind" = direct ]; then ref="$out/$name-reference-direct.exr"; args=(--method direct); fi
        if [ ! -f "$ref" ]; then
          echo "== $name $kind reference ($ref_spp spp)"
          "$bin" render "$toml" "${args[@]}" --width "$width" --spp "$ref_spp" --seed 1 \
            --exposure "$ev" --output "$ref" --quiet
        fi
      done
      for bounces in 1 0; do
        for order in 8 5 3; do
          tag="$name-prt-o$order-b$bounces"
          echo "== $tag"
          "$bin" render "$toml" --method prt --order "$order" --bounces "$bounces" \
            --width "$width" --spp 4 --prt-cache "$cache" --exposure "$ev" --output "$out/$tag.exr" \
            --quiet
          ref="$out/$name-reference.exr"
          [ "$bounces" = 0 ] && ref="$out/$name-reference-direct.exr"
          "$bin" compare "$out/$tag.exr" "$ref" --json --error-map "$out/$tag-error.png" \
            > "$out/$tag-metrics.json"
        done
      done
      if [ "$light" = sun ]; then
        echo "== $name sg"
        "$bin" render "$toml" --method sg --visibility exact --width "$width" --spp 4 --output "$out/$name-sg.exr" \
          --quiet
        "$bin" compare "$out/$name-sg.exr" "$out/$name-reference.exr" --json \
          --error-map "$out/$name-sg-error.png" > "$out/$name-sg-metrics.json"
      fi
    done
  done
  # Precompute time and memory per order: the diffuse transfer with one bounce, computed afresh
  # (each order in an empty cache directory); then the order-8 transfer relit on the CPU.
  for order in 3 5 8; do
    echo "== $scene precompute, order $order"
    fresh="$cache/cost-$scene-$order"
    timed "$out/$scene-precompute-o$order" -- "$bin" render "scenes/prt/$scene-diffuse-env.toml" \
      --method prt --order "$order" --prt-cache "$fresh" --width "$width" \
      --output "$out/$scene-precompute-o$order.exr" --quiet
  done
  echo "== $scene relighting on the CPU"
  "$bin" render "scenes/prt/$scene-diffuse-env.toml" --method prt --order 8 --device cpu \
    --prt-cache "$cache/cost-$scene-8" --width "$width" --output "$out/$scene-relight-cpu.exr" \
    --quiet
done
# PNG previews kept in the repository: reference, PRT at orders 3 and 8 with one bounce, its
# error map, SG and its error map; the other orders keep their metrics only.
rm -f "$out"/*-prt-o5-*.png "$out"/*-b0.png "$out"/*-b0-error.png "$out"/*-o3-b1-error.png \
  "$out"/*-reference-direct.png
rm -f "$out"/*-precompute-o*.exr "$out"/*-precompute-o*.png "$out"/*-relight-cpu.exr \
  "$out"/*-relight-cpu.png
python3 scripts/prt-numbers.py "$out"
echo "wrote $out/numbers.md"
