#!/usr/bin/env bash
# Build the brdf-atlas plugin into BRDF Explorer (github wdas/brdf, qmake,
# Qt 5) out of tree: the upstream checkout is only read, never written.
#
#     cpp-plugin/apply.sh BRDF_SRC_DIR BUILD_DIR [LIBDIR]
#
# - copies the upstream tree (without .git) into BUILD_DIR, refreshing an
#   earlier copy (files keep their times: make rebuilds what changed and
#   what includes the five edited files);
# - copies the plugin's own files (the map widget, BRDFReconstructed, the
#   glue, the C headers) into BUILD_DIR/src/brdf/brdf-atlas/, and writes
#   brdf-atlas-paths.pri there with LIBDIR, the directory holding
#   libbrdf_atlas_c.so (default: this workspace's target/release, or
#   $CARGO_TARGET_DIR/release);
# - in the copy, inserts our own lines (each ends with "// brdf-atlas" or
#   "# brdf-atlas") after named anchor lines of five upstream files
#   (brdf.pro, BRDFMeasuredMERL.h, ParameterWindow.h, ParameterWindow.cpp,
#   MainWindow.cpp; the list below). Nothing is changed or removed. An
#   anchor that is missing or not unique stops the script with a message
#   (upstream moved: update the anchors here);
# - writes src/data/sphere.obj in the copy if upstream lacks it (some
#   mirrors do; the "Lit Object" view loads it).
# Then: cd BUILD_DIR && qmake && make. Running it again changes nothing
# that is not needed.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/.." && pwd)
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
    echo "usage: $0 BRDF_SRC_DIR BUILD_DIR [LIBDIR]" >&2
    exit 2
fi
upstream=$(cd "$1" && pwd) || { echo "apply.sh: $1: no such directory" >&2; exit 1; }
[ -f "$upstream/src/brdf/brdf.pro" ] || { echo "apply.sh: $upstream/src/brdf/brdf.pro: missing; is $1 a wdas/brdf checkout?" >&2; exit 1; }
build=$(realpath -m "$2")
case "$build/" in
    "$upstream"/*) echo "apply.sh: $build is inside $upstream; build out of tree (another directory), so the checkout stays untouched" >&2; exit 1 ;;
esac
mkdir -p "$build"
# A fresh copy of every upstream file (an earlier run's edits are replaced,
# then made again below); tar keeps the files' times.
(cd "$upstream" && tar --exclude=./.git -cf - .) | (cd "$build" && tar -xf -)
src=$build/src/brdf
libdir=${3:-${CARGO_TARGET_DIR:-$root/target}/release}
libdir=$(cd "$libdir" 2>/dev/null && pwd) || { echo "apply.sh: $libdir: no such directory (build the C library: cargo build --release -p brdf-atlas-ffi)" >&2; exit 1; }
for f in brdf.pro ParameterWindow.h ParameterWindow.cpp MainWindow.cpp BRDFMeasuredMERL.h; do
    [ -f "$src/$f" ] || { echo "apply.sh: $upstream/src/brdf/$f: missing; is $1 a wdas/brdf checkout?" >&2; exit 1; }
done
[ -f "$libdir/libbrdf_atlas_c.so" ] || echo "apply.sh: note: $libdir/libbrdf_atlas_c.so does not exist yet (cargo build --release -p brdf-atlas-ffi)" >&2

# Insertions: FILE, ANCHOR (a whole line, matched exactly after trimming
# trailing whitespace), LINE to insert after it. All checked before any write.
python3 - "$src" <<'PY'
import os, sys
src = sys.argv[1]
edits = [
    ("brdf.pro", "QT   += widgets opengl",
     "include(brdf-atlas/brdf-atlas.pri) # brdf-atlas"),
    ("BRDFMeasuredMERL.h", "    bool loadMERLData( const char* filename );",
     "    friend class BRDFReconstructed; // brdf-atlas: fills the table from memory"),
    ("ParameterWindow.h", "    void openBRDFFiles( std::vector<std::string> );",
     "    void addBRDF( BRDFBase* b ); // brdf-atlas: defined in brdf-atlas/AtlasGlue.cpp"),
    ("ParameterWindow.cpp", '#include "ParameterWindow.h"',
     '#include "brdf-atlas/AtlasGlue.h" // brdf-atlas'),
    ("ParameterWindow.cpp", "    mainLayout->addWidget( incidentPhiWidget, addIndex++, 0, 1, 2 );",
     "    brdfAtlasAttach( this, mainLayout, addIndex++ ); // brdf-atlas"),
    ("MainWindow.cpp", '#include "ParameterWindow.h"',
     '#include "brdf-atlas/AtlasGlue.h" // brdf-atlas'),
    ("MainWindow.cpp", "    connect( openBRDF, SIGNAL(triggered()), paramWnd, SLOT(openBRDFFromFile()) );",
     "    brdfAtlasAddMenuEntry( fileMenu, paramWnd ); // brdf-atlas"),
]
texts, errors, plan = {}, [], []
for name, anchor, line in edits:
    path = os.path.join(src, name)
    if name not in texts:
        with open(path, newline="") as f:
            texts[name] = f.read().split("\n")
    lines = texts[name]
    hits = [i for i, l in enumerate(lines) if l.rstrip() == anchor]
    if len(hits) != 1:
        errors.append(f"{path}: anchor line {anchor.strip()!r} found {len(hits)} times, expected once (upstream moved?)")
        continue
    i = hits[0]
    if i + 1 < len(lines) and lines[i + 1].rstrip() == line:
        continue  # already applied
    if any(l.rstrip() == line for l in lines):
        errors.append(f"{path}: {line.strip()!r} is present but not after its anchor; restore the file and apply again")
        continue
    plan.append((name, i, line))
if errors:
    for e in errors:
        print("apply.sh: " + e, file=sys.stderr)
    sys.exit(1)
# Insert from the bottom up so earlier indices stay valid.
for name, i, line in sorted(plan, key=lambda p: (p[0], -p[1])):
    lines = texts[name]
    eol = "\r" if lines[i].endswith("\r") else ""
    lines.insert(i + 1, line + eol)
for name in {p[0] for p in plan}:
    path = os.path.join(src, name)
    tmp = path + ".brdf-atlas.tmp"
    with open(tmp, "w", newline="") as f:
        f.write("\n".join(texts[name]))
    os.replace(tmp, path)
    print(f"apply.sh: {path}: {sum(1 for p in plan if p[0] == name)} line(s) inserted")
PY

dest=$src/brdf-atlas
mkdir -p "$dest"
cp "$here"/widget/*.{h,cpp} "$here"/brdf-explorer/*.{h,cpp,pri} "$root"/include/brdf_atlas.{h,hpp} "$dest"/
printf '# Written by cpp-plugin/apply.sh: where libbrdf_atlas_c.so is.\nBRDF_ATLAS_LIBDIR = %s\n' "$libdir" > "$dest/brdf-atlas-paths.pri"
echo "apply.sh: plugin files in $dest (library from $libdir)"
if [ ! -s "$build/src/data/sphere.obj" ]; then
    mkdir -p "$build/src/data"
    python3 "$here/make-sphere-obj.py" "$build/src/data/sphere.obj"
    echo "apply.sh: wrote $build/src/data/sphere.obj (upstream has none)"
fi
echo "apply.sh: now cd $build && qmake prefix=PREFIX main.pro && make -j2 && make install"
