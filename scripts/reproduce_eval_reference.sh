#!/usr/bin/env bash
# Re-runs `rsvio eval` on the reference trajectory pairs in ../shared/data/eval-reference (with the
# figures its README lists) and ../shared/data/eval-extra, and prints pairs, ATE RMSE and the difference
# to the listed figure. Not part of CI (the test tests/framework/eval/reference_test.cpp is).
# Usage: scripts/reproduce_eval_reference.sh   (RSVIO_BIN, else $RSVIO_BUILD_DIR/bin/rsvio, else build/bin/rsvio;
#        RSVIO_SHARED_DIR, else ../shared next to the repository)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=${RSVIO_BIN:-$ROOT/${RSVIO_BUILD_DIR:-build}/bin/rsvio}
SHARED=${RSVIO_SHARED_DIR:-$ROOT/../shared}
[ -x "$BIN" ] || { echo "rsvio binary not found at $BIN (build first: scripts/build.sh, or set RSVIO_BIN)" >&2; exit 2; }
REF=$SHARED/data/eval-reference
EXTRA=$SHARED/data/eval-extra
[ -d "$REF" ] || { echo "reference data not found at $REF (set RSVIO_SHARED_DIR)" >&2; exit 2; }

# gt est align expected(empty: none listed)
CASES="
$REF/fr2_desk_groundtruth.txt $REF/fr2_desk_ORB.txt none 3.173994
$REF/fr2_desk_groundtruth.txt $REF/fr2_desk_ORB.txt se3 0.008119
$REF/fr2_desk_groundtruth.txt $REF/fr2_desk_ORB.txt sim3 0.006123
$REF/V102_groundtruth.csv $REF/V102.txt none 2.554174
$REF/V102_groundtruth.csv $REF/V102.txt se3 0.091727
$REF/V102_groundtruth.csv $REF/V102.txt sim3 0.083841
$EXTRA/freiburg1_xyz-groundtruth.txt $EXTRA/freiburg1_xyz-rgbdslam_drift.txt none -
$EXTRA/freiburg1_xyz-groundtruth.txt $EXTRA/freiburg1_xyz-rgbdslam_drift.txt se3 -
$EXTRA/freiburg1_xyz-groundtruth.txt $EXTRA/freiburg1_xyz-rgbdslam_drift.txt sim3 -
"
printf '%-34s %-5s %6s %14s %10s %10s %10s\n' estimate align pairs "ATE RMSE (m)" scale listed diff
status=0
while read -r gt est align expected; do
  [ -n "${gt:-}" ] || continue
  # --json prints keys in alphabetical order: the first "pairs" is the association's, "scale" the alignment's.
  out=$("$BIN" eval --gt "$gt" --est "$est" --align "$align" --json)
  field() { sed -n "s/^ *\"$1\": \([-0-9.e+]*\),\{0,1\}$/\1/p" <<<"$out" | head -1; }
  pairs=$(field pairs)
  rmse=$(printf '%.9f' "$(field ate_rmse_m)")
  scale=$(printf '%.6f' "$(field scale)")
  if [ "$expected" = "-" ]; then
    diff="-"
  else
    diff=$(awk -v a="$rmse" -v b="$expected" 'BEGIN { d = a - b; printf "%.1e", d }')
    awk -v a="$rmse" -v b="$expected" 'BEGIN { d = a - b; exit !(d > 1e-5 || d < -1e-5) }' && status=1
  fi
  printf '%-34s %-5s %6s %14s %10s %10s %10s\n' "$(basename "$est")" "$align" "$pairs" "$rmse" "$scale" "$expected" "$diff"
done <<<"$CASES"
[ $status -eq 0 ] && echo "all listed figures reproduced to 1e-5 m" || echo "MISMATCH: a listed figure differs by more than 1e-5 m"
exit $status
