#!/usr/bin/env bash
# build.sh - the thin wrapper behind README's two commands (and CI's sanitizer run).
#   ./build.sh main       install what is missing, build (Release, build/), run the main job
#   ./build.sh test       install what is missing, build (build/), run every test through CTest
#                         (with the glTF validator's npm package in build/npm when npm is there)
#   ./build.sh sanitize   the same tests built with -DMBR_SANITIZE=ON in build-sanitize/
#   ./build.sh gallery    build, then regenerate the README's pictures in docs/images/
set -euo pipefail
cd "$(dirname "$0")"

jobs=$(nproc 2>/dev/null || echo 2)

install_missing() {
    local packages=(cmake g++ make catch2 libstb-dev)
    local missing=()
    for p in "${packages[@]}"; do
        dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
    done
    if ((${#missing[@]})); then
        echo "build.sh: installing ${missing[*]}"
        local sudo=""
        [ "$(id -u)" -eq 0 ] || sudo=sudo
        $sudo apt-get update
        $sudo apt-get install -y "${missing[@]}"
    fi
}

# The Khronos glTF validator (npm package gltf-validator) for the CTest test gltf_validator
# (test/validate_export.sh), installed into DIR/npm when node and npm exist and it is not there
# yet. A failure is tolerated: the test is then reported as skipped.
install_gltf_validator() {  # dir
    local dir=$1
    [ -d "$dir/npm/node_modules/gltf-validator" ] && return 0
    if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
        echo "build.sh: node or npm is missing: the glTF validator test will be skipped"
        return 0
    fi
    mkdir -p "$dir/npm"
    npm install --prefix "$dir/npm" --no-audit --no-fund gltf-validator ||
        echo "build.sh: npm could not install gltf-validator: the glTF validator test will be skipped"
}

configure_and_build() {  # dir, extra cmake arguments...
    local dir=$1
    shift
    cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release "$@"
    cmake --build "$dir" -j "$jobs"
}

main_job() {
    mkdir -p out
    echo "== The Cornell box: solved and rendered -> out/cornell_box.png =="
    build/examples/mbr render examples/scenes/cornell_box.scene -o out/cornell_box.png
    echo
    echo "== Tables 1, 2 and 3 computed now, beside the paper's values =="
    build/examples/mbr tables
    echo
    echo "== Figure 1: DN_3 and DN_4 -> out/figure1_dual_basis.png =="
    build/examples/figure1_dual_basis -o out/figure1_dual_basis.png
    echo
    echo "== Figure 7: error images -> out/figure7a_parallel.png, out/figure7b_perpendicular.png =="
    build/examples/figure7_error_images -o out
}

# The README's gallery, docs/images/: every picture the examples write, regenerated from scratch
# (the room, solved with shadows to its shot limit, takes most of the time: minutes).
gallery() {
    local dir=docs/images tmp
    mkdir -p "$dir"
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' RETURN
    build/examples/mbr render examples/scenes/cornell_box.scene -o "$dir/cornell_box.png" --quiet
    build/examples/mbr render examples/scenes/cornell_box.scene -o "$dir/cornell_box_quadtree.png" \
        --quadtree --quiet
    build/examples/figure1_dual_basis -o "$dir/figure1_dual_basis.png"
    build/examples/figure7_error_images -o "$tmp"
    cp "$tmp/figure7a_parallel.png" "$tmp/figure7b_perpendicular.png" "$dir/"
    build/examples/figure8_coplanar_strips -o "$dir/figure8_coplanar_strips.png"
    build/examples/shadow_transfer --config square --max-shadow-depth 6 -o "$tmp"
    cp "$tmp"/*square*.png "$dir/"
    build/examples/figure10_room -o "$dir/figure10_room.png"
    ls -l "$dir"
    # The tutorial (docs/tutorial/): every chapter program at its defaults, its images and its
    # printed output beside the pages that embed them.
    local program name
    mkdir -p docs/tutorial/images docs/tutorial/output
    for program in build/examples/tutorial_*; do
        [ -x "$program" ] || continue
        name=$(basename "$program")
        echo "== $name =="
        "$program" -o docs/tutorial/images >"$tmp/$name.txt"
        mv "$tmp/$name.txt" "docs/tutorial/output/$name.txt"
    done
}

case "${1:-}" in
    main)
        install_missing
        configure_and_build build
        main_job
        ;;
    test)
        install_missing
        configure_and_build build
        install_gltf_validator build
        (cd build && ctest --output-on-failure -j "$jobs")
        ;;
    gallery)
        install_missing
        configure_and_build build
        gallery
        ;;
    sanitize)
        install_missing
        configure_and_build build-sanitize -DMBR_SANITIZE=ON
        install_gltf_validator build-sanitize
        (cd build-sanitize && ctest --output-on-failure -j "$jobs")
        ;;
    *)
        echo "usage: ./build.sh main|test|sanitize|gallery" >&2
        exit 2
        ;;
esac
