#!/usr/bin/env bash
# Installs the Debian packages (scripts/install-deps.sh), configures and builds CementSPH (Release).
# Idempotent: a second run only rebuilds what changed. BUILD_DIR defaults to ./build.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
bash "$here/scripts/install-deps.sh"
mkdir -p "$build"
# ccache, where the machine has it, makes rebuilds (and several worktrees) cheap; it is optional.
# The launcher carries ccache's settings, so every later `cmake --build` of this folder uses them too:
# CCACHE_BASEDIR rewrites absolute paths under the source root to relative ones before hashing, so a clone at
# another path (CI's clean clone) hits what an earlier clone compiled; CCACHE_NOHASHDIR keeps the build folder's
# path out of the key of -g compiles. A test suite's object still misses in a new clone: its CEMENTSPH_TEST_DATA_DIR
# and CEMENTSPH_BINARY_DIR definitions hold the clone's absolute paths (cmake/CementSPHTesting.cmake).
launcher=()
if command -v ccache >/dev/null 2>&1; then
  cache="env;CCACHE_BASEDIR=$here;CCACHE_NOHASHDIR=1;ccache"
  launcher=("-DCMAKE_CXX_COMPILER_LAUNCHER=$cache" "-DCMAKE_C_COMPILER_LAUNCHER=$cache")
fi
# CEMENTSPH_WERROR=ON (set by .ci/run) makes warnings in our own code errors.
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCEMENTSPH_WERROR="${CEMENTSPH_WERROR:-OFF}" "${launcher[@]}" > "$build/configure.log" 2>&1 ||
  { cat "$build/configure.log"; echo "build.sh: configure failed" >&2; exit 1; }
cmake --build "$build" -j"$(nproc)"
