#!/usr/bin/env bash
# ctest install.consumer: `cmake --install` into a temporary prefix, then use only what it installed:
# its tetpack converts samples/cylinder.vtk; examples/consumer is built against it with CMake
# (find_package(tetpack): shared and static) and with pkg-config (shared and --static) and each build
# prints the counts `tetpack info --json` gives; the shared library has its SONAME and exports exactly
# the functions tetpack.h declares; no internal_*.h is installed; the man page has every subcommand;
# the bash completion completes subcommands, options and option values; the Python module imports from
# the prefix and names the installed command and ParaView plugin.
# usage: install.sh BUILD_DIR SOURCE_DIR C_COMPILER PYTHON_BUILT(ON|OFF) PYTHON [EXTRA_C_FLAGS]
# EXTRA_C_FLAGS: the sanitizer flags under TETPACK_SANITIZE (a consumer of an ASan library is built with
# ASan too).
set -euo pipefail
# Never `producer | grep -q`: grep leaving at its first match can end the producer by SIGPIPE, which
# pipefail reports as a failure (it did, once, for ldd of an ASan consumer); grep reads a captured string.
build=$1 src=$2 cc=$3 python_built=$4 python=$5 flags=${6:-}
fail() { echo "install.consumer: FAIL: $*" >&2; exit 1; }

tmp=$(mktemp -d "${TMPDIR:-/tmp}/tetpack-install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" > "$tmp/install.log" || { cat "$tmp/install.log"; fail "cmake --install"; }
echo "installed:"
(cd "$prefix" && find . \( -type f -o -type l \) | sort | sed 's|^\./|  |')

# Where things are: GNUInstallDirs' libdir (lib or lib/<multiarch>) from the installed .pc file.
pc=$(find "$prefix" -name tetpack.pc -path "*/pkgconfig/*")
[ -n "$pc" ] || fail "no tetpack.pc installed"
libdir=$(dirname "$(dirname "$pc")")
for f in bin/tetpack include/tetpack.h include/tetpack_format.h share/man/man1/tetpack.1.gz \
         share/bash-completion/completions/tetpack; do
    [ -f "$prefix/$f" ] || fail "$f not installed"
done
for f in libtetpack.so libtetpack.a cmake/tetpack/tetpackConfig.cmake cmake/tetpack/tetpackConfigVersion.cmake \
         cmake/tetpack/tetpackTargets.cmake; do
    [ -e "$libdir/$f" ] || fail "$libdir/$f not installed"
done
if grep -q "tetpack-mpi" "$tmp/install.log" || [ -x "$build/tetpack-mpi" ]; then
    [ -x "$prefix/bin/tetpack-mpi" ] || fail "tetpack-mpi built but not installed"
    mpi_man=$(zcat "$prefix/share/man/man1/tetpack-mpi.1.gz" 2>/dev/null || true)
    grep -q "decomposed mesh" <<< "$mpi_man" || fail "tetpack-mpi's man page is missing or empty"
fi
internal=$(find "$prefix" -name "internal_*.h")
[ -z "$internal" ] || fail "private headers installed: $internal"

# The shared library: SONAME libtetpack.so.<major>, and its exported functions are tetpack.h's, all of them.
soname=$(readelf -d "$libdir/libtetpack.so" | sed -n 's/.*Library soname: \[\(.*\)\]/\1/p')
[ "$soname" = "libtetpack.so.1" ] || fail "SONAME is '$soname', expected libtetpack.so.1"
[ -e "$libdir/$soname" ] || fail "$soname not installed"
nm -D --defined-only "$libdir/libtetpack.so" | awk '$2 == "T" && $3 ~ /^tpk_/ {print $3}' | sort > "$tmp/exported"
sed -n 's/^[a-z0-9_ ]*[ *]\(tpk_[a-z0-9_]*\)(.*/\1/p' "$prefix/include/tetpack.h" | sort -u > "$tmp/declared"
diff "$tmp/declared" "$tmp/exported" > "$tmp/symbols.diff" || { cat "$tmp/symbols.diff"; fail "exported symbols (>) differ from tetpack.h (<)"; }
echo "libtetpack.so: SONAME $soname, exports the $(wc -l < "$tmp/declared") functions of tetpack.h"

# A real file, converted by the installed command.
"$prefix/bin/tetpack" convert "$src/samples/cylinder.vtk" "$tmp/cylinder.tpk" --layout tet16 --quiet
"$prefix/bin/tetpack" info "$tmp/cylinder.tpk" --json > "$tmp/info.json"
expected=$("$python" -c 'import json, sys; i = json.load(open(sys.argv[1]))
print("vertices %d\ntets %d\nshell_faces %d" % (i["vertices"], i["tets"], i["shell_faces"]))' "$tmp/info.json")
check_counts() { # name binary
    "$2" "$tmp/cylinder.tpk" > "$tmp/$1.out" || fail "$1 failed on cylinder.tpk"
    got=$(grep -E "^(vertices|tets|shell_faces) " "$tmp/$1.out")
    [ "$got" = "$expected" ] || fail "$1 printed
$got
where tetpack info says
$expected"
    grep -q "^fields [1-9]" "$tmp/$1.out" || fail "$1 found no field"
    echo "$1: ok ($(echo "$got" | tr '\n' ' '))"
}

# CMake: find_package(tetpack) from the prefix only.
cmake -S "$src/examples/consumer" -B "$tmp/cmake" -DCMAKE_C_COMPILER="$cc" -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_C_FLAGS="-Wall -Wextra -Werror $flags" \
      -DCMAKE_EXE_LINKER_FLAGS="$flags" > "$tmp/cmake.log" 2>&1 || { cat "$tmp/cmake.log"; fail "consumer: cmake configure"; }
cmake --build "$tmp/cmake" > "$tmp/cmake-build.log" 2>&1 || { cat "$tmp/cmake-build.log"; fail "consumer: cmake build"; }
grep -q "libtetpack.so.1 => $libdir/" <<< "$(ldd "$tmp/cmake/consumer")" || fail "consumer does not load $libdir/libtetpack.so.1"
check_counts cmake_shared "$tmp/cmake/consumer"
grep -q libtetpack <<< "$(ldd "$tmp/cmake/consumer_static")" && fail "consumer_static loads libtetpack.so"
check_counts cmake_static "$tmp/cmake/consumer_static"

# pkg-config: the .pc file of the prefix only.
export PKG_CONFIG_PATH="$libdir/pkgconfig" PKG_CONFIG_LIBDIR="$libdir/pkgconfig:/usr/lib/$(gcc -print-multiarch 2>/dev/null)/pkgconfig:/usr/lib/pkgconfig:/usr/share/pkgconfig"
# shellcheck disable=SC2046,SC2086
"$cc" -Wall -Wextra -Werror $flags -o "$tmp/pc_shared" "$src/examples/consumer/consumer.c" \
    $(pkg-config --cflags --libs tetpack) -Wl,-rpath,"$(pkg-config --variable=libdir tetpack)" || fail "pkg-config build"
check_counts pkgconfig_shared "$tmp/pc_shared"
# shellcheck disable=SC2046,SC2086
"$cc" -Wall -Wextra -Werror $flags -o "$tmp/pc_static" "$src/examples/consumer/consumer.c" \
    $(pkg-config --cflags tetpack) $(pkg-config --libs --static tetpack | sed 's/-ltetpack\b/-l:libtetpack.a/') \
    || fail "pkg-config --static build"
check_counts pkgconfig_static "$tmp/pc_static"

# The man page: one section per subcommand of `tetpack --help`.
man=$(zcat "$prefix/share/man/man1/tetpack.1.gz")
for cmd in $("$prefix/bin/tetpack" --help | sed -n 's/^  \([a-z][a-z-]*\) .*/\1/p'); do
    grep -q "^\.SS \"tetpack $cmd\"" <<< "$man" || fail "the man page has no section for tetpack $cmd"
done
echo "man page: ok"

# Bash completion: what a user gets pressing TAB after these words.
complete_words() { # words... (the last is the one being completed)
    bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _tetpack; printf "%s\n" "${COMPREPLY[@]}"' \
        _ "$prefix/share/bash-completion/completions/tetpack" "$@"
}
[ "$(complete_words tetpack conv)" = convert ] || fail "completion of 'tetpack conv'"
[ "$(complete_words tetpack convert --lay)" = --layout ] || fail "completion of 'tetpack convert --lay'"
[ "$(complete_words tetpack convert x.vtk --layout '' | tr '\n' ' ')" = "tet16 tet20 tet32 " ] \
    || fail "completion of 'tetpack convert --layout '"
grep -qx -- --backend <<< "$(complete_words tetpack render x.tpk --back)" || fail "completion of 'tetpack render --back'"
echo "bash completion: ok"

# The Python module, from the prefix: libtetpack through _tetpack, and the installed command and plugin.
if [ "$python_built" = ON ]; then
    site=$(dirname "$(find "$prefix" -name __init__.py -path "*/tetpack/__init__.py")")
    PYTHONPATH=$(dirname "$site") "$python" - "$tmp/cylinder.tpk" "$prefix" <<'EOF' || fail "the installed Python module"
import os, sys
import tetpack
prefix = os.path.realpath(sys.argv[2])
assert os.path.realpath(tetpack.__file__).startswith(prefix), tetpack.__file__
assert os.path.realpath(tetpack.executable()) == os.path.join(prefix, "bin", "tetpack"), tetpack.executable()
plugin = tetpack.paraview_plugin_path()
assert os.path.realpath(plugin).startswith(prefix) and os.path.isfile(plugin), plugin
with tetpack.open(sys.argv[1]) as f:
    assert f.tet_count > 0
print("python: ok (%s, plugin %s)" % (os.path.dirname(tetpack.__file__), plugin))
EOF
fi
