#!/usr/bin/env bash
# Install the brdf-atlas C library under a prefix, for C and C++ projects:
#
#     cargo build --release -p brdf-atlas-ffi
#     bash crates/ffi/install.sh PREFIX [BUILD_DIR]
#
# copies libbrdf_atlas_c.a and libbrdf_atlas_c.so from BUILD_DIR (default
# ${CARGO_TARGET_DIR:-target}/release) to PREFIX/lib, brdf_atlas.h and
# brdf_atlas.hpp to PREFIX/include, and writes PREFIX/lib/pkgconfig/brdf_atlas.pc
# from crates/ffi/brdf_atlas.pc.in. Then, with PKG_CONFIG_PATH=PREFIX/lib/pkgconfig:
#
#     c++ -std=c++17 tool.cpp $(pkg-config --cflags --libs brdf_atlas)
set -euo pipefail

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: $0 PREFIX [BUILD_DIR]" >&2
    exit 2
fi
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${2:-${CARGO_TARGET_DIR:-$root/target}/release}
mkdir -p "$1"
prefix=$(cd "$1" && pwd)
version=$(sed -n 's/^version = "\(.*\)"/\1/p' "$root/Cargo.toml" | head -n 1)

for lib in libbrdf_atlas_c.a libbrdf_atlas_c.so; do
    if [ ! -f "$build/$lib" ]; then
        echo "error: $build/$lib not found: run cargo build --release -p brdf-atlas-ffi first" >&2
        exit 1
    fi
done
mkdir -p "$prefix/lib/pkgconfig" "$prefix/include"
install -m 644 "$build/libbrdf_atlas_c.a" "$prefix/lib/"
install -m 755 "$build/libbrdf_atlas_c.so" "$prefix/lib/"
install -m 644 "$root/include/brdf_atlas.h" "$root/include/brdf_atlas.hpp" "$prefix/include/"
sed -e "s|@PREFIX@|$prefix|" -e "s|@VERSION@|$version|" "$here/brdf_atlas.pc.in" \
    > "$prefix/lib/pkgconfig/brdf_atlas.pc"
echo "installed brdf_atlas $version under $prefix"
