#!/usr/bin/env bash
# Issue 25 check 1: drom installed into a fresh prefix, examples/ configured against it from an empty
# build folder (find_package(drom)), built, and run in a chain: an offline job on a coarse flat plate,
# its reduction, and the predictor fed from a thread, which must recover a profile inside the basis
# to 1e-8 (online_predictor exits 1 otherwise).
# Usage: installed_examples.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build="$1" source="$2" work="$3"
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
cmake -S "$source/examples" -B "$work/examples" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/configure.log"
cmake --build "$work/examples" > "$work/build.log"
coarse=(--set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=300 --set removal.voxel_size=1.0
        --set "clamps.0.box=[0,100,0,100]" --set "clamps.1.box=[900,1000,0,100]"
        --set "clamps.2.box=[0,100,900,1000]" --set "clamps.3.box=[900,1000,900,1000]")
"$work/examples/offline_job" "${coarse[@]}" --out "$work/run/db" 2> /dev/null
"$work/examples/reduce_database" "$work/run/db/database.h5" --out "$work/run/model/model.h5"
"$work/examples/online_predictor" "$work/run/model/model.h5"
