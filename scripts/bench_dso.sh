#!/usr/bin/env bash
# rsvio against DSO on the same simulated sequences (issue 17), outside CI. Benchmark only: nothing of
# DSO is in this repository; build it outside with ../shared/tools/dso/build.sh and give its binary.
#
# Sequences (`rsvio simulate`, global shutter, 640x512, 20 Hz, 20 s), seeds 1 2 3 by default:
#   medium  configs/sim/demo.json without its rolling shutter (0.6 m/s, 40 deg/s: accept_gs's motion)
#   fast    configs/sim/gs.json (the paper's Table I means: 0.9 m/s, 75 deg/s, 2.2 m/s^2, 267 deg/s^2)
# Runs: rsvio configs/gs_vo.json at POINTS active points (default 2000, DSO's setting) and 7 keyframes,
# 2 threads, no rendering; DSO (when given) preset 0, mode 1 through ../shared/tools/dso/run.sh.
# Figures: ATE (Sim(3), every frame with a pose, camera poses against the ground truth mapped through
# T_BS; `rsvio eval`), rsvio's own keyframe ATE too, fps (frames over wall time of the process),
# peak RSS (getrusage of the process), and the ratios rsvio / DSO of the medians per motion.
#
# Usage: scripts/bench_dso.sh [--dso DSO_BIN] [--out DIR] [--seeds "1 2 3"] [--motions "medium fast"]
#                             [--points N] [--rerun] [-- extra rsvio --set arguments]
#   DSO_BIN      env or --dso: dso_dataset built by ../shared/tools/dso/build.sh (none: rsvio only)
#   RSVIO_BIN    the binary (default build/bin/rsvio)
#   DSO_RUN      DSO's run script (default ../shared/tools/dso/run.sh next to the repository)
# Datasets are simulated once into OUT/data_<motion>_s<seed> and reused; runs are redone only with
# --rerun (or when their output is missing). Simulating takes 2-3 min per sequence on 2 cores, a run
# about a minute.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
OUT=out/bench_dso
SEEDS="1 2 3"
MOTIONS="medium fast"
POINTS=2000
RERUN=0
DSO_BIN=${DSO_BIN:-}
EXTRA=()
while [ $# -gt 0 ]; do
  case "$1" in
    --dso) DSO_BIN=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --seeds) SEEDS=$2; shift 2 ;;
    --motions) MOTIONS=$2; shift 2 ;;
    --points) POINTS=$2; shift 2 ;;
    --rerun) RERUN=1; shift ;;
    --) shift; EXTRA=("$@"); break ;;
    -h|--help) sed -n 2,22p "$0"; exit 0 ;;
    *) echo "bench_dso: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
BIN=${RSVIO_BIN:-build/bin/rsvio}
DSO_RUN=${DSO_RUN:-$ROOT/../shared/tools/dso/run.sh}
[ -x "$BIN" ] || { echo "bench_dso: $BIN not found; build first (scripts/build.sh) or set RSVIO_BIN" >&2; exit 2; }
if [ -n "$DSO_BIN" ]; then
  [ -x "$DSO_BIN" ] || { echo "bench_dso: DSO binary $DSO_BIN not found" >&2; exit 2; }
  [ -f "$DSO_RUN" ] || { echo "bench_dso: DSO run script $DSO_RUN not found (set DSO_RUN)" >&2; exit 2; }
fi
mkdir -p "$OUT"
EXTRA_SET=()
for a in "${EXTRA[@]+"${EXTRA[@]}"}"; do EXTRA_SET+=(--set "$a"); done

# Peak RSS (kB), wall seconds and exit code of a command, its output to a log.
measure() {  # measure LOG cmd...
  local log=$1; shift
  python3 -c 'import resource, subprocess, sys, time
t = time.monotonic()
with open(sys.argv[1], "w") as f:
    r = subprocess.run(sys.argv[2:], stdout=f, stderr=subprocess.STDOUT)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, "%.3f" % (time.monotonic() - t), r.returncode)' "$log" "$@"
}

for motion in $MOTIONS; do
  case "$motion" in
    medium) SIM=(--config configs/sim/demo.json --set effects.rolling_shutter=null) ;;
    fast) SIM=(--config configs/sim/gs.json) ;;
    *) echo "bench_dso: unknown motion $motion (medium, fast)" >&2; exit 2 ;;
  esac
  for seed in $SEEDS; do
    data="$OUT/data_${motion}_s$seed"
    if [ ! -f "$data/truth.json" ]; then
      echo "== simulating $motion seed $seed -> $data"
      "$BIN" -q simulate "${SIM[@]}" --seed "$seed" --out "$data"
    fi
    run="$OUT/rsvio_${motion}_s$seed"
    if [ $RERUN = 1 ] || [ ! -f "$run/measure.txt" ]; then
      echo "== rsvio gs_vo, $POINTS points, $motion seed $seed -> $run"
      rm -rf "$run"
      mkdir -p "$run"
      read -r kb wall rc < <(measure "$run/stdout.log" "$BIN" -q run --config configs/gs_vo.json --data "$data" \
          --out "$run" --set threads=2 --set backend.active_points="$POINTS" --set frontend.points="$POINTS" \
          --set backend.max_keyframes=7 --set output.render=false "${EXTRA_SET[@]+"${EXTRA_SET[@]}"}")
      echo "$kb $wall $rc" > "$run/measure.txt"
      if [ -f "$run/trajectory.tum" ]; then
        "$BIN" -q eval --data "$data" --est "$run/trajectory.tum" --align sim3 --json > "$run/eval_all.json" || true
      fi
    fi
    if [ -n "$DSO_BIN" ]; then
      drun="$OUT/dso_${motion}_s$seed"
      if [ $RERUN = 1 ] || [ ! -f "$drun/measure.txt" ]; then
        echo "== DSO, $motion seed $seed -> $drun"
        rm -rf "$drun"
        mkdir -p "$drun"
        read -r kb wall rc < <(DSO_BIN="$DSO_BIN" measure "$drun/run.log" bash "$DSO_RUN" "$data" "$drun")
        echo "$kb $wall $rc" > "$drun/measure.txt"
        if [ -f "$drun/trajectory_cam.tum" ]; then
          { echo "# frame: camera"; grep -v '^#' "$drun/trajectory_cam.tum"; } > "$drun/trajectory.tum"
          "$BIN" -q eval --data "$data" --est "$drun/trajectory.tum" --align sim3 --json > "$drun/eval_all.json" || true
        fi
      fi
    fi
  done
done

python3 - "$OUT" "$MOTIONS" "$SEEDS" "$POINTS" <<'EOF'
import json, os, statistics, sys
out, motions, seeds, points = sys.argv[1], sys.argv[2].split(), sys.argv[3].split(), sys.argv[4]

def load(path):
    try:
        return json.load(open(path))
    except Exception:
        return None

def ate_all(run):
    e = load(os.path.join(run, "eval_all.json"))
    if not e:
        return None, None
    # rsvio eval --json: {"ate": {"rmse_m": ...}, "associated": n} or flat keys; take what is there.
    for k in ("ate_rmse_m",):
        if k in e: return e[k], e.get("num_associated") or e.get("associated")
    a = e.get("ate") or {}
    return a.get("rmse_m"), e.get("num_associated") or e.get("associated") or a.get("n")

def frames_of(data):
    n = 0
    for l in open(os.path.join(data, "mav0/cam0/data.csv")):
        if l.strip() and not l.startswith("#"): n += 1
    return n

rows = []
for m in motions:
    for s in seeds:
        data = os.path.join(out, "data_%s_s%s" % (m, s))
        nf = frames_of(data)
        r = os.path.join(out, "rsvio_%s_s%s" % (m, s))
        if os.path.exists(os.path.join(r, "measure.txt")):
            kb, wall, rc = open(os.path.join(r, "measure.txt")).read().split()
            rep = load(os.path.join(r, "report.json")) or {}
            ate, _ = ate_all(r)
            ekf = (rep.get("eval") or {}).get("ate_rmse_m")
            rows.append(dict(m=m, s=s, sys="rsvio", status=rep.get("status", "?"), frames=rep.get("frames_tracked", rep.get("frames")),
                             kf=rep.get("keyframes"), ate=ate, ate_kf=ekf, fps=nf / float(wall), fps_own=rep.get("fps"),
                             rss=int(kb) / 1024.0, pts=(rep.get("points_active_mean") or rep.get("active_points_mean"))))
        d = os.path.join(out, "dso_%s_s%s" % (m, s))
        if os.path.exists(os.path.join(d, "measure.txt")):
            kb, wall, rc = open(os.path.join(d, "measure.txt")).read().split()
            summ = {}
            if os.path.exists(os.path.join(d, "summary.txt")):
                for l in open(os.path.join(d, "summary.txt")):
                    p = l.split(None, 1)
                    if len(p) == 2: summ[p[0]] = p[1].strip()
            ate, _ = ate_all(d)
            lost = "LOST" in summ.get("frames_processed", "")
            rows.append(dict(m=m, s=s, sys="DSO", status="lost" if lost else ("ok" if rc == "0" else "exit " + rc),
                             frames=summ.get("frames_with_pose"), kf=None, ate=ate, ate_kf=None,
                             fps=float(summ["fps"]) if "fps" in summ else None, fps_own=None,
                             rss=float(summ["peak_rss_mb"]) if "peak_rss_mb" in summ else int(kb) / 1024.0, pts=None))

def f(v, fmt):
    return fmt % v if v is not None else "-"

print()
print("rsvio gs_vo at %s points / 7 keyframes vs DSO preset 0 (2000 points, 7 keyframes), 2 threads each" % points)
print("%-7s %-4s %-6s %-8s %7s %5s %10s %10s %7s %9s" % ("motion", "seed", "system", "status", "frames", "kf",
      "ATE mm", "ATE kf mm", "fps", "RSS MB"))
for r in rows:
    print("%-7s %-4s %-6s %-8s %7s %5s %10s %10s %7s %9s" % (r["m"], r["s"], r["sys"], r["status"], f(r["frames"], "%s"),
          f(r["kf"], "%s"), f(r["ate"] and r["ate"] * 1e3, "%.2f"), f(r["ate_kf"] and r["ate_kf"] * 1e3, "%.2f"),
          f(r["fps"], "%.1f"), f(r["rss"], "%.0f")))

def med(vals):
    vals = [v for v in vals if v is not None]
    if not vals: return None, None, None
    return statistics.median(vals), min(vals), max(vals)

print()
print("medians over the seeds [min - max]; ratio = rsvio / DSO (ATE: < 1 is better; fps: > 1 is better)")
print("%-7s %-6s %22s %22s %20s" % ("motion", "system", "ATE mm", "fps", "peak RSS MB"))
for m in motions:
    meds = {}
    for sysname in ("rsvio", "DSO"):
        rs = [r for r in rows if r["m"] == m and r["sys"] == sysname]
        if not rs: continue
        a = med([r["ate"] * 1e3 if r["ate"] is not None else None for r in rs])
        fp = med([r["fps"] for r in rs])
        ms = med([r["rss"] for r in rs])
        meds[sysname] = (a, fp, ms)
        g = lambda t, fmt: ("%s [%s - %s]" % (fmt % t[0], fmt % t[1], fmt % t[2])) if t[0] is not None else "-"
        print("%-7s %-6s %22s %22s %20s" % (m, sysname, g(a, "%.2f"), g(fp, "%.1f"), g(ms, "%.0f")))
    if "rsvio" in meds and "DSO" in meds:
        (a1, f1, m1), (a2, f2, m2) = meds["rsvio"], meds["DSO"]
        rat = lambda x, y: "%.2f" % (x / y) if x is not None and y else "-"
        print("%-7s %-6s %22s %22s %20s" % (m, "ratio", rat(a1[0], a2[0]), rat(f1[0], f2[0]), rat(m1[0], m2[0])))
print("\nATE: Sim(3)-aligned RMSE over every frame with a pose (rsvio eval); 'ATE kf': rsvio's report.json (keyframes).")
print("fps: input frames / wall time of the whole process; a run that stopped early still divides all frames.")
EOF
