#!/usr/bin/env bash
# Acceptance figures of the global-shutter visual odometry (issue 8), outside CI:
#   simulate configs/sim/accept_gs.json (30 s, 640x512, 20 Hz, medium motion) for each seed, run
#   configs/gs_vo.json on it with 800 and with 2000 active points (7 keyframes), and tabulate keyframe
#   ATE after Sim(3) alignment (absolute and as a share of the path), frames per second against the
#   20 Hz camera, keyframes and the mean time per stage.
#
# Usage: bash scripts/acceptance_vo.sh [OUT_DIR] [SEED ...]     (default out/acceptance_vo, seeds 1 2)
#   RSVIO_BIN   the binary (default build/bin/rsvio; build first with scripts/build.sh)
#   THREADS     estimator threads (default 2)
# Datasets are simulated once per seed into OUT_DIR/data_s<seed> and reused; delete them to re-simulate.
# Takes about 3 min per seed to simulate and 1 min per run on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/acceptance_vo}
shift || true
SEEDS=("$@")
[ ${#SEEDS[@]} -gt 0 ] || SEEDS=(1 2)
BIN=${RSVIO_BIN:-build/bin/rsvio}
THREADS=${THREADS:-2}
[ -x "$BIN" ] || { echo "acceptance_vo: $BIN not found; run scripts/build.sh or set RSVIO_BIN" >&2; exit 2; }
mkdir -p "$OUT"

for seed in "${SEEDS[@]}"; do
  data="$OUT/data_s$seed"
  if [ ! -f "$data/truth.json" ]; then
    echo "== simulating configs/sim/accept_gs.json, seed $seed -> $data"
    "$BIN" -q simulate --config configs/sim/accept_gs.json --seed "$seed" --out "$data"
  fi
  for pts in 800 2000; do
    run="$OUT/run_s${seed}_p$pts"
    echo "== seed $seed, $pts active points -> $run"
    "$BIN" -q run --config configs/gs_vo.json --data "$data" --out "$run" --set threads="$THREADS" \
      --set backend.active_points="$pts" --set frontend.points="$pts" --set backend.max_keyframes=7 \
      --set output.render=false || echo "   (run failed: see $run/report.json)"
  done
done

python3 - "$OUT" "${SEEDS[@]}" <<'EOF'
import json, sys, os
out, seeds = sys.argv[1], sys.argv[2:]
stages = ["preprocess", "track", "trace", "keyframe", "activate", "optimise", "marginalise"]
print()
print("%-5s %6s %7s %4s %6s %6s %9s %8s  %s" % ("seed", "points", "status", "kf", "fps", "rt", "ATE (m)", "ATE %", "ms per call: " + " ".join(stages)))
for seed in seeds:
    for pts in (800, 2000):
        p = os.path.join(out, "run_s%s_p%d" % (seed, pts), "report.json")
        if not os.path.exists(p):
            print("%-5s %6d  (no report)" % (seed, pts)); continue
        r = json.load(open(p))
        e = r.get("eval", {})
        ate = e.get("ate_rmse_m"); path = e.get("gt_path_length_m")
        pct = 100.0 * ate / path if ate is not None and path else float("nan")
        st = " ".join("%.1f" % r.get("stage_ms", {}).get(s, float("nan")) for s in stages)
        print("%-5s %6d %7s %4d %6.1f %6.2f %9.4f %7.3f%%  %s" % (seed, pts, r["status"], r["keyframes"], r["fps"],
              r["realtime_factor"], ate if ate is not None else float("nan"), pct, st))
print("\nfps: frames per second of wall time; rt: fps / camera rate (20 Hz); ATE: keyframes after Sim(3) alignment;")
print("acceptance (issue 8): ATE below 0.1 % of the path and rt above 1 at 800 points.")
EOF
