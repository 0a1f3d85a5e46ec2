#!/usr/bin/env bash
# Runs the shipped scenes (shortened) with two builds of mtled and compares every file they write, byte by byte;
# summary.json is compared without the entries that measure the machine (times, memory, rates, paths). Use it
# around a change that must not change results:
#   git worktree add ../before HEAD && (cd ../before && cmake -B build && cmake --build build -j2)
#   scripts/same-outputs.sh ../before/build build
# Exit 0 when every run agrees, 1 when some file differs (each difference listed).
set -euo pipefail
old_build=${1:?usage: same-outputs.sh OLD_BUILD NEW_BUILD [WORK]}
new_build=${2:?usage: same-outputs.sh OLD_BUILD NEW_BUILD [WORK]}
work=${3:-$(mktemp -d)}
scenes=$(cd "$(dirname "$0")/../share/scenes" && pwd)
all_fields='["green_strain","cauchy_stress","von_mises_stress","jacobian"]'

# name | scene | overrides (each a --set)
runs=(
  "needle|needle_small_sample.json|/needle/depth=0.004 /integrator/load_steps=300 /output/every_steps=150 /output/cell_data=$all_fields"
  "needle_ascii|needle_small_sample.json|/mesh/target_nodes=2000 /needle/depth=0.003 /integrator/load_steps=200 /output/vtu_format=ascii /output/history_every_steps=7"
  "contact|needle_small_sample_contact.json|/mesh/target_nodes=2000 /needle/depth=0.003 /integrator/load_steps=200 /output/every_steps=100"
  "compression|compression_semiconfined.json|/output/every_steps=100 /output/cell_data=$all_fields"
  "cube_ogden|uniaxial_cube_ogden.json|/output/cell_data=$all_fields"
  "cube_central|uniaxial_cube_neohookean.json|/integrator={\"type\":\"central_difference\",\"duration\":0.05,\"damping\":50} /output/every_steps=200"
  "unstable|uniaxial_cube_ogden.json|/integrator/time_step_factor=10 /monitors/stable_step_every_steps=0 /output/every_steps=2"
  "layers|needle_large_sample_layers.json|/mesh/target_nodes=6000 /needle/depth=0.005 /integrator/load_steps=100"
  "brain|needle_brain_phantom.json|/needle/depth=0.003 /integrator/load_steps=60 /integrator/tolerance=0.05 /output/every_steps=50"
)

# summary.json less what measures the machine rather than the run.
stable_summary() {
  python3 - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
for key in ("setup_time_s", "solve_time_s", "wall_time_s", "peak_rss_mb", "ip_updates_per_s", "plugins_loaded", "scene"):
    s.pop(key, None)
backend = s.get("backend", {})
for key in list(backend):
    if key.endswith("_s") or key.endswith("per_s") or key == "threads":
        backend.pop(key)
print(json.dumps(s, indent=1, sort_keys=True))
PY
}

status=0
for run in "${runs[@]}"; do
  IFS='|' read -r name scene overrides <<<"$run"
  sets=()
  for o in $overrides; do sets+=(--set "$o"); done
  for side in old new; do
    build=$old_build; [[ $side == new ]] && build=$new_build
    rm -rf "$work/$side/$name"; mkdir -p "$work/$side"
    # A build tree's RUNPATH names its own lib/ by absolute path: a copied build must be told where its libraries are.
    LD_LIBRARY_PATH="$build/lib" "$build/bin/mtled" run "$scenes/$scene" -o "$work/$side/$name" --threads 2 --no-progress "${sets[@]}" \
      >"$work/$side/$name.log" 2>&1 && echo 0 >"$work/$side/$name.exit" || echo $? >"$work/$side/$name.exit"
  done
  differ=0
  if ! diff -q <(cd "$work/old/$name" && find . -type f | sort) <(cd "$work/new/$name" && find . -type f | sort) >/dev/null; then
    echo "$name: the two runs wrote different files"; differ=1
  fi
  while read -r file; do
    if [[ $file == ./summary.json ]]; then
      diff <(stable_summary "$work/old/$name/$file") <(stable_summary "$work/new/$name/$file") >"$work/$name.summary.diff" ||
        { echo "$name: summary.json differs ($work/$name.summary.diff)"; differ=1; }
    elif [[ -f $work/new/$name/$file ]] && ! cmp -s "$work/old/$name/$file" "$work/new/$name/$file"; then
      echo "$name: $file differs"; differ=1
    fi
  done < <(cd "$work/old/$name" && find . -type f | sort)
  cmp -s "$work/old/$name.exit" "$work/new/$name.exit" || { echo "$name: exit codes differ"; differ=1; }
  files=$(cd "$work/new/$name" && find . -type f | wc -l)
  [[ $differ == 0 ]] && echo "$name: exit $(cat "$work/new/$name.exit"), $files files identical" || status=1
done
exit $status
