#!/usr/bin/env bash
# The .glb files gslam writes pass the Khronos glTF validator (validate_gltf.mjs says which
# findings it allows). Usage: gltf_validator_test.sh GSLAM_BINARY VALIDATOR_DIR
# Exits 77 (skipped) when Node or the validator is missing: scripts/install_deps.sh installs both.
set -euo pipefail
gslam=$1 validator=$2
here=$(cd "$(dirname "$0")" && pwd)
if ! command -v node > /dev/null || [ ! -d "$validator/node_modules/gltf-validator" ]; then
  echo "skipped: Node or gltf-validator missing under $validator (scripts/install_deps.sh installs them)"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '{"refine_passes": 1, "mapping": {"iterations": 3}}' > "$work/quick.json"
"$gslam" reconstruct --out "$work/run" --max-frames 4 --config "$work/quick.json" > /dev/null 2>&1
node "$here/validate_gltf.mjs" "$validator" "$work/run/map.glb"
# A semantic map: its classes as application-specific attributes (_LABEL_k, _LABEL_PROBABILITY_k).
"$gslam" generate "$work/labelled" --frames 4 --labels > /dev/null 2>&1
"$gslam" reconstruct "$work/labelled" --out "$work/labelled_run" --config "$work/quick.json" > /dev/null 2>&1
grep -q '"_LABEL_0"' "$work/labelled_run/map.glb" || { echo "map.glb of a labelled run has no _LABEL_0"; exit 1; }
node "$here/validate_gltf.mjs" "$validator" "$work/labelled_run/map.glb"
