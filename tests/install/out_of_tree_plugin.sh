#!/usr/bin/env bash
# usage: out_of_tree_plugin.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 source=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
example="$source/examples/mooney_rivlin_material"

cmake --install "$build" --prefix "$work/install" > "$work/install.log"
# Configured exactly as docs/plugins.md says, with no build type: the mtled package makes it Release.
cmake -S "$example" -B "$work/plugin-build" -DCMAKE_PREFIX_PATH="$work/install" > "$work/configure.log"
grep -q '^CMAKE_BUILD_TYPE:STRING=Release$' "$work/plugin-build/CMakeCache.txt" || {
  echo "the out-of-tree plugin is not built as Release by default"; exit 1; }
cmake --build "$work/plugin-build" -j2 > "$work/build.log"
test -f "$work/plugin-build/mtled-material-mooney_rivlin.so"

mtled="$work/install/bin/mtled"
"$mtled" plugins --plugin-path "$work/plugin-build" --describe mooney_rivlin | grep -q '`c10`'
"$mtled" run "$example/cube.json" --plugin-path "$work/plugin-build" -o "$work/out"

# The run is physically right: the nominal stress on the top face equals the homogeneous uniaxial solution of
# the Mooney-Rivlin energy (the lateral stretch found by bisection on a zero lateral stress; derivatives of W
# by central differences, whose error ~1e-10 is far below the 0.5% tolerance).
python3 - "$work/out/summary.json" "$example/cube.json" <<'PY'
import json, sys
summary = json.load(open(sys.argv[1])); scene = json.load(open(sys.argv[2]))
assert summary["status"] == "ok", summary
assert "mtled-material-mooney_rivlin.so" in summary["plugins_loaded"], summary["plugins_loaded"]
m = scene["materials"][0]; c10, c01, D = m["c10"], m["c01"], m["D"]
size = scene["mesh"]["size"]; stretch = 1 + scene["boundaries"][1]["displacement"][2] / size[2]
def W(l):
    J = l[0] * l[1] * l[2]; I1 = sum(x * x for x in l)
    I2 = l[0]**2 * l[1]**2 + l[1]**2 * l[2]**2 + l[0]**2 * l[2]**2
    return c10 * (J ** (-2 / 3) * I1 - 3) + c01 * (J ** (-4 / 3) * I2 - 3) + (J - 1) ** 2 / D
def P(l, i, h=1e-6):
    a = list(l); b = list(l); a[i] += h; b[i] -= h
    return (W(a) - W(b)) / (2 * h)
lo, hi = 0.9, 1.5
for _ in range(100):
    mid = 0.5 * (lo + hi)
    if P([mid, mid, stretch], 0) > 0: hi = mid
    else: lo = mid
exact = P([lo, lo, stretch], 2) * size[0] * size[1]
force = summary["final_reactions_N"]["top"][2]
error = abs(force / exact - 1)
print(f"Mooney-Rivlin cube: top force {force:.6g} N, exact {exact:.6g} N, relative error {error:.2e}")
assert error < 5e-3, error
PY
