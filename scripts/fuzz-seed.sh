#!/usr/bin/env bash
# Fills fuzz/corpus/<target>/ with the seed inputs of the fuzz targets (see docs/robustness.md,
# "Fuzzing"). The corpus is not committed (it grows while fuzzing); run this once before the
# first `cargo fuzz run`. Existing corpus files are kept.
#
# Seeds: the real inputs (scenes/*.toml, scenes/prt/*.toml, the small models of scenes/models/
# as shipped and decompressed, the environment maps of scenes/envmaps/), the same models
# re-encoded as ASCII PLY, OBJ and GLB, hand-made minimal files of every format
# (scripts/fuzz-seed.py), tiny EXRs written by the crate's own EXR writers (through
# `interreflect convert-envmap`), and every stored regression input (tests/data/fuzz/<target>/).
#
# Needs python3 and gzip; builds the interreflect binary (release) for the EXR seeds.
set -euo pipefail
cd "$(dirname "$0")/.."

out=fuzz/corpus
targets=(scene_toml ply obj gltf exr hdr mesh_clean)
for t in "${targets[@]}"; do
    mkdir -p "$out/$t"
done

# Hand-made minimal files, and the small models re-encoded in the other formats.
python3 scripts/fuzz-seed.py "$out" scenes/models/teapot.ply.gz scenes/models/bunny.ply.gz

# Real scene files (their mesh and map references resolve to missing files while fuzzing).
cp scenes/*.toml scenes/prt/*.toml "$out/scene_toml/"

# Real meshes: as shipped (gzip, detected by signature) and decompressed.
for m in teapot bunny dragon-11k; do
    cp "scenes/models/$m.ply.gz" "$out/ply/$m.ply.gz"
    gzip -dc "scenes/models/$m.ply.gz" > "$out/ply/$m.ply"
done

# Real environment maps, and tiny maps written by the crate's own writers: half floats with
# PIZ compression (write_exr_half) and 32-bit floats with ZIP compression (write_exr).
cp scenes/envmaps/*.exr "$out/exr/"
cargo build --release --quiet --bin interreflect
bin="${CARGO_TARGET_DIR:-target}/release/interreflect"
"$bin" convert-envmap scenes/envmaps/sunrise.exr "$out/exr/tiny-half-8x4.exr" --width 8 > /dev/null 2>&1
"$bin" convert-envmap scenes/envmaps/courtyard.exr "$out/exr/tiny-float-4x2.exr" --width 4 --float > /dev/null 2>&1

# Every stored regression input (crashes found earlier and hand-made nasty inputs).
for t in "${targets[@]}"; do
    if [ -d "tests/data/fuzz/$t" ]; then
        cp tests/data/fuzz/"$t"/* "$out/$t/"
    fi
done

for t in "${targets[@]}"; do
    printf '%-11s %4d files %8d bytes\n' "$t" "$(ls "$out/$t" | wc -l)" "$(cat "$out/$t"/* | wc -c)"
done
