#!/usr/bin/env bash
# The MPI benchmark of BENCHMARKS.md ("Studies and plans over MPI ranks", issue 13):
#  * the 1 ml phantom study (5 radii x 2 integrators + 4 viscosities = 14 injections) in one process on 1
#    and 2 threads, and under mpirun on 2 ranks (one worker, 2 threads) and 3 ranks (two workers, 1 thread
#    each): ranks x threads = the 2 cores;
#  * the vertebra plan of the tests (3 starts) in one process and on 3 ranks.
# Each configuration runs REPEATS times, interleaved; the script prints every wall time (s) and checks that
# the MPI tables equal the serial ones (timing and rank columns aside).
# Usage: Testing/Benchmarks/Mpi/mpi-scaling.sh [BUILD_DIR] [REPEATS]   (from the repository root)
set -euo pipefail
build="${1:-build}"
repeats="${2:-3}"
bin="$build/bin/cementsph"
out="$(mktemp -d)"
tip="$(python3 -c "import json;t=json.load(open('Data/foam-phantom/truth.json'))['injection']['tip_mm'];print(','.join(repr(x) for x in t))")"
study=(study --ct Data/foam-phantom/pre.nrrd --scene Data/scenes/paper-1ml.json --tip-mm "$tip"
       --viscosities-pa-s 50,100,200,400 --no-pictures)
# A transpedicular entry clear of the canal (plan refuses a shaft through it: PlanTrajectory.h).
plan=(plan --ct Data/vertebra-phantom/pre.nrrd --scene Data/scenes/paper.json --entry-mm 48.5,52.4,22.5
      --min-depth-mm 10 --max-depth-mm 36 --target-mm 32,21,22.5 --target-radius-mm 6
      --min-volume-ml 1 --max-volume-ml 4 --max-syringe-mpa 3 --max-leakage-ml 0 --quiet)
# --bind-to none: Open MPI binds each rank to one core when it starts two ranks or fewer, so a rank's OpenMP
# threads would share that one core (measured: 2 ranks x 2 threads 85 s against 51 s in one process).
mpi=(mpirun -q --allow-run-as-root --oversubscribe --bind-to none)

seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1; t1=$(date +%s.%N); python3 -c "print(f\"{$t1 - $t0:.2f}\")"; }
# The figures of a study table without the columns that depend on where and how fast a run ran.
figures() { python3 - "$1" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
for r in rows:
    for k in ("wall_time_s", "real_time_factor", "analysis_time_s", "rank"): r.pop(k, None)
    print(sorted(r.items()))
PY
}

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); load $(cut -d' ' -f1-3 /proc/loadavg)"
for i in $(seq 1 "$repeats"); do
  echo "repeat $i: study 1 process 1 thread  $(OMP_NUM_THREADS=1 seconds "$bin" "${study[@]}" --out "$out/s1t1")"
  echo "repeat $i: study 1 process 2 threads $(OMP_NUM_THREADS=2 seconds "$bin" "${study[@]}" --out "$out/s1t2")"
  echo "repeat $i: study 2 ranks x 2 threads $(OMP_NUM_THREADS=2 seconds "${mpi[@]}" -n 2 "$bin" "${study[@]}" --out "$out/s2")"
  echo "repeat $i: study 3 ranks x 1 thread  $(OMP_NUM_THREADS=1 seconds "${mpi[@]}" -n 3 "$bin" "${study[@]}" --out "$out/s3")"
  echo "repeat $i: plan 1 process 2 threads  $(OMP_NUM_THREADS=2 seconds "$bin" "${plan[@]}" --out "$out/p1")"
  echo "repeat $i: plan 3 ranks x 1 thread   $(OMP_NUM_THREADS=1 seconds "${mpi[@]}" -n 3 "$bin" "${plan[@]}" --out "$out/p3")"
done
for config in s1t2 s2 s3; do
  for table in study.csv spreading_vs_viscosity.csv; do
    cmp <(figures "$out/s1t1/$table") <(figures "$out/$config/$table") > /dev/null &&
      echo "same figures: $config/$table = s1t1/$table" || echo "DIFFERENT: $config/$table"
  done
done
python3 - "$out" <<'PY'
import json, sys
a = json.load(open(sys.argv[1] + "/p1/plan.json")); b = json.load(open(sys.argv[1] + "/p3/plan.json"))
print("plan: same evaluations on 3 ranks:", a["evaluations"] == b["evaluations"], "-", len(a["evaluations"]), "injections")
PY
python3 - "$out/s1t2/study.csv" "$out/s1t2/spreading_vs_viscosity.csv" <<'PY'
import csv, sys
walls = [float(r["wall_time_s"]) for f in sys.argv[1:] for r in csv.DictReader(open(f))]
print(f"study (2 threads): {len(walls)} injections, {sum(walls):.2f} s of injections, the longest {max(walls):.2f} s")
PY
echo "outputs in $out"
