#!/usr/bin/env bash
# Fuzz the scene parser, validator and `check`'s assessment for SECONDS (default 1800).
# Seeds: every shipped scene (jobs/, tests/scenes/, templates/) and fuzz/seeds/; a dictionary
# of every key and tag in them. Needs the nightly toolchain and cargo-fuzz
# (`cargo install cargo-fuzz`). Crashes land in fuzz/artifacts/scene/; the corpus grows in
# $FUZZ_CORPUS (default /tmp/grainflow-fuzz-corpus), never in the repository.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-1800}
corpus=${FUZZ_CORPUS:-/tmp/grainflow-fuzz-corpus}
mkdir -p "$corpus"
scenes=$(find jobs tests/scenes templates fuzz/seeds -name '*.toml' | sort)
for f in $scenes; do cp "$f" "$corpus/seed-$(echo "$f" | tr '/' '_')"; done
dict="$corpus.dict"
# Every key (`name =`, `name = {`), every quoted word and a few structural tokens.
{
  cat $scenes | grep -ohE '^[[:space:]]*[a-z_0-9]+[[:space:]]*=' | tr -d ' =' | sort -u |
    sed 's/.*/"&"/'
  cat $scenes | grep -ohE '[a-z_0-9]+ = ' | tr -d ' =' | sort -u | sed 's/.*/"&"/'
  cat $scenes | grep -ohE '"[a-z0-9_.-]+"' | sort -u | sed 's/"/\\"/g; s/.*/"&"/'
  cat $scenes | grep -ohE '^\[+[a-z_.]+\]+' | sort -u | sed 's/.*/"&"/'
  printf '%s\n' '"nan"' '"inf"' '"-inf"' '"1e308"' '"-1e308"' '"1e-308"' '"0"' '"-1"' \
    '"18446744073709551615"' '"9223372036854775807"' '"4294967295"' '"[]"' '"{}"' '" = "'
} | sort -u >"$dict"
echo "fuzz: $(ls "$corpus" | wc -l) inputs, $(wc -l <"$dict") dictionary entries, ${secs} s"
cargo +nightly fuzz run scene -s none --release --debug-assertions "$corpus" -- \
  -dict="$dict" -max_total_time="$secs" -timeout=10 -rss_limit_mb=3072 -max_len=16384 \
  -print_final_stats=1
