#!/bin/sh
# Builds the libdynamicedt3d reference used by `tetherbot edt-bench` (Debian: apt-get install -y libdynamicedt3d-dev).
set -e
here=$(cd "$(dirname "$0")" && pwd)
out="${1:-$here/../../target/bench-ref}"
mkdir -p "$out"
g++ -O2 -std=c++17 "$here/edt3d.cpp" -o "$out/edt3d" -ldynamicedt3d
echo "$out/edt3d"
