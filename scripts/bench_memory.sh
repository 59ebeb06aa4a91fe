#!/usr/bin/env bash
# Long runs: peak memory against sequence length (issue 16). Not part of CI (about 10 min of CPU on
# 2 cores). Simulates two global-shutter sequences at low resolution (configs/sim/tiny_gs.json: 320x256,
# 20 Hz, here without supersampling) of SHORT_S and LONG_S seconds (default 60 and 600), runs configs/gs_vo.json
# on both and reports peak RSS (getrusage ru_maxrss of the run process) and the size of every output
# file, so what grows with the sequence shows (the diagnostics log and per-frame records are expected
# to). Usage: scripts/bench_memory.sh [build-dir] [work-dir]   (defaults: build, /tmp/rsvio_bench_memory)
# TAG=name names the runs (run_<name>_<dur>s), so two builds can be compared on the same simulated data.
# SEED (simulator seed, default 1), SPEED (m/s, default 0.45) and ROT_SPEED (deg/s, default 35) set the
# sequences (the same for both lengths); the data folder's name carries them.
# Figures: docs/backend.md, "Memory on long runs".
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
BUILD=${1:-build}
WORK=${2:-/tmp/rsvio_bench_memory}
SHORT_S=${SHORT_S:-60}
LONG_S=${LONG_S:-600}
TAG=${TAG:+${TAG}_}
BIN="$BUILD/bin/rsvio"
[ -x "$BIN" ] || { echo "rsvio: $BIN not found (build first: bash scripts/build.sh)" >&2; exit 2; }
mkdir -p "$WORK"
# Peak RSS in kB of a command (its own, not the shell's): python's getrusage of children.
peak_kb() {
  python3 -c 'import resource, subprocess, sys
r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
sys.stderr.write(r.stderr.decode()[-2000:] if r.returncode else "")
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, r.returncode)' "$@"
}
SEED=${SEED:-1}
SPEED=${SPEED:-0.45}
ROT_SPEED=${ROT_SPEED:-35}
for dur in "$SHORT_S" "$LONG_S"; do
  data="$WORK/data_s${SEED}_v${SPEED}_w${ROT_SPEED}_${dur}s"
  if [ ! -f "$data/truth.json" ]; then
    echo "simulating ${dur} s ..."
    "$BIN" -q simulate --config "$ROOT/configs/sim/tiny_gs.json" --out "$data" --set motion.duration_s="$dur" \
      --set camera.supersampling=1 --set motion.mean_speed_m_s="$SPEED" --set motion.mean_rot_speed_deg_s="$ROT_SPEED" --seed "$SEED" \
      --set motion.mean_accel_m_s2=1.1 --set motion.mean_rot_accel_deg_s2=130
  fi
  echo "running gs_vo on ${dur} s ..."
  read -r kb rc < <(peak_kb "$BIN" -q run --config "$ROOT/configs/gs_vo.json" --data "$data" --out "$WORK/run_${TAG}${dur}s" \
                      --set output.render=false)
  echo "$dur $kb $rc" > "$WORK/peak_${TAG}${dur}s.txt"
done
echo
echo "sequence  frames  status  peak RSS (MB)  outputs (kB): trajectory keyframes states points diagnostics"
for dur in "$SHORT_S" "$LONG_S"; do
  read -r d kb rc < "$WORK/peak_${TAG}${dur}s.txt"
  run="$WORK/run_${TAG}${dur}s"
  frames=$(python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print(r["frames"], r["status"])' "$run/report.json")
  sizes=""
  for f in trajectory.tum keyframes.tum states.csv points.ply diagnostics.bin; do
    sizes="$sizes $(( $(stat -c %s "$run/$f" 2>/dev/null || echo 0) / 1024 ))"
  done
  printf "%6s s  %s  %13.1f  %s\n" "$dur" "$frames" "$(python3 -c "print($kb / 1024)")" "$sizes"
done
read -r _ kb_s _ < "$WORK/peak_${TAG}${SHORT_S}s.txt"
read -r _ kb_l _ < "$WORK/peak_${TAG}${LONG_S}s.txt"
python3 -c 'import sys; s, l = float(sys.argv[1]), float(sys.argv[2]); print("peak RSS long/short: %.3f (goal <= 1.10)" % (l / s))' "$kb_s" "$kb_l"
