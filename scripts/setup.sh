#!/usr/bin/env bash
# Installs tailsim's Debian 12 packages (only those missing) and builds Release into build/.
set -euo pipefail
cd "$(dirname "$0")/.."
# libqhull-dev: mujocoConfig.cmake (libmujoco-dev 2.2.2) lists /usr/include/libqhull_r as an include dir;
# without it CMake generation fails.
# libhdf5-dev: output.time_series_file: hdf5; hdf5-tools (h5dump, h5ls) and python3-h5py: its tests.
# pybind11-dev, python3-dev, python3-numpy: the Python module (docs/python.md); python3-matplotlib: the
# optional plot of examples/sweep.py; python3-pandas: reading results.csv in the docs' analysis example
# (docs/python.md, test docs_python_examples).
# clang, libclang-rt-14-dev: the libFuzzer target of the experiment loader (scripts/fuzz.sh, CI).
# libjs-three: three.js r111 (and its OrbitControls), copied into each result folder's page/ by the
# result page DIR/index.html (docs/result-page.md). chromium, chromium-driver, python3-selenium: the
# page's browser test (CTest result_page_browser) and scripts/page_load_time.py.
PKGS="build-essential cmake libmujoco-dev libmujoco-samples libeigen3-dev libyaml-cpp-dev
  libosmesa6-dev ffmpeg libgtest-dev googletest libbenchmark-dev libboost-dev libcli11-dev
  gnuplot-nox libtinyxml2-dev nlohmann-json3-dev
  libqhull-dev clang libclang-rt-14-dev python3-jsonschema python3-yaml libpagmo-dev libnlopt-cxx-dev
  parallel slurm-wlm munge libhdf5-dev hdf5-tools python3-h5py pybind11-dev python3-dev python3-numpy
  python3-matplotlib python3-pandas libjs-three chromium chromium-driver python3-selenium"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -n "$missing" ]; then
  echo "tailsim: installing$missing"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $missing
fi
# CI builds with warnings as errors (CMake option TAILSIM_WERROR); set explicitly so the cache never keeps it.
WERROR=OFF; [ "${CI:-}" = true ] && WERROR=ON
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DTAILSIM_WERROR=$WERROR >/dev/null
# TAILSIM_TARGET=tailsim (scripts/run.sh): only the program and the 6 libraries it links (7 targets);
# unset: everything, tests and benchmarks included.
cmake --build build -j"$(nproc)" ${TAILSIM_TARGET:+--target "$TAILSIM_TARGET"}
