#!/usr/bin/env bash
# Runs every fuzz target on stable Rust through RUSTC_BOOTSTRAP and prints one summary line each
# (target, exit code, executions, seconds); exits non-zero if any target found a crash.
#   RUNS=N     executions per target (default 1,000,000; issue 36's note gives 10,000,000 each)
#   SECONDS_PER_TARGET=S  instead, run each target for S seconds (CI: a short run of every target)
#   TARGETS="c3d trc"  only these
#   FUZZ_SEED=N  libFuzzer's seed (default 0: a new one each run); CI fixes it so a run is repeatable
#   SANITIZER=none  build without AddressSanitizer (default: address). Our crates forbid unsafe
#              code, and ASan's allocator was most of a C3D run's time: without it the take
#              readers run about 4x as many inputs a second (issue 36's long runs)
# The OSC and NatNet targets start from seeds/ with the OSC dictionary; the take readers from
# seeds/takes/<format>/ (cut from the c3d.org samples and the replay fixtures, see its SOURCE.md).
set -euo pipefail
cd "$(dirname "$0")"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
all="frame datagram control labels outputs natnet natnet_server qtm_client qtm_server c3d trc csv"
limit="-runs=${RUNS:-1000000}"
[ -n "${SECONDS_PER_TARGET:-}" ] && limit="-max_total_time=$SECONDS_PER_TARGET"
failed=0
for t in ${TARGETS:-$all}; do
  mkdir -p "corpus/$t"
  case "$t" in
    c3d | trc | csv)
      cp -n "seeds/takes/$t"/* "corpus/$t/"
      extra=(-max_len=65536)
      ;;
    *)
      find seeds -maxdepth 1 -type f -exec cp -n {} "corpus/$t/" \;
      extra=(-dict=osc.dict -max_len=4096)
      ;;
  esac
  start=$(date +%s)
  RUSTC_BOOTSTRAP=1 cargo fuzz run -O -s "${SANITIZER:-address}" "$t" "corpus/$t" -- "$limit" "${extra[@]}" \
    -seed="${FUZZ_SEED:-0}" -rss_limit_mb=2048 -print_final_stats=1 > "logs-$t.txt" 2>&1 && rc=0 || rc=$?
  end=$(date +%s)
  execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "logs-$t.txt" | grep -oE '[0-9]+$' || echo "?")
  echo "target=$t rc=$rc executions=$execs seconds=$((end - start))"
  if [ "$rc" -ne 0 ]; then
    failed=1
    grep -E 'ERROR|panicked|SUMMARY' "logs-$t.txt" | head -5 >&2 || true
  fi
done
exit "$failed"
