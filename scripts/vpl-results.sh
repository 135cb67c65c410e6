#!/usr/bin/env bash
# The VPL baseline against the SG method at equal time, and writes results/visibility/vpl/
# (numbers in results/visibility/vpl/numbers.md; the discussion is in results/visibility.md):
# - sg with its approximate visibility (--visibility approx: variance shadow maps and the
#   visibility maps at tree nodes) on ring, bunny and dragon, indirect light, 64 px wide, 16 spp;
# - vpl with the same visibility (VPL + ISM, the classic renderer) and with shadow rays, at
#   200, 800, 3200 and 12800 VPLs, same size and samples;
# - everything against the 4096-spp path-traced references of results/sg-cpu/ (rendered by
#   scripts/sg-cpu-results.sh, required), with error maps; "equal time" takes, for each scene,
#   the vpl run with the most VPLs that took no longer than sg.
# Renders run one after another, so sg and vpl share the machine's conditions.
#
#   scripts/vpl-results.sh     (about 15 min on 2 cores)
#   SG_ONLY=1 scripts/vpl-results.sh   (re-renders sg only and rebuilds the tables from the vpl
#                                       runs' committed logs and metrics; about 4 min)
set -euo pipefail
cd "$(dirname "$0")/.."
out=results/visibility/vpl
refs=results/sg-cpu
bin="${INTERREFLECT:-target/release/interreflect}"
mkdir -p "$out"
if [ -z "${INTERREFLECT:-}" ]; then cargo build --release --quiet; fi
counts="${COUNTS:-200 800 3200 12800}"
for scene in ring bunny dragon; do
  ref="$refs/$scene-reference-s1.exr"
  [ -f "$ref" ] || { echo "missing $ref: run scripts/sg-cpu-results.sh first" >&2; exit 1; }
  echo "== $scene sg approx"
  "$bin" render "scenes/$scene.toml" --method sg --visibility approx --device cpu --indirect-only \
    --width 64 --spp 16 --output "$out/$scene-sg-approx.exr" --quiet
  "$bin" compare "$out/$scene-sg-approx.exr" "$ref" --json \
    --error-map "$out/$scene-sg-approx-error.png" > "$out/$scene-sg-approx-metrics.json" 2>/dev/null
  [ -n "${SG_ONLY:-}" ] && continue
  for vis in approx exact; do
    for n in $counts; do
      name="$scene-vpl-$vis-$n"
      echo "== $scene vpl $vis, $n VPLs"
      "$bin" render "scenes/$scene.toml" --method vpl --visibility "$vis" --device cpu --vpls "$n" \
        --indirect-only --width 64 --spp 16 --output "$out/$name.exr" --quiet
      "$bin" compare "$out/$name.exr" "$ref" --json --error-map "$out/$name-error.png" \
        > "$out/$name-metrics.json" 2>/dev/null
    done
  done
done
python3 - "$out" "$counts" <<'PY'
import json, os, sys
out, counts = sys.argv[1], [int(c) for c in sys.argv[2].split()]
def j(name):
    with open(os.path.join(out, name)) as f:
        return json.load(f)
lines = ["| scene | method | VPLs | render (s) | rel_rmse | relMSE | FLIP |",
         "|---|---|---|---|---|---|---|"]
eq = ["| scene | sg approx: time, relMSE | vpl + ISM at equal time: VPLs, time, relMSE | relMSE vpl ÷ sg | vpl + shadow rays at equal time: VPLs, time, relMSE | relMSE vpl ÷ sg |",
      "|---|---|---|---|---|---|"]
for scene in ["ring", "bunny", "dragon"]:
    sg, sgm = j(f"{scene}-sg-approx.json"), j(f"{scene}-sg-approx-metrics.json")
    t_sg = sg["seconds"]["render"]
    def row(label, n, log, m):
        lines.append(f"| {scene} | {label} | {n} | {log['seconds']['render']:.1f} | {m['rel_rmse']*100:.1f} % | "
                     f"{m['relmse']:.3g} | {m['flip']:.3f} |")
    maps = sg["sg"].get("node_maps", 0)
    row("sg approx", f"— ({maps} node maps)" if maps else 200, sg, sgm)
    cells = [f"{t_sg:.1f} s, {sgm['relmse']:.3g}"]
    for vis in ["approx", "exact"]:
        best = None
        for n in counts:
            log, m = j(f"{scene}-vpl-{vis}-{n}.json"), j(f"{scene}-vpl-{vis}-{n}-metrics.json")
            row(f"vpl {vis}", n, log, m)
            if log["seconds"]["render"] <= t_sg:
                best = (n, log["seconds"]["render"], m["relmse"])
        if best is None:
            n = counts[0]
            log, m = j(f"{scene}-vpl-{vis}-{n}.json"), j(f"{scene}-vpl-{vis}-{n}-metrics.json")
            best = (n, log["seconds"]["render"], m["relmse"])
        cells += [f"{best[0]}, {best[1]:.1f} s, {best[2]:.3g}", f"**{best[2] / sgm['relmse']:.1f}×**"]
    eq.append(f"| {scene} | " + " | ".join(cells) + " |")
with open(os.path.join(out, "numbers.md"), "w") as f:
    f.write("# The VPL baseline against sg: measured numbers\n\nWritten by `scripts/vpl-results.sh`; discussion in "
            "`results/visibility.md`. Indirect light, 64 px wide, 16 spp, against the 4096-spp references.\n\n")
    f.write("## Equal time\n\n" + "\n".join(eq) + "\n\n## Every run\n\n" + "\n".join(lines) + "\n")
print(open(os.path.join(out, "numbers.md")).read())
PY
