#!/usr/bin/env bash
# Strong scaling, small variant: one fixed lattice (strong-small.toml, 2048 x 1024) on N ranks.
#
#   jobs/scaling/strong.sh [RANKS...]          default ranks: 1 2
#
# Environment (all optional):
#   THREADS=1        rayon threads per rank (--threads)
#   SCENE=jobs/scaling/strong-small.toml
#   OUT=runs/scaling/strong       one run folder per rank count: $OUT/np$N (+ $OUT/np$N.log)
#   STEPS=           override the scene's step count (--steps)
#   GRAINFLOW=target/release/grainflow
#   MPIRUN=mpirun    MPIRUN_ARGS="" (extra launcher options)
# Ends with scripts/scaling-report --kind strong on the run folders ($OUT/strong-scaling.{csv,png}).
set -euo pipefail
cd "$(dirname "$0")/../.."

THREADS=${THREADS:-1}
SCENE=${SCENE:-jobs/scaling/strong-small.toml}
OUT=${OUT:-runs/scaling/strong}
STEPS=${STEPS:-}
GRAINFLOW=${GRAINFLOW:-target/release/grainflow}
MPIRUN=${MPIRUN:-mpirun}
MPIRUN_ARGS=${MPIRUN_ARGS:-}
if [ "$#" -gt 0 ]; then ranks=("$@"); else ranks=(1 2); fi

for n in "${ranks[@]}"; do
    [[ "$n" =~ ^[1-9][0-9]*$ ]] || { echo "strong.sh: rank count '$n' is not a positive integer" >&2; exit 1; }
done
[[ "$THREADS" =~ ^[1-9][0-9]*$ ]] || { echo "strong.sh: THREADS='$THREADS' is not a positive integer" >&2; exit 1; }
[ -x "$GRAINFLOW" ] || { echo "strong.sh: $GRAINFLOW not found; build it first: cargo build --release" >&2; exit 1; }
command -v "$MPIRUN" >/dev/null || { echo "strong.sh: $MPIRUN not found (apt-get install openmpi-bin, or set MPIRUN)" >&2; exit 1; }
[ -f "$SCENE" ] || { echo "strong.sh: scene $SCENE not found" >&2; exit 1; }
if [ "$(id -u)" -eq 0 ]; then
    # Open MPI refuses to run as root unless told twice (containers, CI).
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
export OMP_NUM_THREADS=$THREADS RAYON_NUM_THREADS=$THREADS
steps_arg=()
[ -n "$STEPS" ] && steps_arg=(--steps "$STEPS")

"$GRAINFLOW" check "$SCENE"
mkdir -p "$OUT"
dirs=()
for n in "${ranks[@]}"; do
    out="$OUT/np$n"
    rm -rf "$out"
    echo "== strong scaling: $n rank(s) x $THREADS thread(s): $out"
    # shellcheck disable=SC2086  # MPIRUN_ARGS is a word list on purpose
    "$MPIRUN" --bind-to none --oversubscribe -np "$n" $MPIRUN_ARGS \
        "$GRAINFLOW" run "$SCENE" --out "$out" --quiet --threads "$THREADS" ${steps_arg[@]+"${steps_arg[@]}"} \
        2>&1 | tee "$OUT/np$n.log"
    dirs+=("$out")
done

scripts/scaling-report --kind strong "${dirs[@]}"
