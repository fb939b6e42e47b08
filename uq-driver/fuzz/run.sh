#!/usr/bin/env bash
# `make fuzz`: builds the fuzz targets with libFuzzer on stable Rust and runs each for a fixed
# time. Not part of `make test`.
#
#   FUZZ_SECONDS   seconds per target (default 60)
#   FUZZ_TARGETS   targets to run (default: all, see below)
#
# The seeds in corpus/<target>/ are read, never written; what libFuzzer learns goes to
# target/fuzz/corpus/<target>/ (kept between runs). A crashing, hanging or memory-hungry input
# is saved under target/fuzz/artifacts/<target>/ and the script exits 1; reproduce it with
#   target/fuzz/x86_64-unknown-linux-gnu/release/<target> FILE
# and, once fixed, copy it to regressions/<target>/ so that `cargo test` (tests/fuzz_corpus.rs)
# keeps checking it.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
seconds="${FUZZ_SECONDS:-60}"
targets="${FUZZ_TARGETS:-model_description store_reader study_file}"
triple="$(rustc -vV | sed -n 's/^host: //p')"
out="$root/target/fuzz"

# libFuzzer's instrumentation through stable rustc flags (what cargo-fuzz passes, without the
# nightly-only sanitizers: the code under test is safe Rust, so what is hunted is panics,
# hangs and runaway memory). --target keeps build scripts and proc macros uninstrumented.
export RUSTFLAGS="--cfg fuzzing -Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares -Cdebug-assertions -Coverflow-checks"
cargo build --release --manifest-path "$here/Cargo.toml" --target "$triple" \
  --target-dir "$out" $(for t in $targets; do printf -- '--bin %s ' "$t"; done)

failed=()
for t in $targets; do
  mkdir -p "$out/corpus/$t" "$out/artifacts/$t"
  echo "== fuzzing $t for ${seconds} s (seeds: uq-driver/fuzz/corpus/$t)"
  # -timeout: one input slower than 10 s is a hang (the quadratic parser took minutes);
  # -rss_limit_mb / -malloc_limit_mb: runaway memory is a failure too.
  if ! "$out/$triple/release/$t" "$out/corpus/$t" "$here/corpus/$t" "$here/regressions/$t" \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 \
      -max_len=200000 -print_final_stats=1 \
      -artifact_prefix="$out/artifacts/$t/" 2>"$out/$t.log"; then
    failed+=("$t")
  fi
  grep -E "^(stat::number_of_executed_units|stat::peak_rss_mb)|ERROR|panicked|SUMMARY" \
    "$out/$t.log" || true
done
if ((${#failed[@]})); then
  echo "make fuzz: failures in: ${failed[*]} (inputs in target/fuzz/artifacts/, logs in target/fuzz/*.log)" >&2
  exit 1
fi
echo "make fuzz: no failure in ${targets} (${seconds} s each)"
