#!/usr/bin/env bash
# Weak scaling, small variant: fixed cells per rank. For N ranks the lattice is
# (NX_PER_RANK * N) x NY, generated from weak-template.toml (@NX@, @NY@) into $OUT/np$N.toml.
# The slab decomposition splits x, so every rank keeps NX_PER_RANK x NY cells.
#
#   jobs/scaling/weak.sh [RANKS...]            default ranks: 1 2
#
# Environment (all optional):
#   NX_PER_RANK=1024 NY=1024
#   THREADS=1        rayon threads per rank (--threads)
#   TEMPLATE=jobs/scaling/weak-template.toml
#   OUT=runs/scaling/weak         one run folder per rank count: $OUT/np$N (+ np$N.toml, np$N.log)
#   STEPS=           override the template's step count (--steps)
#   GRAINFLOW=target/release/grainflow
#   MPIRUN=mpirun    MPIRUN_ARGS="" (extra launcher options)
# Ends with scripts/scaling-report --kind weak on the run folders ($OUT/weak-scaling.{csv,png}).
set -euo pipefail
cd "$(dirname "$0")/../.."

NX_PER_RANK=${NX_PER_RANK:-1024}
NY=${NY:-1024}
THREADS=${THREADS:-1}
TEMPLATE=${TEMPLATE:-jobs/scaling/weak-template.toml}
OUT=${OUT:-runs/scaling/weak}
STEPS=${STEPS:-}
GRAINFLOW=${GRAINFLOW:-target/release/grainflow}
MPIRUN=${MPIRUN:-mpirun}
MPIRUN_ARGS=${MPIRUN_ARGS:-}
if [ "$#" -gt 0 ]; then ranks=("$@"); else ranks=(1 2); fi

posint() { [[ "$2" =~ ^[1-9][0-9]*$ ]] || { echo "weak.sh: $1='$2' is not a positive integer" >&2; exit 1; }; }
for n in "${ranks[@]}"; do posint "rank count" "$n"; done
posint THREADS "$THREADS"; posint NX_PER_RANK "$NX_PER_RANK"; posint NY "$NY"
[ -x "$GRAINFLOW" ] || { echo "weak.sh: $GRAINFLOW not found; build it first: cargo build --release" >&2; exit 1; }
command -v "$MPIRUN" >/dev/null || { echo "weak.sh: $MPIRUN not found (apt-get install openmpi-bin, or set MPIRUN)" >&2; exit 1; }
[ -f "$TEMPLATE" ] || { echo "weak.sh: template $TEMPLATE not found" >&2; exit 1; }
if [ "$(id -u)" -eq 0 ]; then
    # Open MPI refuses to run as root unless told twice (containers, CI).
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi
export OMP_NUM_THREADS=$THREADS RAYON_NUM_THREADS=$THREADS
steps_arg=()
[ -n "$STEPS" ] && steps_arg=(--steps "$STEPS")

mkdir -p "$OUT"
dirs=()
for n in "${ranks[@]}"; do
    out="$OUT/np$n"
    scene="$OUT/np$n.toml"
    nx=$((NX_PER_RANK * n))
    sed -e "s/@NX@/$nx/g" -e "s/@NY@/$NY/g" "$TEMPLATE" > "$scene"
    if grep -q '@[A-Z_]*@' "$scene"; then
        echo "weak.sh: $scene still has placeholders: $(grep -o '@[A-Z_]*@' "$scene" | sort -u | tr '\n' ' ')" >&2
        exit 1
    fi
    "$GRAINFLOW" check "$scene" > "$OUT/np$n.check" || { cat "$OUT/np$n.check" >&2; exit 1; }
    rm -rf "$out"
    echo "== weak scaling: $n rank(s) x $THREADS thread(s), lattice ${nx}x${NY}: $out"
    # shellcheck disable=SC2086  # MPIRUN_ARGS is a word list on purpose
    "$MPIRUN" --bind-to none --oversubscribe -np "$n" $MPIRUN_ARGS \
        "$GRAINFLOW" run "$scene" --out "$out" --quiet --threads "$THREADS" ${steps_arg[@]+"${steps_arg[@]}"} \
        2>&1 | tee "$OUT/np$n.log"
    dirs+=("$out")
done

scripts/scaling-report --kind weak "${dirs[@]}"
