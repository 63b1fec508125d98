#!/usr/bin/env bash
# tailsim as a library. A small downstream project (tests/downstream) is built against
#   (1) an installed tailsim: `cmake --install` of this build into a temporary prefix, then
#       find_package(tailsim); the installed program runs the README's experiment from elsewhere;
#   (2) the source tree through add_subdirectory (only the libraries it links are built).
# Both programs run and must print the Fig. 7 result of this build's own tailsim.
# usage: downstream_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "$1" && pwd)
bin=$(cd "$2" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tailsim-downstream-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
ok() { echo "ok: $*"; }

want=$("$bin/tailsim" run "$src/configs/default.yaml" --out "$tmp/ref" --quiet >/dev/null &&
       python3 -c "import json,sys; print('%.6f' % json.load(open(sys.argv[1]))['cases'][0]['runs']['analytic']['phi_net_deg'])" "$tmp/ref/summary.json")
[ -n "$want" ] || fail "no reference phi_net"

# (1) install + find_package
cmake --install "$bin" --prefix "$tmp/prefix" >"$tmp/install.log" 2>&1 || fail "cmake --install: $(tail -5 "$tmp/install.log")"
for f in bin/tailsim lib/cmake/tailsim/tailsimConfig.cmake lib/cmake/tailsim/tailsimConfigVersion.cmake \
         include/tailsim/models/analytic/analytic_simulation.h include/tailsim/tailsim_version.h \
         include/tailsim/controllers/tail_controller.h share/tailsim/robots/paper_quadruped.yaml; do
  [ -e "$tmp/prefix/$f" ] || fail "not installed: $f"
done
[ ! -e "$tmp/prefix/include/tailsim/app" ] || fail "the app's sources were installed as headers"
cmake -S "$src/tests/downstream" -B "$tmp/pkg" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release \
  >"$tmp/pkg.log" 2>&1 || fail "configure with find_package: $(tail -20 "$tmp/pkg.log")"
cmake --build "$tmp/pkg" -j2 >>"$tmp/pkg.log" 2>&1 || fail "build with find_package: $(tail -20 "$tmp/pkg.log")"
got=$("$tmp/pkg/fig7" | awk '{print $2}')
[ "$got" = "$want" ] || fail "find_package build: phi_net $got, the CLI says $want"
got=$(cd "$tmp" && "$tmp/pkg/fig7_yaml" "$src/configs/default.yaml" | awk '{print $4}')
[ "$got" = "$want" ] || fail "find_package build (YAML): phi_net $got, the CLI says $want"
ok "find_package(tailsim) from an installed prefix: fig7 and fig7_yaml print phi_net $want"
# the installed program, from another folder, with the built-in robot
mkdir -p "$tmp/elsewhere"
printf 'name: installed\nrobot: paper\ntail: {links: 1}\ntrajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\nmodels: [analytic]\n' \
  >"$tmp/elsewhere/exp.yaml"
(cd "$tmp/elsewhere" && "$tmp/prefix/bin/tailsim" run exp.yaml --out res --quiet >/dev/null) || fail "installed tailsim run"
ok "installed tailsim runs an experiment with 'robot: paper' from another folder"
# the installed Python module (when built): imported from the prefix, it finds the robots installed there
if ls "$bin"/python/tailsim*.so >/dev/null 2>&1; then
  py=$(grep -m1 '^_Python3_EXECUTABLE:INTERNAL=' "$bin/CMakeCache.txt" | cut -d= -f2)
  pydir=$(grep -m1 '^TAILSIM_PYTHON_INSTALL_DIR:' "$bin/CMakeCache.txt" | cut -d= -f2)
  ls "$tmp/prefix/$pydir"/tailsim*.so >/dev/null 2>&1 || fail "Python module not installed in $pydir"
  got=$(cd "$tmp/elsewhere" && PYTHONPATH="$tmp/prefix/$pydir" "${py:-python3}" -c '
import sys, tailsim
assert tailsim.__file__.startswith(sys.argv[1]), tailsim.__file__
assert tailsim.robot("paper")["file"] == sys.argv[1] + "/share/tailsim/robots/paper_quadruped.yaml", tailsim.robot("paper")["file"]
r = tailsim.simulate(robot="paper", tail={"links": 1}, quadruped={"d_Q2B_m": 0.125},
                     trajectory={"theta0_deg": 0, "dtheta_deg": -90, "dT_s": 0.25, "w_ss": 0.25})
print("%.6f" % r.summary["phi_net_deg"])' "$tmp/prefix") || fail "installed Python module"
  [ "$got" = "$want" ] || fail "installed Python module: phi_net $got, the CLI says $want"
  ok "installed Python module ($pydir) uses <prefix>/share/tailsim/robots and prints phi_net $want"
fi

# (2) add_subdirectory: builds only tailsim::analytic's libraries for fig7
cmake -S "$src/tests/downstream" -B "$tmp/sub" -DTAILSIM_SOURCE="$src" -DCMAKE_BUILD_TYPE=Release \
  >"$tmp/sub.log" 2>&1 || fail "configure with add_subdirectory: $(tail -20 "$tmp/sub.log")"
cmake --build "$tmp/sub" -j2 --target fig7 >>"$tmp/sub.log" 2>&1 || fail "build with add_subdirectory: $(tail -20 "$tmp/sub.log")"
got=$("$tmp/sub/fig7" | awk '{print $2}')
[ "$got" = "$want" ] || fail "add_subdirectory build: phi_net $got, the CLI says $want"
built=$(find "$tmp/sub/tailsim" -name '*.a' -printf '%f\n' | sort | tr '\n' ' ')
[ "$built" = "libtailsim_analytic.a libtailsim_core.a " ] || fail "add_subdirectory built more than fig7 needs: $built"
ok "add_subdirectory(tailsim): fig7 prints phi_net $want, built only: $built"
echo PASS
