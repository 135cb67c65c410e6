#!/usr/bin/env bash
# Drives `interreflect view` on ring, bunny and dragon as a user would, under a virtual X
# display, and writes results/viewer/ (window screenshots and the frame log of each scene;
# the discussion is results/viewer.md). With no argument (or `sg`) it runs sg on
# scenes/<scene>.toml; with `prt` it runs prt on scenes/prt/<scene>-glossy-sun.toml (the files
# are then prefixed prt-; the transfer is computed afresh, in a cache of its own that is
# removed afterwards, so that its time is measured). For each scene:
# - waits for the first full-quality frame and takes a screenshot;
# - orbits with the mouse for 20 s (left drag), takes a screenshot while moving, releases and
#   waits for the full-quality frame;
# - moves the light for 20 s (L switches the left drag to light 0), likewise.
# The viewer logs every frame it shows with its size, time and stages; numbers.md collects the
# moving and still frame times from those logs.
#
# Needs xvfb-run (scripts/install-deps.sh), xdotool and imagemagick (`apt-get install xdotool
# imagemagick`). About 12 min for sg, 5 min for prt (2 of them the dragon's transfer).
#   scripts/viewer-results.sh [sg|prt]
set -euo pipefail
cd "$(dirname "$0")/.."
for tool in xvfb-run xdotool import; do
  command -v "$tool" >/dev/null || { echo "$tool is missing: apt-get install xvfb xdotool imagemagick" >&2; exit 1; }
done
cargo build --release --quiet
out=results/viewer
mkdir -p "$out"

if [ "${1:-}" != "--inside" ]; then
  method=${1:-sg}
  case "$method" in
    sg) prefix="" ;;
    prt) prefix="prt-" ;;
    *) echo "usage: $0 [sg|prt]" >&2; exit 2 ;;
  esac
  for scene in ring bunny dragon; do
    echo "== $method on $scene"
    xvfb-run -a -s '-screen 0 1280x800x24' "$0" --inside "$scene" "$method" "$prefix"
  done
  python3 - "$out" "$method" "$prefix" <<'PY'
import re, sys, statistics
out, method, prefix = sys.argv[1:4]
rows = []
for scene in ["ring", "bunny", "dragon"]:
    phase = "start"
    times = {"start": [], "orbit-moving": [], "orbit-still": [], "light-moving": [], "light-still": []}
    size = {}
    transfer = None
    for line in open(f"{out}/{prefix}{scene}-log.txt"):
        if line.startswith("--- orbit"):
            phase = "orbit"
            continue
        if line.startswith("--- light"):
            phase = "light"
            continue
        t = re.match(r"view: prt: transfer computed in ([0-9.]+) s", line)
        if t:
            transfer = float(t.group(1))
        m = re.match(r"view: " + method + r" (\d+)×(\d+) at \d+ spp(, moving)?: ([0-9.]+) s", line)
        if not m:
            continue
        moving = m.group(3) is not None
        key = "start" if phase == "start" else f"{phase}-{'moving' if moving else 'still'}"
        times[key].append(float(m.group(4)))
        size["moving" if moving else "still"] = f"{m.group(1)}×{m.group(2)}"
    def secs(x):
        return f"{x:.2f} s" if x >= 1 else f"{x * 1000:.0f} ms"
    def med(v):
        return f"{secs(statistics.median(v))} ({len(v)})" if v else "—"
    rows.append((scene, size.get("still", "?"), size.get("moving", "?"), med(times["start"]),
                 med(times["orbit-moving"]), med(times["orbit-still"]),
                 med(times["light-moving"]), med(times["light-still"]),
                 (statistics.median(times["orbit-moving"]) / statistics.median(times["orbit-still"]))
                 if times["orbit-moving"] and times["orbit-still"] else None,
                 (statistics.median(times["light-moving"]) / statistics.median(times["light-still"] or times["start"]))
                 if times["light-moving"] and (times["light-still"] or times["start"]) else None,
                 transfer))
with open(f"{out}/{prefix}numbers.md", "w") as f:
    f.write(f"# The viewer: measured frame times of {method}\n\nWritten by `scripts/viewer-results.sh {method}` from the viewer's frame log; "
            f"median frame time (number of frames) of {method} in each phase.\n\n")
    f.write("| scene | still size | moving size | first frame | orbiting: moving | orbiting: still | light: moving | light: still | moving ÷ still, orbit | moving ÷ still, light |\n")
    f.write("|---|---|---|---|---|---|---|---|---|---|\n")
    for r in rows:
        ratio = lambda x: f"{x:.3f}" if x is not None else "—"
        f.write(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]} | {r[5]} | {r[6]} | {r[7]} | {ratio(r[8])} | {ratio(r[9])} |\n")
    if any(r[10] is not None for r in rows):
        f.write("\nprt's transfer, computed on its own thread before the first frame (the frames before it are pending): "
                + ", ".join(f"{r[0]} {r[10]:.1f} s" for r in rows if r[10] is not None)
                + " (a session caches it, and the next one reads it; this script measures it afresh).\n")
PY
  cat "$out/${prefix}numbers.md"
  exit 0
fi

# Inside the virtual display: one scene.
scene=$2 method=$3 prefix=$4
log="$out/$prefix$scene-log.txt"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
: >"$log"
if [ "$method" = prt ]; then
  cache=results/cache/viewer-results-prt; rm -rf "$cache"
  target/release/interreflect view "scenes/prt/$scene-glossy-sun.toml" --method prt \
    --prt-cache "$cache" >>"$log" 2>&1 &
else
  target/release/interreflect view "scenes/$scene.toml" >>"$log" 2>&1 &
fi
pid=$!
trap 'kill $pid 2>/dev/null || true; [ -z "${cache:-}" ] || rm -rf "$cache"' EXIT
full() { grep -v moving "$log" | grep -c 'spp: ' || true; }
waitfull() { for _ in $(seq 1 900); do [ "$(full)" -gt "$1" ] && return 0; sleep 1; done; echo "no full frame" >&2; exit 1; }
# The window at half size, in 256 colours: small enough to commit.
shot() { import -window root -crop 1024x640+0+0 -resize 50% -colors 256 "PNG8:$out/$prefix$scene-$1.png"; }
waitfull 0; sleep 1; shot still
# Keyboard input needs the focus (there is no window manager under Xvfb).
xdotool windowfocus --sync "$(xdotool search --name interreflect | head -1)"
n=$(full)
echo "--- orbit" >>"$log"
xdotool mousemove 650 330 mousedown 1
for _ in $(seq 1 100); do xdotool mousemove_relative -- 2 0; sleep 0.2; done
shot orbit-moving
xdotool mouseup 1
waitfull "$n"
n=$(full)
echo "--- light" >>"$log"
xdotool mousemove 650 330 key l
sleep 0.5
xdotool mousedown 1
for _ in $(seq 1 100); do xdotool mousemove_relative -- 0 -1; sleep 0.2; done
xdotool mouseup 1
waitfull "$n"; sleep 1; shot light-still
