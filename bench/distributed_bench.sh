#!/usr/bin/env bash
# Parallel efficiency of the offline job on this machine, all in one run (issue 26): the same case as
# 1 rank x 1 thread (the serial baseline), 1 rank x 2 threads, and 2 ranks x 1 thread (mpirun). Prints
# one JSON object: wall seconds, speedups and efficiencies against the baseline, per-station time,
# rank 0's peak memory, the database size, and whether every database has the baseline's bytes.
#   bash bench/distributed_bench.sh [CASE] [--set key=value ...]
# Default: the quick flat plate (cases/flat_plate.toml with its run.quick overrides).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
drom="${DROM_BINARY:-$root/build/apps/drom}"
case_args=("$@")
if [ ${#case_args[@]} -eq 0 ]; then
  case_args=("$root/cases/flat_plate.toml" --set mesh.nx=20 --set mesh.ny=20 --set path.station_spacing=100)
fi
work="$(mktemp -d /tmp/drom_distributed_bench.XXXXXX)"
trap 'rm -rf "$work"' EXIT
# mpirun refuses root unless told (docs/distributed.md); 2 ranks on 2 cores need --oversubscribe only
# when another job holds a slot, which the shared machine often does.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
run() {  # name, launcher..., then drom's threads
  local name=$1 threads=$2
  shift 2
  local start end
  start=$(date +%s.%N)
  "$@" "$drom" offline "${case_args[@]}" --threads "$threads" --quiet --out "$work/$name"
  end=$(date +%s.%N)
  echo "$name $(echo "$end - $start" | bc)" >>"$work/times"
}
run serial_1x1 1
run ranks1_threads2 2
run ranks2_threads1 1 mpirun --oversubscribe -np 2
/usr/bin/python3 - "$work" <<'PY'
import json, sys, pathlib, filecmp
work = pathlib.Path(sys.argv[1])
times = dict((l.split()[0], float(l.split()[1])) for l in (work / "times").read_text().splitlines())
base = times["serial_1x1"]
summary = json.loads((work / "serial_1x1" / "summary.json").read_text())
out = {"case": summary["case"], "stations": summary["stations"], "unknowns": summary["unknowns"], "profiles": summary["profiles"],
       "serial_per_station_s": summary["time_per_station_s"], "removal_s": summary["removal_time_s"],
       "equilibrium_s": summary["equilibrium_time_s"], "peak_memory_mb": summary["peak_memory_mb"], "database_mb": summary["database_mb"], "runs": {}}
for name, t in times.items():
    cores = 1 if name == "serial_1x1" else 2
    same = filecmp.cmp(work / "serial_1x1" / "database.h5", work / name / "database.h5", shallow=False)
    out["runs"][name] = {"wall_s": round(t, 2), "speedup": round(base / t, 3), "efficiency": round(base / t / cores, 3), "same_bytes": same}
print(json.dumps(out, indent=1))
PY
