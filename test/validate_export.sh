#!/usr/bin/env bash
# test/validate_export.sh - the CTest test gltf_validator (test/CMakeLists.txt): mbr export writes
# the Cornell box and the room as .glb, with and without lightmaps, into a temporary folder, and
# the Khronos glTF validator (test/validate_gltf.js, the npm package gltf-validator) checks them.
#
#   test/validate_export.sh MBR_PROGRAM SOURCE_DIR NPM_DIR
#
# NPM_DIR is where `npm install --prefix NPM_DIR gltf-validator` put the package (build.sh test
# does it, into build/npm). Exit status: 0 when every file validates without errors, 1 when one
# has errors or an export fails, 77 (CTest's SKIP_RETURN_CODE: reported as skipped, not passed)
# when node or the package is missing, found before any export is run.
set -euo pipefail

if (($# != 3)); then
    echo "usage: $0 MBR_PROGRAM SOURCE_DIR NPM_DIR" >&2
    exit 2
fi
mbr=$1 src=$2 npm_dir=$3
validate="$src/test/validate_gltf.js"

if ! command -v node >/dev/null 2>&1; then
    echo "validate_export.sh: node is not installed: the glTF validator test is skipped" >&2
    exit 77
fi
# The module must load (from NPM_DIR, else the usual way), as validate_gltf.js loads it.
status=0
node -e "const p = require('path').resolve(process.argv[1], 'node_modules', 'gltf-validator');
         try { require(p); } catch (e) { require('gltf-validator'); }" "$npm_dir" \
    >/dev/null 2>&1 || status=$?
if ((status != 0)); then
    echo "validate_export.sh: the npm package gltf-validator is not in $npm_dir/node_modules" \
        "(npm install --prefix $npm_dir gltf-validator; build.sh test does it): skipped" >&2
    exit 77
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Fast solves: the validator checks the files' structure, not the radiosity's accuracy.
fast=(--shots 2 --max-depth 4 --quiet)
"$mbr" export "$src/examples/scenes/cornell_box.scene" -o "$tmp/cornell_box.glb" "${fast[@]}" \
    --save-solution "$tmp/cornell_box.solution"
"$mbr" export "$src/examples/scenes/cornell_box.scene" -o "$tmp/cornell_box_lightmaps.glb" \
    --load-solution "$tmp/cornell_box.solution" --lightmaps 256 --quiet
"$mbr" export "$src/examples/scenes/room.scene" -o "$tmp/room.glb" "${fast[@]}" \
    --shadows none --save-solution "$tmp/room.solution"
"$mbr" export "$src/examples/scenes/room.scene" -o "$tmp/room_lightmaps.glb" \
    --load-solution "$tmp/room.solution" --lightmaps 512 --exposure 2 --quiet

status=0
node "$validate" "$npm_dir" "$tmp"/*.glb || status=$?
exit "$status"
