#!/usr/bin/env bash
# The peer comparison (issue 14): DOLFINx's semismooth Newton (examples/peers/dolfinx/punch.py,
# CG + GAMG, serial) and `saddle run` on the very same meshes, one code after the other, in one
# run of this script. For each N the peer builds the box (−1,1)²×(0,1) of 2N×2N×N hexahedra of
# 6 tetrahedra, solves, and exports its mesh; then `saddle bench --meshes` runs
# examples/peers/punch.toml end to end on every exported mesh and writes the table.
#
#   examples/peers/compare.sh                 # N = 16 24 32 (55.5k, 180k, 418k DOFs)
#   examples/peers/compare.sh 8 12            # a quick check
#   examples/peers/compare.sh --degree 2      # P2: N = 12 16 (156k, 376k DOFs), punch_p2.toml
#
# At --degree 2 the peer solves with P2 displacements and stresses at the four points of the
# degree-2 rule and exports the second-order mesh (10-node tetrahedra); saddle runs
# examples/peers/punch_p2.toml (plain P2, the same discrete problem) on it; the tables are
# meshes_p2.md and meshes_p2.csv, the peer's JSON peer<N>_p2.json (the P1 files stay).
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
degree=1
if [ "${1:-}" = --degree ]; then
    degree=${2:?--degree needs 1 or 2}
    shift 2
fi
case $degree in
    1) scene=examples/peers/punch.toml suffix= default_sizes=(16 24 32) ;;
    2) scene=examples/peers/punch_p2.toml suffix=_p2 default_sizes=(12 16) ;;
    *) echo "error: --degree $degree: the peer has P1 and P2 (1 or 2)" >&2; exit 1 ;;
esac
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=("${default_sizes[@]}")
if [ ! -x "$PEER_PYTHON" ]; then
    echo "error: PEER_PYTHON=$PEER_PYTHON is not an executable Python; see examples/peers/README.md" >&2
    exit 1
fi
[ "$SADDLE" != target/release/saddle ] || cargo build --release --quiet --bin saddle
mkdir -p "$WORK" "$DOCS"
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
meshes=() peers=()
for n in "${sizes[@]}"; do
    # Γ₁'s rim |x₁|, |x₂| = 0.75 lies on nodes only when 4 divides N; otherwise the peer clamps the
    # nodes beyond it and saddle the closure of the facets outside Γ₁, which are not the same nodes
    [ $((n % 4)) -eq 0 ] || echo "warning: N = $n is not a multiple of 4: Γ₁'s rim falls between nodes and the two codes clamp different nodes there (their answers differ)" >&2
    echo "peer: N = $n, P$degree (load $(cut -d' ' -f1 /proc/loadavg))" >&2
    name=$n$suffix
    "$PEER_PYTHON" examples/peers/dolfinx/punch.py "$n" --degree "$degree" --contact pdas --solver gamg \
        --no-linear-ref --export-msh "$WORK/box$name.msh" --json "$WORK/peer$name.json" > "$WORK/peer$name.log" 2>&1 \
        || { echo "error: the peer failed at N = $n; see $WORK/peer$name.log" >&2; exit 1; }
    grep -E "plastic :|timings|peak resident" "$WORK/peer$name.log" >&2
    meshes+=("$WORK/box$name.msh") peers+=("$WORK/peer$name.json")
done
# each degree its own bench folder, so that P2 does not overwrite P1's tables
out=$WORK${suffix:+/p$degree}
"$SADDLE" bench "$scene" --out "$out" \
    --meshes "$(IFS=,; echo "${meshes[*]}")" --peer "$(IFS=,; echo "${peers[*]}")"
cp "$out/meshes.md" "$DOCS/meshes$suffix.md"
cp "$out/meshes.csv" "$DOCS/meshes$suffix.csv"
cp "${peers[@]}" "$DOCS/"
echo "wrote $DOCS/meshes$suffix.md, meshes$suffix.csv and the peer's JSON" >&2
