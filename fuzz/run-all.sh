#!/usr/bin/env bash
# Runs every fuzz target for RUNS executions (default 1,000,000) on stable Rust through
# RUSTC_BOOTSTRAP, seeded from seeds/ with the OSC dictionary. Prints one summary line each.
set -euo pipefail
cd "$(dirname "$0")"
runs="${RUNS:-1000000}"
for t in frame datagram control labels outputs natnet; do
  mkdir -p "corpus/$t"
  cp -n seeds/* "corpus/$t/" 2>/dev/null || true
  start=$(date +%s)
  RUSTC_BOOTSTRAP=1 cargo fuzz run -O "$t" "corpus/$t" -- -runs="$runs" -dict=osc.dict \
    -max_len=4096 -print_final_stats=1 > "logs-$t.txt" 2>&1 && rc=0 || rc=$?
  end=$(date +%s)
  execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "logs-$t.txt" | grep -oE '[0-9]+$' || echo "?")
  echo "target=$t rc=$rc executions=$execs seconds=$((end - start))"
done
