# Sourced (not run) by the scripts that start emoshift, from the repository root.
# `emoshift_bin [debug|release]` sets `bin` to the binary they run: $EMOSHIFT when set (CI
# passes the one `cargo test` built: `cargo build -p daemon` resolves dependencies without the
# dev-dependencies' features and would compile much of the workspace again), else the profile's
# build, made now. Exits 1, saying what to do, when there is no binary to run.
emoshift_bin() {
  local profile="${1:-debug}"
  if [ -n "${EMOSHIFT:-}" ]; then
    bin="$EMOSHIFT"
  elif [ "$profile" = release ]; then
    cargo build -q --release -p daemon --bin emoshift
    bin="${CARGO_TARGET_DIR:-$PWD/target}/release/emoshift"
  else
    cargo build -q -p daemon --bin emoshift
    bin="${CARGO_TARGET_DIR:-$PWD/target}/debug/emoshift"
  fi
  [ -x "$bin" ] || {
    echo "FAIL build: no $bin (build it with \`cargo build -p daemon\`, or set EMOSHIFT to a built emoshift)"
    exit 1
  }
}
