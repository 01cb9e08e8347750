#!/usr/bin/env bash
# Replays the real sequences in ../shared/data through `gslam live --headless` at their recorded
# rate (30 Hz) and prints what a robot would see: frames tracked and dropped, tracking latency,
# keyframes mapped and skipped, ATE, peak memory. Run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
gslam=${GSLAM_BUILD_DIR:-build}/app/gslam
data=../shared/data
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| sequence | frames | dropped | latency p50 / p95 ms | keyframes mapped / skipped | ATE cm | peak MiB |"
echo "|---|---|---|---|---|---|---|"
for seq in tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy sevenscenes_redkitchen_first200; do
  if [ ! -d "$data/$seq" ]; then echo "| $seq | skipped: not in $data | | | | | |"; continue; fi
  "$gslam" live "$data/$seq" --out "$out/run" --overwrite --headless "$@" > "$out/log" 2>&1 || { cat "$out/log"; exit 1; }
  python3 - "$out/run/summary.json" "$seq" <<'PY'
import json, sys
s = json.load(open(sys.argv[1])); live = s["live"]
ate = s.get("ate_rmse_m")
print(f"| {sys.argv[2].split('/')[0]} | {s['frames']} | {live['frames_dropped']} | "
      f"{live['tracking_latency_ms']['p50']:.0f} / {live['tracking_latency_ms']['p95']:.0f} | "
      f"{live['keyframes_mapped']} / {live['keyframes_skipped']} | "
      f"{'-' if ate is None else f'{ate * 100:.2f}'} | {s['peak_memory_mib']:.0f} |")
PY
done
