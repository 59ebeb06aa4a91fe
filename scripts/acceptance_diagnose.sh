#!/usr/bin/env bash
# Acceptance of the diagnosis loop (issue 15) at 640x512, 20 s, medium motion (as configs/sim/demo.json):
# for each effect and seed, simulate with the effect hidden, run the model without its plugin, diagnose
# from the run folder alone, run again with the named line, compare (diagnose --against). Clean data
# with 5 seeds (gs_vo with and without affine brightness) must give verdict none. Prints the verdict table; not part of CI (about 2 min per case
# on 2 cores).
#
#   scripts/acceptance_diagnose.sh [OUT]          (default out/acceptance_diagnose)
#   EFFECTS="exposure vignetting" SEEDS="1 2 3" CLEAN_SEEDS="1 2 3 4 5" scripts/acceptance_diagnose.sh
#   EFFECTS=time_offset CLEAN=clean_vio CLEAN_SEEDS="1 2 3" scripts/acceptance_diagnose.sh out/acc_toff
#
# Effects: rolling_shutter (rs.json, 58.94 us per row = 30 ms readout), exposure (exposure.json, +-1 stop
# over 8 s, 0.05 stops jitter), vignetting (vignette.json, corner at half), response (response.json,
# gamma 2.2), rs_exposure (rs.json plus exposure.json's effect: two hidden effects, diagnosed in up to 3
# rounds, one row each: both named one after the other, then none). "ratio" is ATE before / after; it
# compares unequal spans when the before run failed; "same span" is that ratio over the frames both
# runs tracked (diagnose --against's common span), with the before-run's poses there. ROUNDS=2 diagnoses every after-run once more.
# time_offset (time_offset.json: 15 ms) and clean_vio start from configs/default.json (visual-inertial,
# offset not estimated): run them with EFFECTS="time_offset" CLEAN="clean_vio".
# START=default (a config name under configs/) starts every case from that config instead.
# The "before" model is configs/gs_vo.json for the visual effects; for exposure without affine
# brightness (--set photometric.affine=null), since gs_vo already models it (rs_exposure too).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${RSVIO_BIN:-$ROOT/build/bin/rsvio}"
OUT="${1:-out/acceptance_diagnose}"
EFFECTS="${EFFECTS:-rolling_shutter exposure vignetting response rs_exposure}"
SEEDS="${SEEDS:-1 2 3}"
CLEAN_SEEDS="${CLEAN_SEEDS:-1 2 3 4 5}"
CFG="$ROOT/configs"
MOTION=(--set motion.mean_speed_m_s=0.6 --set motion.mean_rot_speed_deg_s=40.0
        --set motion.mean_accel_m_s2=1.0 --set motion.mean_rot_accel_deg_s2=150.0)
mkdir -p "$OUT"
TABLE="$OUT/table.txt"

simcfg() {
  case "$1" in
    rolling_shutter|rs_exposure) echo "$CFG/sim/rs.json" ;;
    exposure) echo "$CFG/sim/exposure.json" ;;
    vignetting) echo "$CFG/sim/vignette.json" ;;
    response) echo "$CFG/sim/response.json" ;;
    time_offset) echo "$CFG/sim/time_offset.json" ;;
    clean|clean_noaffine|clean_vio) echo "$CFG/sim/gs.json" ;;
  esac
}
# The rolling-shutter sequence with the exposure effect of exposure.json added (two hidden effects).
EXPOSURE_EFFECT='effects.exposure={"plugin":"effect.exposure","params":{"amplitude_stops":1.0,"period_s":8.0,"jitter_stops":0.05}}'
sim_sets() { case "$1" in rs_exposure) echo "--set $EXPOSURE_EFFECT" ;; esac; }
simname() { case "$1" in rs_exposure) echo rs_exposure ;; *) basename "$(simcfg "$1")" .json ;; esac; }
# Rounds of diagnosis per case: 3 for two hidden effects (both named, then none) and for vignetting (a
# run with a fixed polynomial is named again for what it left; with the online estimate one round
# suffices and the second gives none), else 1 unless ROUNDS says otherwise (ROUNDS=2 checks that the
# second diagnosis gives none).
rounds() { case "$1" in rs_exposure|vignetting) echo 3 ;; *) echo "${ROUNDS:-1}" ;; esac; }
model() {
  if [ -n "${START:-}" ]; then echo "$CFG/$START.json"; return; fi
  case "$1" in time_offset|clean_vio) echo "$CFG/default.json" ;; *) echo "$CFG/gs_vo.json" ;; esac
}
base_sets() { case "$1" in exposure|rs_exposure|clean_noaffine) echo "--set photometric.affine=null" ;; esac; }

field() {  # field JSON_FILE PYTHON_EXPR
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print($2)" "$1"
}

# ATE in m; a failed run shows "F<frames>" (lost after that many frames; its ATE covers only those).
ate_of() {
  field "$1" "('%.4f' % d['eval']['ate_rmse_m'] if 'eval' in d else 'n/a') + ('' if d['status'] == 'ok' else ' F%d' % d['frames'])"
}

# "ratio": whole-run ATE before / after (unequal spans when a run failed); "same span": the same ratio
# over the frames both runs tracked, with the before-run's pose count in that span (diagnose --against).
printf "%-16s %4s %-16s %-44s %12s %12s %8s %14s %s\n" effect seed verdict "top: statistic / threshold (score)" \
  "ATE before" "ATE after" ratio "same span" "evidence" | tee "$TABLE"

# One case: run the model, diagnose, add the named line, run again, compare (diagnose --against), and
# repeat while the verdict names an effect (at most 3 rounds: two hidden effects need two), one table
# row per round. A round's "ATE before" is the run it diagnosed, "ATE after" the run with its line added.
one() {
  local effect=$1 seed=$2
  local d="$OUT/$effect-$seed"
  local data="$OUT/data-$(simname "$effect")-$seed"
  mkdir -p "$d"
  if [ ! -f "$data/.complete" ]; then  # simulated once per (config, seed), reused by later calls
    rm -rf "$data"
    # shellcheck disable=SC2046
    "$BIN" simulate --config "$(simcfg "$effect")" --out "$data" --seed "$seed" "${MOTION[@]}" $(sim_sets "$effect") \
      > "$d/sim.log" 2>&1
    touch "$data/.complete"
  fi
  local sets run="$d/before" round
  sets="$(base_sets "$effect")"
  # shellcheck disable=SC2086
  "$BIN" run --config "$(model "$effect")" --data "$data" --out "$run" $sets > "$d/before.log" 2>&1 || true
  for round in 1 2 3; do
    local diag="$d/diagnose$round.json" verdict line top ate_b ate_a="-" ratio="-" span="-" ev="-" next="$d/after$round"
    [ "$round" = 1 ] && diag="$d/diagnose.json" && next="$d/after"
    "$BIN" diagnose --run "$run" --json > "$diag" 2> "${diag%.json}.err" || true
    verdict=$(field "$diag" "d['verdict']")
    top=$(field "$diag" "(lambda e: '%s %.3g / %.3g (%.2f)' % (e['effect'], e['statistic'], e['threshold'], e['score']))(d['ranking'][0]) if d['ranking'] else '-'")
    ate_b=$(ate_of "$run/report.json")
    if [ "$verdict" != none ]; then
      line=$(field "$diag" "d['config_line']")
      sets="$sets $line"
      # shellcheck disable=SC2086
      "$BIN" run --config "$(model "$effect")" --data "$data" --out "$next" $sets > "$next.log" 2>&1 || true
      "$BIN" diagnose --run "$next" --against "$run" --json > "$next/against.json" 2>/dev/null || true
      ate_a=$(ate_of "$next/report.json")
      ratio=$(field "$next/against.json" "'%.2f' % d['against']['ate_ratio'] if 'ate_ratio' in d['against'] else '-'")
      span=$(field "$next/against.json" "(lambda c: '%.2f (%d)' % (c['ate_ratio'], c['frames_before']) if 'ate_ratio' in c else '-')(d['against'].get('common_span', {}))")
      ev=$(field "$next/against.json" "('gone' if d['against']['evidence_gone'] else 'still there') if 'evidence_gone' in d['against'] else '-'")
    fi
    local label="$seed"
    [ "$round" != 1 ] && label="$seed.$round"
    printf "%-16s %4s %-16s %-44s %12s %12s %8s %14s %s\n" "$effect" "$label" "$verdict" "$top" "$ate_b" "$ate_a" "$ratio" "$span" \
      "$ev" | tee -a "$TABLE"
    [ "$verdict" = none ] && break
    [ "$round" -ge "$(rounds "$effect")" ] && break
    run="$next"
  done
}

for e in $EFFECTS; do for s in $SEEDS; do one "$e" "$s"; done; done
CLEAN="${CLEAN:-clean clean_noaffine}"
for s in $CLEAN_SEEDS; do for c in $CLEAN; do one "$c" "$s"; done; done
echo "table: $TABLE (per case: $OUT/<effect>-<seed>/{before,after,diagnose.json,against.json})"
