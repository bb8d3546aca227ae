#!/usr/bin/env bash
# Set up and run the whole test suite (release mode: the validation cases are real physics runs).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
cargo fmt --all -- --check
cargo clippy --release --all-targets --quiet -- -D warnings
cargo test --release --workspace --no-fail-fast
