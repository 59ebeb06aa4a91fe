#!/usr/bin/env bash
# Acceptance figures of the rolling-shutter visual-inertial odometry (issues 13/14), outside CI:
#   for each scene seed, simulate the medium-motion rolling-shutter sequence (configs/sim/demo.json:
#   640x512, 20 Hz, 20 s, ~30 ms readout) and its global-shutter twin (same seed,
#   --set effects.rolling_shutter=null), then run
#     rs_vio on RS data with the true line delay given (58.94 us),
#     gs_vio on RS data (the model that lacks the effect),
#     gs_vio on the GS twin (the reference),
#   and tabulate status, frames, keyframe ATE (SE(3): metric; Sim(3) and its scale), the time and scale
#   of the visual-inertial initialisation and the final scale.
#
# Usage: bash scripts/acceptance_vio.sh [OUT_DIR] [SEED ...]   (default out/acceptance_vio, seeds 1 2 3)
#   RSVIO_BIN  the binary (default build/bin/rsvio)
#   MODES      the runs per seed (default "rsvio_rs gsvio_rs gsvio_gs"); rsviodm_rs and gsviodm_gs are
#              rs_vio on RS and gs_vio on the twin with imu.dynamic_marginalization=true
#   SETS       more --set lines for every run, e.g. SETS="imu.init_scale_factor=1.3"
#   TAG        appended to the run folders (run_s<seed>_<mode><TAG>), to keep variants apart
# Datasets are simulated once into OUT_DIR/med_<rs|gs>_s<seed> and reused (about 3 min each on 2 cores);
# each run takes 0.5-1 min; two runs go at a time.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/acceptance_vio}
shift || true
SEEDS=("$@")
[ ${#SEEDS[@]} -gt 0 ] || SEEDS=(1 2 3)
BIN=${RSVIO_BIN:-build/bin/rsvio}
MODES=${MODES:-rsvio_rs gsvio_rs gsvio_gs}
[ -x "$BIN" ] || { echo "acceptance_vio: $BIN not found; run scripts/build.sh or set RSVIO_BIN" >&2; exit 2; }
mkdir -p "$OUT"

for seed in "${SEEDS[@]}"; do
  for sh in rs gs; do
    data="$OUT/med_${sh}_s$seed"
    [ -f "$data/truth.json" ] && continue
    echo "== simulating configs/sim/demo.json ($sh), seed $seed -> $data"
    set_gs=()
    [ "$sh" = gs ] && set_gs=(--set effects.rolling_shutter=null)
    "$BIN" -q simulate --config configs/sim/demo.json --seed "$seed" --out "$data" "${set_gs[@]}"
  done
done

run_one() {  # seed mode
  local seed=$1 mode=$2 cfg data sets=()
  case $mode in
    rsvio_rs) cfg=configs/rs_vio.json; data="$OUT/med_rs_s$seed"; sets=(--set shutter.params.line_delay_us=58.94) ;;
    gsvio_rs) cfg=configs/gs_vio.json; data="$OUT/med_rs_s$seed" ;;
    gsvio_gs) cfg=configs/gs_vio.json; data="$OUT/med_gs_s$seed" ;;
    rsviodm_rs) cfg=configs/rs_vio.json; data="$OUT/med_rs_s$seed"
                sets=(--set shutter.params.line_delay_us=58.94 --set imu.dynamic_marginalization=true) ;;
    gsviodm_gs) cfg=configs/gs_vio.json; data="$OUT/med_gs_s$seed"; sets=(--set imu.dynamic_marginalization=true) ;;
    *) echo "acceptance_vio: unknown mode $mode" >&2; return 1 ;;
  esac
  for s in ${SETS:-}; do sets+=(--set "$s"); done
  local run="$OUT/run_s${seed}_$mode${TAG:-}"
  "$BIN" -q run --config "$cfg" --data "$data" --out "$run" --set output.render=false "${sets[@]}" > "$run.log" 2>&1 \
    || echo "   (seed $seed $mode failed: see $run/report.json)"
  # The Sim(3) figures (report.json holds the SE(3) ones of metric outputs).
  "$BIN" -q eval --data "$data" --est "$run/keyframes.tum" --align sim3 --json > "$run.sim3.json" 2> /dev/null || true
}

jobs=()
for seed in "${SEEDS[@]}"; do
  for mode in $MODES; do jobs+=("$seed $mode"); done
done
for ((i = 0; i < ${#jobs[@]}; i += 2)); do
  echo "== ${jobs[$i]}${jobs[$((i + 1))]:+, ${jobs[$((i + 1))]}}"
  run_one ${jobs[$i]} &
  [ -n "${jobs[$((i + 1))]:-}" ] && run_one ${jobs[$((i + 1))]}
  wait
done

python3 - "$OUT" "$MODES" "${TAG:-}" "${SEEDS[@]}" <<'EOF'
import json, sys, os, statistics
out, modes, tag, seeds = sys.argv[1], sys.argv[2].split(), sys.argv[3], sys.argv[4:]
def load(p):
    try:
        return json.load(open(p))
    except Exception:
        return None
print()
print("%-4s %-10s %7s %7s %9s %10s %7s %8s %8s %7s %5s  %s" % ("seed", "mode", "status", "frames", "SE3 (mm)",
      "Sim3 (mm)", "scale", "init (s)", "s_init", "s_end", "dm", "error"))
med = {}
for mode in modes:
    vals = []
    for seed in seeds:
        base = os.path.join(out, "run_s%s_%s%s" % (seed, mode, tag))
        r = load(os.path.join(base, "report.json"))
        if not r:
            print("%-4s %-10s  (no report)" % (seed, mode)); vals.append(float("inf")); continue
        s3 = load(base + ".sim3.json") or {}
        ev = r.get("eval", {})
        vio = r.get("extra", {}).get("vio", {})
        metric = ev.get("align") == "se3"
        se3 = ev.get("ate_rmse_m") if metric else None
        sim3 = s3.get("ate_rmse_m")
        scale = s3.get("alignment", {}).get("scale")
        data = os.path.join(out, "med_%s_s%s" % (mode[-2:], seed))
        t0 = (load(os.path.join(data, "truth.json")) or {}).get("clocks", {}).get("start_ns", 0) * 1e-9
        ok = r["status"] == "ok"
        vals.append(se3 if ok and se3 is not None else float("inf"))
        init_t = vio.get("initialised_at_s")
        dm = vio.get("dynamic_marginalization")
        print("%-4s %-10s %7s %7d %9s %10s %7s %8s %8s %7s %5s  %s" % (
            seed, mode, r["status"], r.get("frames", 0),
            "%.1f" % (1e3 * se3) if se3 is not None else "-",
            "%.1f" % (1e3 * sim3) if sim3 is not None else "-",
            "%.3f" % scale if scale is not None else "-",
            "%.2f" % (init_t - t0) if vio.get("initialised") and init_t else "-",
            "%.3f" % vio["scale_at_initialisation"] if vio.get("initialised") else "-",
            "%.3f" % vio["scale"] if vio.get("initialised") else "-",
            "%d/%d" % (dm["switches"], dm["half_resets"]) if dm else "-",
            (r.get("error") or "")[:80]))
    med[mode] = statistics.median(vals) if vals else float("nan")
print("medians of the SE(3) ATE (failed = inf): " + ", ".join("%s %.1f mm" % (m, 1e3 * v) for m, v in med.items()))
if "rsvio_rs" in med and "gsvio_gs" in med:
    print("rs_vio on RS vs gs_vio on the twin %.2fx" % (med["rsvio_rs"] / med["gsvio_gs"]))
EOF
