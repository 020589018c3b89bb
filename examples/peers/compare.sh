#!/usr/bin/env bash
# The peer comparison (issue 14): DOLFINx's semismooth Newton (examples/peers/dolfinx/punch.py,
# CG + GAMG, serial) and `saddle run` on the very same meshes, one code after the other, in one
# run of this script. For each N the peer builds the box (−1,1)²×(0,1) of 2N×2N×N hexahedra of
# 6 tetrahedra, solves, and exports its mesh; then `saddle bench --meshes` runs
# examples/peers/punch.toml end to end on every exported mesh and writes the table.
#
#   examples/peers/compare.sh                 # N = 16 24 32 (55.5k, 180k, 418k DOFs)
#   examples/peers/compare.sh 8 12            # a quick check
#
# Environment: PEER_PYTHON (the peer's Python, default .venv-peer/bin/python; install as in
# examples/peers/README.md), WORK (meshes, logs and solutions, default target/peer), DOCS (where
# the tables and the peer's JSON are copied, default docs/peer), SADDLE (default
# target/release/saddle, built first).
set -euo pipefail
cd "$(dirname "$0")/../.."
PEER_PYTHON=${PEER_PYTHON:-.venv-peer/bin/python}
WORK=${WORK:-target/peer}
DOCS=${DOCS:-docs/peer}
SADDLE=${SADDLE:-target/release/saddle}
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(16 24 32)
if [ ! -x "$PEER_PYTHON" ]; then
    echo "error: PEER_PYTHON=$PEER_PYTHON is not an executable Python; see examples/peers/README.md" >&2
    exit 1
fi
[ "$SADDLE" != target/release/saddle ] || cargo build --release --quiet --bin saddle
mkdir -p "$WORK" "$DOCS"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
meshes=() peers=()
for n in "${sizes[@]}"; do
    echo "peer: N = $n (load $(cut -d' ' -f1 /proc/loadavg))" >&2
    "$PEER_PYTHON" examples/peers/dolfinx/punch.py "$n" --contact pdas --solver gamg --no-linear-ref \
        --export-msh "$WORK/box$n.msh" --json "$WORK/peer$n.json" > "$WORK/peer$n.log" 2>&1 \
        || { echo "error: the peer failed at N = $n; see $WORK/peer$n.log" >&2; exit 1; }
    grep -E "plastic :|timings" "$WORK/peer$n.log" >&2
    meshes+=("$WORK/box$n.msh") peers+=("$WORK/peer$n.json")
done
"$SADDLE" bench examples/peers/punch.toml --out "$WORK" \
    --meshes "$(IFS=,; echo "${meshes[*]}")" --peer "$(IFS=,; echo "${peers[*]}")"
cp "$WORK/meshes.md" "$WORK/meshes.csv" "${peers[@]}" "$DOCS/"
echo "wrote $DOCS/meshes.md, meshes.csv and the peer's JSON" >&2
