#!/usr/bin/env bash
# usage: out_of_tree_plugin.sh BUILD_DIR SOURCE_DIR WORK_DIR
# Installs mtled, then builds the two example plugins against the installed package exactly as docs/plugins.md
# and docs/needle-plugins.md say, runs the installed conformance suites on the material, runs a scene with each
# plugin and checks the physical answers.
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
# The installed Python module (when the build made one) runs the same scene in-process from the prefix alone, with
# the same plugins found the same way: the same result.vtu, byte for byte.
package=$(ls -d "$work"/install/lib/python3*/dist-packages 2>/dev/null || true)
if [ -n "$package" ]; then
  PYTHONPATH="$package" /usr/bin/python3 - "$example/cube.json" "$work/plugin-build" "$work/python" <<'PY'
import sys
import mtled
assert "/install/lib/" in mtled.__file__, mtled.__file__  # the installed package, not the build tree's
run = mtled.run(mtled.Scene.load(sys.argv[1]), sys.argv[3], plugin_paths=[sys.argv[2]])
assert run.status == "ok" and "mtled-material-mooney_rivlin.so" in run.summary["plugins_loaded"], run.summary
PY
  cmp "$work/out/result.vtu" "$work/python/result.vtu"
fi

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

# The installed conformance suites on the plugin, as docs/plugins.md says.
"$mtled" conformance "$work/plugin-build/mtled-material-mooney_rivlin.so" > "$work/conformance.log" 2>&1 || {
  cat "$work/conformance.log"; echo "the conformance suites failed on mooney_rivlin"; exit 1; }
grep -q '^\[  PASSED  \] [1-9][0-9]* tests' "$work/conformance.log" || {
  cat "$work/conformance.log"; echo "the conformance runner ran no test of mooney_rivlin"; exit 1; }
# The law is written once: its SIMD batch, derived from that source, equals its one-point stress to 1e-12 of the
# stress scale (per unit condition number of C) on every instruction set of this CPU.
python3 - "$work/conformance.log" <<'PY'
import re, sys
worst = [float(x) for x in re.findall(r"^mooney_rivlin on \S+: max .* = (\S+) eps$", open(sys.argv[1]).read(), re.M)]
assert worst, "the conformance runner printed no batch comparison for mooney_rivlin"
print(f"Mooney-Rivlin batch against one point: at most {max(worst) * 2.220446e-16:.2e} over {len(worst)} instruction sets")
assert max(worst) * 2.220446e-16 <= 1e-12, worst
PY

# The needle model, as docs/needle-plugins.md says: built against the installed package (with its needle
# geometry library), run with --plugin-path and, at the same time, a copy of the library named by the
# scene's plugin_paths (one plugin, not a duplicate).
needle="$source/examples/flat_punch_needle"
cmake -S "$needle" -B "$work/needle-build" -DCMAKE_PREFIX_PATH="$work/install" > "$work/needle-configure.log"
cmake --build "$work/needle-build" -j2 > "$work/needle-build.log"
mkdir -p "$work/scene/plugins"
cp "$work/needle-build/mtled-needle-flat_punch.so" "$work/scene/plugins/"
python3 -c "import json,sys; s=json.load(open(sys.argv[1])); s['plugin_paths']=['plugins']; json.dump(s, open(sys.argv[2],'w'))" \
  "$needle/block.json" "$work/scene/block.json"
"$mtled" run "$work/scene/block.json" --plugin-path "$work/needle-build" -o "$work/punch" > "$work/punch.log" 2>&1 || {
  cat "$work/punch.log"; exit 1; }
# The same indentation by the built-in kinematic needle, never puncturing, driving the same footprint.
python3 -c "
import json, sys
s = json.load(open(sys.argv[1])); n = s['needle']
s['needle'] = dict(n, type='kinematic', puncture_strain=1e6, driven='nodes_near_axis', capture_radius=n['diameter'] / 2)
json.dump(s, open(sys.argv[2], 'w'))" "$needle/block.json" "$work/kinematic.json"
"$mtled" run "$work/kinematic.json" -o "$work/kinematic" > "$work/kinematic.log" 2>&1

python3 - "$work/punch/summary.json" "$work/kinematic/summary.json" "$needle/block.json" <<'PY'
import json, sys
punch, kinematic, scene = (json.load(open(f)) for f in sys.argv[1:4])
assert punch["status"] == "ok", punch
assert "mtled-needle-flat_punch.so" in punch["plugins_loaded"], punch["plugins_loaded"]
force = punch["needle"]["final_force_N"]
# Equilibrium of the relaxed block: the fixed bottom carries the punch's force (tolerance: the relaxation's
# residual, 0.4% measured on this grid).
bottom = punch["final_reactions_N"]["bottom"][2]
imbalance = abs(bottom - force) / force
# The built-in needle in its indentation phase drives the same nodes the same way: the same force to round-off.
difference = abs(kinematic["needle"]["final_force_N"] / force - 1)
# Sneddon's rigid flat punch on an incompressible half-space, F = 8 mu a d, is a lower bound here: the block is
# 10 mm thick under a 3 mm radius and bonded at the bottom, which stiffens it (by about half at a/h = 0.3).
n, mu = scene["needle"], scene["materials"][0]["mu"]
half_space = 8 * mu * n["diameter"] / 2 * n["depth"]
print(f"flat punch: force {force:.6g} N, bottom reaction {bottom:.6g} N (imbalance {imbalance:.2e}), "
      f"kinematic needle {kinematic['needle']['final_force_N']:.6g} N (difference {difference:.1e}), "
      f"half-space {half_space:.4g} N (ratio {force / half_space:.3f})")
assert imbalance < 1e-2, imbalance
assert difference < 1e-9, difference
assert 1.0 < force / half_space < 2.0, force / half_space
PY
