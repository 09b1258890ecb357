#!/usr/bin/env bash
# The library as a package: `cmake --install` into a temporary prefix, then a consumer program
# built twice, once with find_package(karst) (karst::karst) and once with pkg-config (karst.pc),
# must compile, link and call the library. Then `DESTDIR=... cmake --install` (the configured
# prefix under a staging root, as a packager runs it): the binary, the library, the headers, the
# man page, the bash completion, the data table and the Python package are installed, and each
# works from there: the binary runs, man renders the page, bash completes with the installed
# script, and /usr/bin/python3 imports the installed package, which loads the staged libkarst.
set -u
KARST=$1
SRC=$2
BUILD=$(cd "$(dirname "$KARST")" && pwd)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
cmake --install "$BUILD" --prefix "$T/prefix" >"$T/install.log" 2>&1 || { cat "$T/install.log"; fail "cmake --install"; }
for f in include/karst.h include/karst/network.h lib/pkgconfig/karst.pc lib/cmake/karst/karstConfig.cmake bin/karst; do
  [ -e "$T/prefix/$f" ] || { ls -R "$T/prefix" | head -40; fail "$f not installed"; }
done
mkdir -p "$T/consumer"
cat >"$T/consumer/main.c" <<'C'
#include <stdio.h>
#include <karst.h>
int main(void) {
  karst_network_t net;
  karst_network_init(&net);
  karst_network_add_node(&net, 0, 0, 0, NULL);
  karst_network_add_node(&net, 3, 4, 0, NULL);
  karst_network_add_edge(&net, 0, 1, NULL);
  double len = karst_network_edge_length(&net, 0);
  karst_network_destroy(&net);
  printf("karst %s %.1f\n", karst_version(), len);
  return len == 5.0 ? 0 : 1;
}
C
cat >"$T/consumer/CMakeLists.txt" <<'CM'
cmake_minimum_required(VERSION 3.18)
project(consumer C)
find_package(karst REQUIRED)
add_executable(consumer main.c)
target_link_libraries(consumer PRIVATE karst::karst)
CM
# A sanitized libkarst needs the sanitizer runtime first in the consumer too.
SAN=""
if grep -q "KARST_SANITIZE:BOOL=ON" "$BUILD/CMakeCache.txt"; then SAN="-fsanitize=address,undefined"; fi
cmake -S "$T/consumer" -B "$T/cbuild" -DCMAKE_PREFIX_PATH="$T/prefix" -DCMAKE_C_FLAGS="$SAN" \
  -DCMAKE_EXE_LINKER_FLAGS="$SAN" >"$T/c.log" 2>&1 && cmake --build "$T/cbuild" >>"$T/c.log" 2>&1 \
  || { cat "$T/c.log"; fail "consumer with find_package(karst)"; }
"$T/cbuild/consumer" | grep -q "^karst [0-9.]* 5.0$" || fail "consumer (CMake) output"
echo "ok: find_package(karst) consumer"
export PKG_CONFIG_PATH="$T/prefix/lib/pkgconfig"
cc $SAN -std=c11 "$T/consumer/main.c" $(pkg-config --cflags karst) $(pkg-config --libs karst) \
  -Wl,-rpath,"$T/prefix/lib" -o "$T/consumer_pc" || fail "consumer with pkg-config"
"$T/consumer_pc" | grep -q "^karst [0-9.]* 5.0$" || fail "consumer (pkg-config) output"
echo "ok: pkg-config consumer"
# With MPI, the plugin (libkarst_mpi.so) is installed beside libkarst, and the installed karst,
# started by mpirun, opens it from there (LD_LIBRARY_PATH makes the installed libkarst the one
# loaded): the ranks split the members, as ensemble_log.json says.
if [ -e "$BUILD/libkarst_mpi.so" ]; then
  [ -e "$T/prefix/lib/libkarst_mpi.so" ] || fail "libkarst_mpi.so not installed beside libkarst"
  mpirun --allow-run-as-root --oversubscribe -np 2 -x LD_LIBRARY_PATH="$T/prefix/lib" \
    -x ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0" \
    "$T/prefix/bin/karst" ensemble "$SRC/datasets/scenarios/branchwork.yaml" -n 2 -j 1 \
    -o "$T/mpi" --quiet >"$T/mpi.log" 2>&1 || { cat "$T/mpi.log"; fail "installed karst under mpirun"; }
  grep -q '"ranks": 2' "$T/mpi/ensemble_log.json" || fail "installed karst under mpirun: not 2 ranks"
  echo "ok: the installed karst runs under mpirun -np 2 with the installed MPI plugin"
fi

# The VTK plugin (libkarst_vtk.so) is installed beside libkarst. The installed karst writes its
# .vtp files without it and without VTK loaded, and opens it from there to read one back.
[ -e "$T/prefix/lib/libkarst_vtk.so" ] || fail "libkarst_vtk.so not installed beside libkarst"
LD_LIBRARY_PATH="$T/prefix/lib" LD_DEBUG=files "$T/prefix/bin/karst" generate \
  "$SRC/datasets/scenarios/branchwork.yaml" -o "$T/gen" --quiet >"$T/gen.log" 2>&1 \
  || { tail -5 "$T/gen.log"; fail "installed karst generate"; }
if grep -q "libvtk" "$T/gen.log"; then fail "karst generate loaded VTK"; fi
LD_LIBRARY_PATH="$T/prefix/lib" LD_DEBUG=files "$T/prefix/bin/karst" metrics "$T/gen/network.vtp" \
  --format csv -o "$T/gen/metrics.csv" --quiet >"$T/read.log" 2>&1 \
  || { tail -5 "$T/read.log"; fail "installed karst metrics on a .vtp"; }
grep -q "$T/prefix/lib/libkarst_vtk.so" "$T/read.log" || fail "the installed plugin was not the one loaded"
[ -s "$T/gen/metrics.csv" ] || fail "installed karst metrics wrote nothing"
echo "ok: the installed karst writes .vtp without VTK and reads one with the installed plugin"

# --- DESTDIR install of everything -------------------------------------------------------
cache() { sed -n "s/^$1:[A-Z]*=//p" "$BUILD/CMakeCache.txt"; }
PREFIX=$(cache CMAKE_INSTALL_PREFIX)
D="$T/stage"
DESTDIR="$D" cmake --install "$BUILD" >"$T/destdir.log" 2>&1 || { cat "$T/destdir.log"; fail "DESTDIR cmake --install"; }
R="$D$PREFIX"
LIBDIR=$(cache CMAKE_INSTALL_LIBDIR)
for f in bin/karst include/karst.h include/karst/export.h include/karst/version.h \
  share/man/man1/karst.1 share/bash-completion/completions/karst share/karst/published_metrics.csv; do
  [ -e "$R/$f" ] || { find "$D" | head -60; fail "DESTDIR: $f not installed"; }
done
ls "$R/$LIBDIR"/libkarst.so* >/dev/null 2>&1 || fail "DESTDIR: libkarst not installed in $LIBDIR"
cmp -s "$R/share/man/man1/karst.1" "$BUILD/karst.1" || fail "installed man page differs from the build's"
LD_LIBRARY_PATH="$R/$LIBDIR" "$R/bin/karst" --version | head -n 1 | grep -q "^karst [0-9.]*$" \
  || fail "installed karst --version"
LC_ALL=C.UTF-8 MANWIDTH=100 man -l "$R/share/man/man1/karst.1" 2>&1 | grep -q "karst export" \
  || fail "man -l of the installed page"
got=$(bash -c 'source "$1"; COMP_WORDS=(karst expo); COMP_CWORD=1; _karst; echo "${COMPREPLY[*]}"' _ \
  "$R/share/bash-completion/completions/karst")
[ "$got" = "export" ] || fail "installed completion: karst expo<TAB> gave '$got'"
echo "ok: DESTDIR install of the binary, library, headers, man page, completion and data"
if [ "$(cache KARST_WITH_PYTHON)" = "ON" ]; then
  PYDIR="$R/$(cache KARST_PYTHON_INSTALL_DIR)"
  ls "$PYDIR"/karst/_karst*.so "$PYDIR/karst/__init__.py" >/dev/null 2>&1 \
    || { find "$D" -name '*.py' | head; fail "Python package not installed in $PYDIR"; }
  PRE=""
  if [ "$(cache KARST_SANITIZE)" = "ON" ]; then PRE=$(cc -print-file-name=libasan.so); fi
  # The installed extension must load the staged libkarst (its RPATH is relative to itself), not
  # one installed earlier elsewhere; with ASan, the runtime is preloaded and leaks are not
  # checked here (tests/python/run_python_tests.sh does).
  KARST_DATA_DIR="$R/share/karst" LD_PRELOAD="$PRE" ASAN_OPTIONS=detect_leaks=0 PYTHONPATH="$PYDIR" \
    /usr/bin/python3 - "$SRC" "$R/$LIBDIR" <<'PY' \
    || fail "import karst from the DESTDIR install"
import os, sys
import karst
src, libdir = sys.argv[1:]
assert os.path.dirname(karst.__file__) == os.path.join(os.environ["PYTHONPATH"], "karst"), karst.__file__
maps = open("/proc/self/maps").read()
loaded = {l.split()[-1] for l in maps.splitlines() if "libkarst.so" in l}
assert loaded and all(os.path.realpath(p).startswith(os.path.realpath(libdir)) for p in loaded), loaded
m = karst.metrics(os.path.join(src, "datasets/surveys/karstnet/Monachou.pl"))
assert (m["nodes"], m["edges"]) == (251, 258), m
pub = karst.published()
assert pub["n_caves"] == 34 and pub["path"] == os.environ["KARST_DATA_DIR"] + "/published_metrics.csv", pub
print("ok: the installed package loads", *loaded)
PY
fi
