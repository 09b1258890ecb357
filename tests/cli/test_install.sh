#!/usr/bin/env bash
# The library as a package: `cmake --install` into a temporary prefix, then a consumer program
# built twice, once with find_package(karst) (karst::karst) and once with pkg-config (karst.pc),
# must compile, link and call the library.
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
