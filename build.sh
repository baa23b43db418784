#!/usr/bin/env bash
# build.sh - the thin wrapper behind README's two commands (and CI's sanitizer run).
#   ./build.sh main       install what is missing, build (Release, build/), run the main job
#   ./build.sh test       install what is missing, build (build/), run every test through CTest
#   ./build.sh sanitize   the same tests built with -DMBR_SANITIZE=ON in build-sanitize/
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

configure_and_build() {  # dir, extra cmake arguments...
    local dir=$1
    shift
    cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release "$@"
    cmake --build "$dir" -j "$jobs"
}

main_job() {
    mkdir -p out
    echo "== Table 1: parallel squares, beside the paper =="
    build/examples/table1_parallel_squares
    echo
    echo "== Table 1 again with the rhombus radius near the paper's (14 cells) =="
    build/examples/table1_parallel_squares --rhombus-radius 14
    echo
    echo "== Table 2: perpendicular squares, beside the paper =="
    build/examples/table2_perpendicular_squares
    echo
    echo "== Table 2 again with the rhombus radius near the paper's (14 cells) =="
    build/examples/table2_perpendicular_squares --rhombus-radius 14
    echo
    echo "== Table 3: dual coefficients mu_{3;0,l} beside the paper =="
    build/examples/table3_dual_coefficients
    echo
    echo "== Figure 1: DN_3 and DN_4 -> out/figure1_dual_basis.png =="
    build/examples/figure1_dual_basis -o out/figure1_dual_basis.png
    if [ -x build/examples/figure7_error_images ]; then
        echo
        echo "== Figure 7: error images -> out/figure7a_parallel.png, out/figure7b_perpendicular.png =="
        build/examples/figure7_error_images -o out
    fi
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
        (cd build && ctest --output-on-failure -j "$jobs")
        ;;
    sanitize)
        install_missing
        configure_and_build build-sanitize -DMBR_SANITIZE=ON
        (cd build-sanitize && ctest --output-on-failure -j "$jobs")
        ;;
    *)
        echo "usage: ./build.sh main|test|sanitize" >&2
        exit 2
        ;;
esac
