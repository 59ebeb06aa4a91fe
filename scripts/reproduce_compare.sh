#!/usr/bin/env bash
# Re-runs a comparison grid with `rsvio compare` and prints its table, so a figure quoted in a closing
# note can be reproduced by anyone. Not part of CI.
# Usage:
#   scripts/reproduce_compare.sh OUT --configs A.json B.json --data D1 D2 [--runs N] [--jobs J]
#       runs that grid into OUT;
#   scripts/reproduce_compare.sh OUT --from OLD_OUT/compare.json
#       runs the grid recorded in an earlier compare.json ("invocation") again into OUT.
# RSVIO_BIN, else $RSVIO_BUILD_DIR/bin/rsvio, else build/bin/rsvio. Exit code: that of rsvio compare
# (0 all runs ok, 1 some failed, 2 usage error).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=${RSVIO_BIN:-$ROOT/${RSVIO_BUILD_DIR:-build}/bin/rsvio}
[ -x "$BIN" ] || { echo "rsvio binary not found at $BIN (build first: scripts/build.sh, or set RSVIO_BIN)" >&2; exit 2; }
[ $# -ge 2 ] || { sed -n '2,12p' "$0" >&2; exit 2; }
OUT=$1; shift
if [ "$1" = "--from" ]; then
  [ -f "${2:-}" ] || { echo "no such file: ${2:-}" >&2; exit 2; }
  # The recorded invocation, turned back into arguments (python3 reads the JSON; nothing else needs it).
  mapfile -t ARGS < <(python3 - "$2" <<'PY'
import json, sys
inv = json.load(open(sys.argv[1]))["invocation"]
print("--configs"); [print(c) for c in inv["configs"]]
print("--data"); [print(d) for d in inv["data"]]
for k in ("runs", "jobs"):
    print("--" + k); print(inv[k])
print("--timeout-s"); print(inv["timeout_s"])
PY
)
  set -- "${ARGS[@]}"
fi
set +e
"$BIN" compare "$@" --out "$OUT"
rc=$?
set -e
exit $rc
