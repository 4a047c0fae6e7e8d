#!/usr/bin/env bash
# Soak test (not in CI): the paper's cup (scenes/paper/cup.json, full size: 65,535 particles,
# 2,022 tetrahedra) for a long simulated time, then checks of its gauges and of the process's
# memory. docs/validation.md ("Soak") records what was run and measured.
#
#   scripts/soak.sh [--duration S] [--out DIR] [--bin PATH] [--threads N] [--scene FILE]
#                   [--resume]
#   scripts/soak.sh --check DIR   # the checks again on a finished (or stopped) soak's folder
#
# The run writes a checkpoint every 0.5 s of simulated time (CHECKPOINT_EVERY), so a soak
# stopped by hand or by the machine goes on with --resume (same --out) from its last one, in
# as many sittings as it takes; memory.csv numbers each sitting.
#
# Exit code 0: every check passed; 1: one failed; 3: none failed, but the run ended before the
# pour did, so momentum and memory after it were not checked. Defaults: 60 s simulated, out/soak, build/release/bin/sphfem, all cores. Checks:
# - every gauge value of every frame is finite, and the run exits with code 0;
# - leaks: `leaked` (crossed + inside a body) is 0 in every frame;
# - momentum: once the pour has ended and the water has settled (the last half of the frames
#   after the emitter's end), the total momentum (fluid + cup) neither drifts nor grows: its
#   least-squares trend per second, and its largest magnitude, stay below TOL (default 1 %) of
#   the momentum of the poured water falling at 1 m/s (M * 1 m/s);
# - memory: the resident size, sampled every 5 s with the simulated time reached, grows by less
#   than 5 % from the first sample after the pour to the last (the buffers are reserved at the
#   start, but pages become resident as the emitter fills them; after the pour it must be flat).
set -euo pipefail
cd "$(dirname "$0")/.."

duration=60 out=out/soak bin=build/release/bin/sphfem threads=0 scene=scenes/paper/cup.json
tol=${TOL:-0.01}
every=${CHECKPOINT_EVERY:-0.5}
check_only="" resume=""
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --bin) bin=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --scene) scene=$2; shift 2 ;;
    --check) check_only=1; out=$2; shift 2 ;;
    --resume) resume=1; shift ;;
    *) echo "soak: unknown option $1 (see the top of $0)" >&2; exit 2 ;;
  esac
done
log="$out/soak.log" mem="$out/memory.csv"
if [ -n "$check_only" ]; then
  # A run stopped by hand has no exit line: its frames are checked as far as they go.
  code=$(sed -n 's/^soak: run exited with code \([0-9]*\).*/\1/p' "$log" | tail -1)
  code=${code:-0}
else
[ -x "$bin" ] || { echo "soak: no $bin; build first (make build) or pass --bin" >&2; exit 2; }

mkdir -p "$out"
sitting=0
if [ -n "$resume" ] && [ -f "$out/checkpoint.bin" ] && [ -f "$mem" ]; then
  sitting=$(( $(tail -n 1 "$mem" | cut -d, -f4) + 1 ))
  echo "soak: sitting $sitting resumes from $out/checkpoint.bin" | tee -a "$log"
  more=(--resume)
else
  [ -n "$resume" ] && echo "soak: nothing to resume in $out; starting afresh" >&2
  echo "wall_s,rss_kib,sim_s,sitting" > "$mem"
  : > "$log"
  more=()
fi
start=$(date +%s)
"$bin" run "$scene" --out "$out" --duration "$duration" --threads "$threads" --quiet \
  --checkpoint-every "$every" "${more[@]}" >> "$log" 2>&1 &
pid=$!
while kill -0 "$pid" 2>/dev/null; do
  rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
  sim=$(tail -n 1 "$out/gauges.csv" 2>/dev/null | cut -d, -f1 || true)
  [ -n "$rss" ] && echo "$(( $(date +%s) - start )),$rss,${sim:-0},$sitting" >> "$mem"
  sleep 5
done
set +e
wait "$pid"
code=$?
set -e
wall=$(( $(date +%s) - start ))
echo "soak: run exited with code $code after $wall s wall" | tee -a "$log"
fi

python3 - "$out" "$scene" "$code" "$tol" <<'PY'
import csv, json, math, re, sys
out, scene_path, code, tol = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
rows = list(csv.DictReader(open(f"{out}/gauges.csv")))
text = re.sub(r"//[^\n]*|/\*.*?\*/", "", open(scene_path).read(), flags=re.S)
scene = json.loads(text)
fluid = scene.get("fluid", {})
end = max((e.get("end", 1e30) for e in fluid.get("emitters", [])), default=0.0)
r = fluid.get("particle_radius", 0.005)
rho0 = fluid.get("rest_density", 1000.0)
failures = []

bad = [(row["time"], k) for row in rows for k, v in row.items() if not math.isfinite(float(v))]
if bad: failures.append(f"non-finite values, first at t = {bad[0][0]} s in {bad[0][1]}")
leaked = max(float(row.get("leaked", 0)) for row in rows)
if leaked > 0: failures.append(f"leaks: up to {leaked:g} particles in a frame")

t = [float(row["time"]) for row in rows]
n = [float(row["n_fluid"]) for row in rows]
p = [[float(row[f"momentum_total_{c}"]) for c in "xyz"] for row in rows]
mass = n[-1] * rho0 * (2 * r) ** 3  # the lattice holds rho0 at one particle per (2r)^3
scale = mass * 1.0
settled = [i for i, ti in enumerate(t) if ti > end]
settled = settled[len(settled) // 2:]
trend = peak = float("nan")
if len(settled) >= 3:
    ts = [t[i] for i in settled]
    tm = sum(ts) / len(ts)
    trend = 0.0
    for c in range(3):
        ps = [p[i][c] for i in settled]
        pm = sum(ps) / len(ps)
        slope = sum((a - tm) * (b - pm) for a, b in zip(ts, ps)) / sum((a - tm) ** 2 for a in ts)
        trend = max(trend, abs(slope))
    peak = max(math.sqrt(sum(x * x for x in p[i])) for i in settled)
    if trend > tol * scale: failures.append(f"momentum drifts by {trend:.3g} kg m/s per s")
    if peak > tol * scale: failures.append(f"momentum reaches {peak:.3g} kg m/s at rest")

mem = list(csv.DictReader(open(f"{out}/memory.csv")))
# Within each sitting (a process of its own), from its first sample after the pour to its last;
# the largest growth of them.
after = [m for m in mem if float(m.get("sim_s") or 0) > end]
growth = float("nan")
for s in sorted({m.get("sitting", "0") for m in after}):
    mine = [m for m in after if m.get("sitting", "0") == s]
    if len(mine) < 2: continue
    a, b = float(mine[0]["rss_kib"]), float(mine[-1]["rss_kib"])
    g = (b - a) / a
    growth = g if math.isnan(growth) else max(growth, g)
if growth > 0.05: failures.append(f"memory grew {100 * growth:.1f} % after the pour")
if code != 0: failures.append(f"the run exited with code {code}")

print(f"soak: {t[-1]:g} s simulated, {len(rows)} frames, {n[-1]:.0f} particles ({mass:.2f} kg)")
print(f"soak: leaked max {leaked:g}; settled frames {len(settled)}: momentum trend "
      f"{trend:.3g} kg m/s per s, largest {peak:.3g} kg m/s (limit {tol * scale:.3g})")
print(f"soak: resident memory {mem[0]['rss_kib'] if mem else '?'} .. "
      f"{mem[-1]['rss_kib'] if mem else '?'} KiB; after the pour ({len(after)} samples): "
      f"growth {100 * growth:.2f} %")
if not settled: print(f"soak: the run did not reach the end of the pour (t = {end:g} s): "
                      "momentum and memory after it are not checked")
ms = [float(row["ms_step"]) for row in rows[1:] if float(row["ms_step"]) > 0]
if ms: print(f"soak: ms per step: mean {sum(ms) / len(ms):.1f}, max {max(ms):.1f}")
for f in failures: print("soak: FAIL:", f)
if failures: print("soak: failed")
elif not settled: print("soak: incomplete (no failure so far)")
else: print("soak: ok")
sys.exit(1 if failures else (3 if not settled else 0))
PY
