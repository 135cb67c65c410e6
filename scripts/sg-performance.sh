#!/usr/bin/env bash
# The SG frame-time table of results/sg-performance.md: ring, dragon and bunny at 256×192, 1 spp,
# indirect light only, with --visibility exact and approx, rendered by a baseline build and by
# this build back to back on the same machine, each against a 1024-spp path-traced reference.
#
#   scripts/sg-performance.sh [BASELINE_BINARY]
#
# CUT (environment, default "tile") is this build's --cut. BASELINE_BINARY defaults to a release
# build of commit 8bf32a1 made in a git worktree under target/baseline-8bf32a1 (several minutes
# the first time). NEW_BINARY (environment) is this build's binary; without it the script runs
# `cargo build --release` and uses target/release/interreflect. Work files (and the cached
# references) go to target/sg-performance/.
set -euo pipefail
cd "$(dirname "$0")/.."
BASE_COMMIT=8bf32a1
WORK=target/sg-performance
mkdir -p "$WORK"
if [ $# -ge 1 ]; then
  BASE="$1"
else
  TREE=target/baseline-$BASE_COMMIT
  if [ ! -x "$TREE/target/release/interreflect" ]; then
    [ -d "$TREE" ] || git worktree add --detach "$TREE" "$BASE_COMMIT"
    (cd "$TREE" && cargo build --release)
  fi
  BASE="$TREE/target/release/interreflect"
fi
if [ -n "${NEW_BINARY:-}" ]; then
  NEW="$NEW_BINARY"
else
  cargo build --release
  NEW=target/release/interreflect
fi
ARGS=(--method sg --indirect-only --width 256 --height 192 --spp 1 --quiet)
secs() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seconds"]["render"])' "$1"; }
err() { "$NEW" compare --json "$1" "$2" | python3 -c 'import json,sys; print(json.load(sys.stdin)["rel_rmse"])'; }
rows=()
for s in ring dragon bunny; do
  ref="$WORK/$s-reference.exr"
  [ -f "$ref" ] || "$NEW" render scenes/$s.toml --method reference --indirect-only \
    --width 256 --height 192 --spp 1024 --quiet -o "$ref"
  for v in exact approx; do
    "$BASE" render scenes/$s.toml "${ARGS[@]}" --visibility $v -o "$WORK/$s-$v-base.exr"
    "$NEW" render scenes/$s.toml "${ARGS[@]}" --cut "${CUT:-tile}" --visibility $v \
      -o "$WORK/$s-$v-new.exr"
    tb=$(secs "$WORK/$s-$v-base.json"); tn=$(secs "$WORK/$s-$v-new.json")
    eb=$(err "$WORK/$s-$v-base.exr" "$ref"); en=$(err "$WORK/$s-$v-new.exr" "$ref")
    rows+=("$s $v $tb $tn $eb $en")
  done
done
python3 - "$BASE_COMMIT" "${CUT:-tile}" "${rows[@]}" > results/sg-performance.md <<'PY'
import sys, platform
base, cut = sys.argv[1], sys.argv[2]
print("# SG frame time against the build of commit", base)
print()
print(f"Written by `scripts/sg-performance.sh`: `render scenes/<scene>.toml --method sg --indirect-only"
      f" --width 256 --height 192 --spp 1`, this build with `--cut {cut}`, both binaries run back to back on one machine"
      f" ({platform.machine()}, 2 threads); rel_rmse against a 1024-spp path-traced reference of the"
      " same settings. The render time is the run log's `seconds.render` (the whole frame: tree,"
      " lighting, visibility maps, cuts, shading).")
print()
print(f"| scene | visibility | {base} (s) | this build (s) | speed-up | rel_rmse {base} | rel_rmse this build | change (pp) |")
print("|---|---|---:|---:|---:|---:|---:|---:|")
for row in sys.argv[3:]:
    s, v, tb, tn, eb, en = row.split()
    tb, tn, eb, en = map(float, (tb, tn, eb, en))
    print(f"| {s} | {v} | {tb:.2f} | {tn:.2f} | {tb / tn:.1f}× | {100 * eb:.2f} % | {100 * en:.2f} % | {100 * (en - eb):+.2f} |")
rows = [r.split() for r in sys.argv[3:]]
fast = [r for r in rows if float(r[2]) / float(r[3]) >= 30]
close = [r for r in rows if float(r[5]) - float(r[4]) <= 0.005]
print()
print(f"The frame bar (issue 26) asks for at least 30× with at most +0.5 pp on every row: {len(fast)} of"
      f" {len(rows)} rows are 30× faster and {len(close)} of {len(rows)} are within +0.5 pp, so the bar is"
      f" {'met' if len(fast) == len(close) == len(rows) else '**not met**'}. Where the time goes and"
      " what is next: `docs/sg-performance.md`.")
PY
cat results/sg-performance.md
