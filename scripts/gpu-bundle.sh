#!/usr/bin/env bash
# Builds a relocatable bundle for a GPU node that has the NVIDIA driver but none of mtled's Debian packages and no
# network: the installed mtled (RPATH $ORIGIN), the shared libraries it needs beside it (not the C library, which
# every Linux has), the GPU tests, the benchmark scenes with their meshes generated beforehand (Abaqus files: the
# GPU node needs no Gmsh), and scripts/gpu-check.sh. Run it on the build machine after scripts/setup.sh --tests
# (the build must have found the CUDA toolkit).
# Usage: scripts/gpu-bundle.sh [BUNDLE_DIR]   (default: gpu-bundle)      Then: BUNDLE_DIR/gpu-check.sh BUNDLE_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
bundle=$(realpath -m "${1:-gpu-bundle}")
build=build
[ -f "$build/lib/mtled/plugins/mtled-backend-cuda.so" ] ||
  { echo "no cuda backend in $build: configure with the CUDA toolkit (scripts/setup.sh --tests finds /usr/local/cuda)"; exit 2; }
rm -rf "$bundle"
cmake --install "$build" --prefix "$bundle" >/dev/null
# Gmsh's generators and its reader need libgmsh and OpenCASCADE (hundreds of MB): left out; meshes come as files.
for plugin in "$bundle"/lib/mtled/plugins/*.so; do
  if ldd "$plugin" | grep -q libgmsh; then
    rm "$plugin"
    component=$(basename "$plugin" .so)
    component=${component#mtled-}
    echo "${component%%-*} ${component#*-}: left out of the GPU bundle: it needs Gmsh. Write the scene's mesh with mtled mesh where Gmsh is, and read it here" \
      >> "$bundle/lib/mtled/plugins/left-out.txt"
  fi
done
rm -rf "$bundle/include" "$bundle/lib/cmake"
# The GPU tests, run from the bundle (tests/support reads MTLED_TEST_* from the environment).
mkdir -p "$bundle/tests"
cp "$build/bin/cuda_backend_test" "$build/bin/device_layout_test" "$bundle/tests/"
# The libraries the binaries load that a bare machine may lack (everything but the C library and the loader).
copy_libraries() {
  ldd "$1" | awk '/=> \// {print $3}' | while read -r library; do
    case "$(basename "$library")" in
      libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|ld-linux*|libmtled*) ;;
      *) cp -n "$library" "$bundle/lib/" ;;
    esac
  done
}
for binary in "$bundle"/bin/* "$bundle"/lib/*.so* "$bundle"/lib/mtled/plugins/*.so "$bundle"/tests/*; do
  copy_libraries "$binary"
done
# The benchmark scenes with their generated meshes.
mkdir -p "$bundle/scenes"
for scene in needle_small_sample needle_brain_phantom; do
  "$build/bin/mtled" mesh "share/scenes/$scene.json" -o "$bundle/scenes/$scene.inp" --log-level warn
  python3 - "share/scenes/$scene.json" "$bundle/scenes/$scene.json" "$scene.inp" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["description"] = "(bundle) " + scene["description"]
scene["mesh"] = {"type": "abaqus_file", "path": sys.argv[3]}
json.dump(scene, open(sys.argv[2], "w"), indent=1)
PY
done
cp scripts/gpu-check.sh "$bundle/"
du -sh "$bundle"
echo "bundle: $bundle (run: $bundle/gpu-check.sh $bundle)"
