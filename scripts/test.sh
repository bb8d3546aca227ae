#!/usr/bin/env bash
# Set up and run the whole test suite (release mode: the validation cases are real physics runs).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo fmt --all -- --check
cargo clippy --release --workspace --all-targets --quiet -- -D warnings
# Doc comments' links resolve (a broken intra-doc link is an error).
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
log=$(mktemp)
trap 'rm -f "$log"' EXIT
status=0
cargo test --release --workspace --no-fail-fast 2>&1 | tee "$log" || status=$?
# The scaling report's own arithmetic (no matplotlib needed).
python3 scripts/scaling-report --self-test || status=$?
# The study script's scene edits and Pareto front (no runs).
python3 scripts/study --self-test || status=$?
# One closing line over every test binary (cargo's own last line is the doc-test run).
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "tests: %d passed, %d failed\n", p, f }' "$log"
exit "$status"
