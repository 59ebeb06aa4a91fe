#!/usr/bin/env bash
# Acceptance figures of the rolling-shutter visual odometry (issue 13), outside CI:
#   for each scene seed and motion (medium: configs/sim/demo.json; fast: configs/sim/rs.json), simulate
#   the rolling-shutter sequence (640x512, 20 s, ~30 ms readout) and its global-shutter twin (same seed,
#   --set effects.rolling_shutter=null), then run
#     rs_vo on RS data with the true line delay given (58.94 us),
#     gs_vo on RS data (the model that lacks the effect),
#     gs_vo on the GS twin (the reference),
#     rs_vo_ld on RS data: the line delay unknown, estimated online from 0 (configs/rs_vo_ld.json),
#     rs_vo_ld from a guess 20 % short (47.15 us),
#   and tabulate keyframe ATE after Sim(3) alignment, frames tracked, fps, the ratios and the final
#   line-delay estimate against the true 58.94 us.
#
# Usage: bash scripts/acceptance_rs.sh [OUT_DIR] [SEED ...]   (default out/acceptance_rs, seeds 1 2 3)
#   RSVIO_BIN  the binary (default build/bin/rsvio)   MOTIONS  "medium fast" (default) or one of them
#   POINTS     active points (default: the config's 800)
#   MODES      runs to make (default "rsvo_rs gsvo_rs gsvo_gs rsvold_rs rsvold08_rs")
# Datasets are simulated once into OUT_DIR/<motion>_<rs|gs>_s<seed> and reused; about 3.5 min each to
# simulate and 0.5-1 min per run on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/acceptance_rs}
shift || true
SEEDS=("$@")
[ ${#SEEDS[@]} -gt 0 ] || SEEDS=(1 2 3)
BIN=${RSVIO_BIN:-build/bin/rsvio}
MOTIONS=${MOTIONS:-"medium fast"}
MODES=${MODES:-"rsvo_rs gsvo_rs gsvo_gs rsvold_rs rsvold08_rs"}
[ -x "$BIN" ] || { echo "acceptance_rs: $BIN not found; run scripts/build.sh or set RSVIO_BIN" >&2; exit 2; }
mkdir -p "$OUT"
EXTRA=()
if [ -n "${POINTS:-}" ]; then EXTRA=(--set backend.active_points="$POINTS" --set frontend.points="$POINTS"); fi

simcfg() { case "$1" in medium) echo configs/sim/demo.json ;; fast) echo configs/sim/rs.json ;; esac; }

for motion in $MOTIONS; do
  for seed in "${SEEDS[@]}"; do
    for sh in rs gs; do
      data="$OUT/${motion}_${sh}_s$seed"
      [ -f "$data/truth.json" ] && continue
      echo "== simulating $(simcfg "$motion") ($sh), seed $seed -> $data"
      set_gs=()
      [ "$sh" = gs ] && set_gs=(--set effects.rolling_shutter=null)
      "$BIN" -q simulate --config "$(simcfg "$motion")" --seed "$seed" --out "$data" "${set_gs[@]}"
    done
    for mode in $MODES; do
      run="$OUT/run_${motion}_s${seed}_$mode"
      case $mode in
        rsvo_rs) cfg=configs/rs_vo.json; data="$OUT/${motion}_rs_s$seed"; sets=(--set shutter.params.line_delay_us=58.94) ;;
        gsvo_rs) cfg=configs/gs_vo.json; data="$OUT/${motion}_rs_s$seed"; sets=() ;;
        gsvo_gs) cfg=configs/gs_vo.json; data="$OUT/${motion}_gs_s$seed"; sets=() ;;
        rsvold_rs) cfg=configs/rs_vo_ld.json; data="$OUT/${motion}_rs_s$seed"; sets=() ;;
        rsvold08_rs) cfg=configs/rs_vo_ld.json; data="$OUT/${motion}_rs_s$seed"; sets=(--set shutter.params.line_delay_us=47.15) ;;
      esac
      echo "== $motion seed $seed $mode -> $run"
      "$BIN" -q run --config "$cfg" --data "$data" --out "$run" --set output.render=false "${sets[@]}" "${EXTRA[@]}" \
        || echo "   (run failed: see $run/report.json)"
    done
  done
done

python3 - "$OUT" "$MOTIONS" "${SEEDS[@]}" <<'EOF'
import json, sys, os, statistics
out, motions, seeds = sys.argv[1], sys.argv[2].split(), sys.argv[3:]
def rep(motion, seed, mode):
    p = os.path.join(out, "run_%s_s%s_%s" % (motion, seed, mode), "report.json")
    return json.load(open(p)) if os.path.exists(p) else None
def ate(r):
    return r.get("eval", {}).get("ate_rmse_m") if r else None
print()
print("%-7s %-5s %-9s %8s %7s %10s %6s %9s  %s" % ("motion", "seed", "mode", "status", "frames", "ATE (mm)", "fps",
                                                  "ld (us)", "error"))
for motion in motions:
    med = {}
    lds = {"rsvold_rs": [], "rsvold08_rs": []}
    for mode in ("rsvo_rs", "gsvo_rs", "gsvo_gs", "rsvold_rs", "rsvold08_rs"):
        vals = []
        for seed in seeds:
            r = rep(motion, seed, mode)
            if not r:
                print("%-7s %-5s %-9s  (no report)" % (motion, seed, mode)); continue
            a = ate(r)
            ok = r["status"] == "ok"
            vals.append(a if ok and a is not None else float("inf"))
            sh = r.get("extra", {}).get("shutter") or {}
            ld = sh.get("line_delay_us", float("nan"))
            if mode in lds: lds[mode].append(ld)
            print("%-7s %-5s %-9s %8s %7d %10.1f %6.1f %9.2f  %s" % (motion, seed, mode, r["status"], r.get("frames", 0),
                  1e3 * a if a is not None else float("nan"), r.get("fps", float("nan")), ld, r.get("error", "")[:90]))
        med[mode] = statistics.median(vals) if vals else float("nan")
    for mode, start in (("rsvold_rs", "0"), ("rsvold08_rs", "47.15 us")):
        v = lds[mode]
        if v and mode in med:
            print("%s line delay estimated from %s (true 58.94 us): %s us, errors %s %%; median ATE vs rs_vo given "
                  "%.2fx (goal: within 10 %%, 1.2x)" % (motion, start, ", ".join("%.2f" % x for x in v),
                  ", ".join("%+.1f" % (100 * (x / 58.94 - 1)) for x in v), med[mode] / med["rsvo_rs"]))
    g = med["gsvo_gs"]
    print("%s medians (failed = inf): rs_vo/RS %.1f mm, gs_vo/RS %.1f mm, gs_vo/GS %.1f mm; rs_vo vs twin %.2fx "
          "(goal <= max(1.3x, +3 mm)), gs_vo on RS vs twin %.1fx (goal >= 3x or failed)" %
          (motion, 1e3 * med["rsvo_rs"], 1e3 * med["gsvo_rs"], 1e3 * g, med["rsvo_rs"] / g, med["gsvo_rs"] / g))
EOF
