#!/usr/bin/env bash
# The GPU check: everything a short window on a GPU machine should run, in one go, writing
# every result into one folder. Its CPU path (--backend cpu --small) runs in CI so it cannot rot.
#
#   scripts/gpu-check.sh bundle BUILD BUNDLE
#       Here, after building BUILD with CUDA (cmake --preset cuda-hopper): copies the CLI, the
#       test binary and the shared libraries they load (not the C library or the GPU driver,
#       which the GPU machine has) into BUNDLE/bin and BUNDLE/lib, for a machine that lacks
#       the Debian packages. Carry BUNDLE over with the repository.
#   scripts/gpu-check.sh run [--backend cuda|cpu] [--small] [--bin DIR] [--out DIR]
#       On the GPU machine, from the repository's root: the CUDA tests (each in its own
#       process, so one sticky fault cannot fail the rest), a compute-sanitizer memcheck of a
#       small scene, `sphfem bench --paper`, the dam-break benchmark, and a scaling run
#       (65k, 1M and 4M particles with 2k, 100k and 400k tetrahedra). DIR is a bundle or a
#       build folder (bin/sphfem, tests/sphfem_tests). --small shrinks every size for a CPU.
#       Each part has its own time limit, the whole stays under 8 minutes on an H100/H200.
#       Exit status: 0 when every part passed, 1 otherwise; OUT/summary.txt says which.
set -uo pipefail

die() { echo "gpu-check: $*" >&2; exit 2; }

bundle() {
  local build=$1 out=$2
  [ -x "$build/bin/sphfem" ] || die "$build/bin/sphfem not found; build first (cmake --preset cuda-hopper && cmake --build --preset cuda-hopper)"
  mkdir -p "$out/bin" "$out/lib"
  cp "$build/bin/sphfem" "$out/bin/"
  [ -x "$build/tests/sphfem_tests" ] && cp "$build/tests/sphfem_tests" "$out/bin/"
  # Every library the binaries load, except the C runtime and the driver (libcuda comes with
  # the GPU's driver and must match it).
  for b in "$out"/bin/*; do
    ldd "$b" | awk '/=> \// {print $3}'
  done | sort -u | grep -Ev '/(libc|libm|libdl|libpthread|librt|ld-linux[^/]*|libcuda)\.so' |
    while read -r lib; do cp -L "$lib" "$out/lib/"; done
  du -sh "$out" | awk '{print "gpu-check: bundle " $2 ": " $1}'
}

backend=cuda
small=0
bin=""
out=out/gpu-check

run_all() {
  while [ $# -gt 0 ]; do
    case $1 in
      --backend) backend=$2; shift 2 ;;
      --small) small=1; shift ;;
      --bin) bin=$2; shift 2 ;;
      --out) out=$2; shift 2 ;;
      *) die "unknown option $1 (see the top of this script)" ;;
    esac
  done
  [ "$backend" = cuda ] || [ "$backend" = cpu ] || die "--backend must be cuda or cpu"
  if [ -z "$bin" ]; then
    for d in build/cuda build/release; do [ -x "$d/bin/sphfem" ] && bin=$d && break; done
  fi
  local cli test
  cli=$(ls "$bin/bin/sphfem" 2>/dev/null) || die "no sphfem under --bin '$bin'"
  test=$(ls "$bin/bin/sphfem_tests" "$bin/tests/sphfem_tests" 2>/dev/null | head -1)
  [ -n "$test" ] || die "no sphfem_tests under --bin '$bin'"
  [ -d "$bin/lib" ] && export LD_LIBRARY_PATH="$PWD/$bin/lib:${LD_LIBRARY_PATH:-}"
  # The tests read scenes and data from this checkout, wherever the binary was built.
  export SPHFEM_SOURCE_DIR="$PWD" SPHFEM_CLI="$PWD/$cli" OMP_WAIT_POLICY=passive
  [ "$backend" = cuda ] && export SPHFEM_CUDA_CHECK=1
  mkdir -p "$out"
  summary="$out/summary.txt"
  : >"$summary"
  failed=0
  {
    echo "gpu-check $(date -u +%Y-%m-%dT%H:%M:%SZ) backend=$backend small=$small"
    uname -srm
    grep -m1 'model name' /proc/cpuinfo || true
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader
  } >>"$summary" 2>&1

  # Limits: 180 + 60 + 120 + 40 + 90 s = 8 min at most on a GPU.
  part tests 180 run_tests "$test"
  part memcheck 60 run_memcheck "$cli"
  part paper_table1 $([ $small = 1 ] && echo 300 || echo 120) run_paper "$cli"
  part dam_break 40 run_dam_break "$cli"
  part scaling 90 run_scaling "$cli"
  cat "$summary"
  return $failed
}

# part NAME SECONDS FUNCTION ARGS...: runs one part with its own limit and log.
part() {
  local name=$1 limit=$2
  shift 2
  local t0=$SECONDS
  ( "$@" ) >"$out/$name.log" 2>&1 &
  local pid=$! waited=0
  while kill -0 $pid 2>/dev/null; do
    if [ $waited -ge "$limit" ]; then
      pkill -TERM -P $pid 2>/dev/null; kill -TERM $pid 2>/dev/null
      echo "time limit of $limit s" >>"$out/$name.log"
      break
    fi
    sleep 1
    waited=$((waited + 1))
  done
  wait $pid
  local rc=$?
  [ $rc -eq 0 ] || failed=1
  printf '%-14s %s  %4d s  (%s)\n' "$name" "$([ $rc -eq 0 ] && echo pass || echo "FAIL rc=$rc")" \
    $((SECONDS - t0)) "$out/$name.log" >>"$summary"
}

# Every test that runs the CUDA backend, each in its own process: a kernel fault is sticky and
# would fail every later test of the same process. On a CPU they skip, saying why.
run_tests() {
  # Backend-parametrised tests run their Cuda instances; the Cpu ones run in make test.
  local test=$1 filter='*Cuda*:*Backends*:FemBackend*-*/Cpu' rc=0 name log
  local names
  names=$("$test" --gtest_list_tests --gtest_filter="$filter" |
    awk '/^[^ ]/ {suite=$1} /^  / {print suite $1}')
  [ -n "$names" ] || { echo "no CUDA tests found"; return 1; }
  for name in $names; do
    log="$out/test_$(echo "$name" | tr '/' '_').log"
    if "$test" --gtest_filter="$name" >"$log" 2>&1; then
      if grep -q '^\[  SKIPPED \]' "$log"; then
        echo "skip  $name: $(grep -m1 -A1 'Skipped' "$log" | tail -1)"
      else
        echo "ok    $name"
      fi
    else
      echo "FAIL  $name"; tail -20 "$log"; rc=1
    fi
  done
  return $rc
}

# A small coupled scene under compute-sanitizer's memcheck (out-of-bounds and misaligned
# accesses, leaks of device memory).
run_memcheck() {
  local cli=$1
  if [ "$backend" != cuda ]; then echo "skipped: memcheck needs the CUDA backend"; return 0; fi
  local cs
  cs=$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null) ||
    { echo "compute-sanitizer not found"; return 1; }
  "$cs" --tool memcheck --error-exitcode 1 --leak-check full \
    "$cli" run scenes/paper/cup.json --backend cuda --duration 0.004 --quiet --out "$out/memcheck_run"
}

run_paper() {
  local cli=$1
  if [ $small = 1 ]; then
    # One scene, a small block: the harness, not the numbers (on a CPU the tank's wall samples
    # cost most of a step whatever the block).
    mkdir -p "$out/paper_scenes"
    cp scenes/paper/cup.json "$out/paper_scenes/"
    "$cli" bench --paper --backend "$backend" --method raytraced --particles-per-side 12 \
      --steps 2 --scenes "$out/paper_scenes" --out "$out"
  else
    "$cli" bench --paper --backend "$backend" --method all --out "$out"
  fi
}

run_dam_break() {
  local cli=$1
  if [ $small = 1 ]; then
    "$cli" bench --backend "$backend" --solver both --particles-per-side 16 --steps 5 --out "$out"
  else
    "$cli" bench --backend "$backend" --solver both --out "$out"
  fi
}

# Fluid blocks of n^3 particles (r = 1 cm) with a soft ball of about 3.1 R^3 tetrahedra
# resting in them; ms per step from the gauges of a short run.
run_scaling() {
  local cli=$1 sizes
  if [ $small = 1 ]; then sizes="20:6 30:9"; else sizes="40:9 100:32 159:51"; fi
  echo "particles_per_side,ball_resolution,particles,tetrahedra,steps,ms_per_step"
  for s in $sizes; do
    local n=${s%%:*}
    local res=${s##*:}
    local dir="$out/scaling_$n"
    mkdir -p "$dir"
    awk -v n="$n" -v res="$res" 'BEGIN {
      side = n * 0.02; h = side / 2;
      printf "{\"name\": \"scaling %d\", \"simulation\": {\"solver\": \"wcsph\", \"dt_max\": 0.001, \"duration\": 0.02},\n", n;
      printf " \"fluid\": {\"particle_radius\": 0.01, \"blocks\": [{\"min\": [0, 0, 0], \"max\": [%g, %g, %g]}]},\n", side, side, side;
      printf " \"domain\": {\"min\": [0, 0, 0], \"max\": [%g, %g, %g]},\n", side, 1.5 * side, side;
      printf " \"bodies\": [{\"name\": \"ball\", \"shape\": \"sphere\", \"position\": [%g, %g, %g], \"radius\": %g, \"resolution\": %d,\n", h, side, h, side / 4, res;
      printf "   \"material\": {\"density\": 500, \"young\": 100000, \"poisson\": 0.3}}],\n";
      printf " \"output\": {\"fps\": 100, \"vtu\": false}}\n";
    }' >"$dir/scene.json"
    "$cli" run "$dir/scene.json" --backend "$backend" --out "$dir/run" --quiet >"$dir/run.log" 2>&1 ||
      { cat "$dir/run.log"; return 1; }
    local tets
    tets=$("$cli" check "$dir/scene.json" | awk '/^body/ {for (i = 1; i <= NF; ++i) if ($(i+1) ~ /^tets/) print $i}')
    awk -F, -v n="$n" -v res="$res" -v tets="$tets" '
      NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
      NR > 2 { steps = $col["step"]; ms += $col["ms_step"]; rows++; np = $col["n_fluid"] }
      END { printf "%d,%d,%d,%s,%d,%.3f\n", n, res, np, tets, steps, rows ? ms / rows : 0 }' \
      "$dir/run/gauges.csv"
  done
}

case ${1:-} in
  bundle) [ $# -eq 3 ] || die "usage: $0 bundle BUILD BUNDLE"; bundle "$2" "$3" ;;
  run) shift; run_all "$@" ;;
  *) die "usage: $0 bundle BUILD BUNDLE | $0 run [--backend cuda|cpu] [--small] [--bin DIR] [--out DIR]" ;;
esac
