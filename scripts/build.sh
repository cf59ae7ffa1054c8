#!/usr/bin/env bash
# Installs the Debian packages (scripts/install-deps.sh), configures and builds CementSPH (Release).
# Idempotent: a second run only rebuilds what changed. BUILD_DIR defaults to ./build.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-$here/build}"
bash "$here/scripts/install-deps.sh"
mkdir -p "$build"
# ccache, where the machine has it, makes rebuilds (and several worktrees) cheap; it is optional.
launcher=()
if command -v ccache >/dev/null 2>&1; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache); fi
# CEMENTSPH_WERROR=ON (set by .ci/run) makes warnings in our own code errors.
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCEMENTSPH_WERROR="${CEMENTSPH_WERROR:-OFF}" "${launcher[@]}" > "$build/configure.log" 2>&1 ||
  { cat "$build/configure.log"; echo "build.sh: configure failed" >&2; exit 1; }
cmake --build "$build" -j"$(nproc)"
