#!/usr/bin/env bash
# Tessera set-up: installs the Debian packages it lacks, configures and builds (Release), then
#   tools/setup.sh run   runs the default scene (small deposition) and prints its quantities
#   tools/setup.sh test  runs the test suite (ctest without the `slow` label)
#   tools/setup.sh build only builds
# Idempotent: packages already present are not reinstalled; the build is incremental.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
action=${1:-build}
build_dir=${TESSERA_BUILD_DIR:-build}

packages=(build-essential cmake pkg-config openmpi-bin libopenmpi-dev libyaml-cpp-dev
          libhdf5-openmpi-dev nlohmann-json3-dev libeigen3-dev libmetis-dev libgtest-dev
          petsc-dev python3 python3-numpy python3-matplotlib python3-h5py)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "tessera setup: installing ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

jobs=$(nproc)
if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release ${TESSERA_CMAKE_ARGS:-} >/dev/null
fi
if ! cmake --build "$build_dir" -j "$jobs" >"$build_dir/build.log" 2>&1; then
  grep -v -E '^\[ *[0-9]+%\]' "$build_dir/build.log" >&2
  echo "tessera setup: build failed (full log: $build_dir/build.log)" >&2
  exit 1
fi

export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
case "$action" in
  build) ;;
  run)
    out=${2:-runs/deposition_small}
    mpirun -n "$jobs" "$build_dir/bin/tessera" run cases/deposition/small.yaml --output "$out"
    ;;
  test)
    cd "$build_dir"
    ctest --output-on-failure -LE slow -j "$jobs" --timeout 1200
    ;;
  *) echo "usage: tools/setup.sh [build|run [DIR]|test]" >&2; exit 2 ;;
esac
