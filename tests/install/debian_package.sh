#!/usr/bin/env bash
# usage: debian_package.sh BUILD_DIR SOURCE_DIR WORK_DIR
# Makes the Debian package as docs/install.md says (cpack -G DEB in the build folder), checks what it declares
# (name, version, the Debian libraries it depends on, no build-tree paths in it), unpacks it into a scratch root
# without installing it, and runs the default scene with the unpacked mtled and its unpacked plugins: the package
# is complete and relocatable. Installing it system-wide (apt install ./mtled_*.deb) is the same files under /usr.
set -euo pipefail
build=$1 source=$2 work=$3
rm -rf "$work" && mkdir -p "$work"

(cd "$build" && cpack -G DEB -B "$work/package" > "$work/cpack.log" 2>&1) || { cat "$work/cpack.log"; exit 1; }
deb=$(ls "$work"/package/mtled_*.deb)
version=$(sed -n 's/^project(mtled VERSION \([0-9.]*\).*/\1/p' "$source/CMakeLists.txt")

field() { dpkg-deb --field "$deb" "$1"; }
[ "$(field Package)" = mtled ] || { echo "package name: $(field Package)"; exit 1; }
[ "$(field Version)" = "$version" ] || { echo "package version $(field Version), project $version"; exit 1; }
depends=$(field Depends)
for library in libfmt libspdlog zlib1g libgomp1 libstdc++6; do
  grep -q "$library" <<< "$depends" || { echo "Depends lacks $library: $depends"; exit 1; }
done

dpkg-deb --extract "$deb" "$work/root"
root="$work/root/usr"
for file in bin/mtled share/doc/mtled/LICENSE share/mtled/scenes/needle_small_sample.json; do
  [ -e "$root/$file" ] || { echo "the package lacks /usr/$file"; exit 1; }
done
if grep -rlq --binary-files=text "$build" "$root"; then
  echo "files of the package name the build folder $build:"; grep -rl --binary-files=text "$build" "$root"; exit 1
fi

# The unpacked mtled finds its libraries (RUNPATH $ORIGIN/../lib) and plugins (../lib/mtled/plugins) beside it.
"$root/bin/mtled" --version
env -u MTLED_PLUGIN_PATH "$root/bin/mtled" --log-level debug run "$root/share/mtled/scenes/needle_small_sample.json" -o "$work/default" \
  --threads 2 > "$work/default.log" 2>&1 || { cat "$work/default.log"; exit 1; }
python3 - "$work/default/summary.json" "$root" "$work/default.log" <<'PY'
import json, os, re, sys
summary, root = json.load(open(sys.argv[1])), os.path.realpath(sys.argv[2])
loaded = re.findall(r'loaded \w+ "\w+" from (\S+)', open(sys.argv[3]).read())
assert len(loaded) == len(summary["plugins_loaded"]), (loaded, summary["plugins_loaded"])
assert summary["status"] == "ok", summary["status"]
needle = summary["needle"]
assert needle["final_depth_m"] > 0 and needle["final_force_N"] > 0, needle
outside = [f for f in loaded if not os.path.realpath(f).startswith(root + "/")]
assert not outside, f"plugins loaded from outside the package: {outside}"
print(f"default scene from the unpacked package: {summary['steps']} steps, needle force "
      f"{needle['final_force_N']:.4g} N at {1e3 * needle['final_depth_m']:.1f} mm, "
      f"{len(summary['plugins_loaded'])} plugins from the package")
PY
