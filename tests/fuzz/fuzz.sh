#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang 14, ASan + UBSan + libFuzzer) into
# the sanitizer build's folder (build-sanitize/) and runs each for a bounded time over its kept corpus
# (tests/fuzz/corpus/<name>/, read only: new inputs go to
# build-sanitize/fuzz-work/<name>/). docs/fuzzing.md has the details.
#
# Usage: tests/fuzz/fuzz.sh [harness...]     (default: all)
# Environment:
#   GLASSPIV_FUZZ_SECONDS  time per harness (default 20)
#   GLASSPIV_FUZZ_JOBS     parallel fuzzing processes per harness (default 1)
#   GLASSPIV_FUZZ_PARALLEL harnesses fuzzed at the same time (default: cores / jobs)
#   GLASSPIV_FUZZ_BUILD_DIR  (default build-sanitize, the sanitizer build's folder)
#   GLASSPIV_FUZZ_SEED     libFuzzer's -seed (default 1: a run explores the same inputs first
#                          each time, so CI's short runs repeat; 0: a new random seed per run)
#   GLASSPIV_FUZZ_EXTRA    more libFuzzer flags, e.g. "-dict=... -max_len=4096"
# A finding (crash, sanitizer report, leak, timeout, out-of-memory, an
# exception other than InputError) ends the script with status 1; its
# reproducer is left in build-sanitize/fuzz-artifacts/<name>/ and printed (base64).
set -euo pipefail
cd "$(dirname "$0")/../.."
src="$PWD/tests/fuzz"
bash scripts/install-deps.sh --clang
# The sanitizer build's own configuration and folder: the libraries compiled
# there for the sanitizer tests serve the harnesses too.
source scripts/sanitize-options.sh
build_dir="$(realpath -m "${GLASSPIV_FUZZ_BUILD_DIR:-$sanitize_build_dir}")"
seconds="${GLASSPIV_FUZZ_SECONDS:-20}"
jobs="${GLASSPIV_FUZZ_JOBS:-1}"
seed="${GLASSPIV_FUZZ_SEED:-1}"

all=(scene_yaml camera_glasspiv camera_opencv camera_mrcal camera_davis target_yaml
     observations_yaml observations_json transport_map correction_operator image)
if [ $# -gt 0 ]; then harnesses=("$@"); else harnesses=("${all[@]}"); fi

targets=()
for h in "${harnesses[@]}"; do targets+=("fuzz_$h" "regress_$h"); done
GLASSPIV_BUILD_DIR="$build_dir" GLASSPIV_BUILD_TARGET="${targets[*]}" bash scripts/build.sh "${sanitize_options[@]}"

asan_options="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}"
# Leaks inside third-party libraries are suppressed (tests/fuzz/lsan.supp); to
# match them, the image harness needs full malloc stacks.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$src/lsan.supp}"
full_malloc_stacks=" image "
export ASAN_OPTIONS="$asan_options"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# The kept corpus and reproducers first, under the same sanitizers.
regress=()
for h in "${harnesses[@]}"; do regress+=("fuzz_regress.$h"); done
ctest --test-dir "$build_dir" --output-on-failure --parallel "$(nproc)" \
  -R "^($(IFS='|'; echo "${regress[*]}"))\$"
# One harness: fuzz it, write its summary line to $summary_dir/<name>, and on a
# finding print the end of its log and the reproducer (base64). Returns 1 on a finding.
fuzz_one() {
  local h="$1"
  local work="$build_dir/fuzz-work/$h"
  local artifacts="$build_dir/fuzz-artifacts/$h"
  local log="$build_dir/fuzz-logs/$h.log"
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  local corpora=("$src/corpus/$h")
  [ -d "$src/crashes/$h" ] && corpora+=("$src/crashes/$h")
  local extra=()
  [ -f "$src/dict/$h.dict" ] && extra+=(-dict="$src/dict/$h.dict")
  [ "$jobs" -gt 1 ] && extra+=(-jobs="$jobs" -workers="$jobs")
  local options="$asan_options"
  [[ "$full_malloc_stacks" == *" $h "* ]] && options="$asan_options:fast_unwind_on_malloc=0"
  local rc
  set +e
  # -jobs writes fuzz-<n>.log into the current folder: one folder per harness.
  # shellcheck disable=SC2086
  (cd "$work" && ASAN_OPTIONS="$options" "$build_dir/tests/fuzz/fuzz_$h" . "${corpora[@]}" "${extra[@]}" \
    -max_total_time="$seconds" -seed="$seed" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" ${GLASSPIV_FUZZ_EXTRA:-} >"$log" 2>&1)
  rc=$?
  set -e
  if [ "$jobs" -gt 1 ]; then cat "$work"/fuzz-*.log >>"$log" 2>/dev/null || true; rm -f "$work"/fuzz-*.log; fi
  local last execs speed cov ft
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  execs=$(grep -E 'stat::number_of_executed_units' "$log" | tail -1 | awk '{print $2}' || true)
  speed=$(grep -E 'stat::average_exec_per_sec' "$log" | tail -1 | awk '{print $2}' || true)
  cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
  ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
  printf '%-22s rc=%-3s execs=%-9s exec/s=%-7s cov=%-6s ft=%s\n' "$h" "$rc" "${execs:-?}" "${speed:-?}" \
    "${cov:-?}" "${ft:-?}" >"$summary_dir/$h"
  [ "$rc" -eq 0 ] && return 0
  {
    echo "FINDING in fuzz_$h (exit $rc); the end of its log:"
    tail -n 60 "$log"
    for f in "$artifacts"/*; do
      [ -f "$f" ] || continue
      echo "reproducer $f ($(stat -c %s "$f") bytes), base64:"
      base64 -w 0 "$f" | head -c 20000
      echo
    done
  } >"$summary_dir/$h.finding"
  return 1
}

# Harnesses run side by side, as many at a time as GLASSPIV_FUZZ_PARALLEL
# (default: the number of cores divided by the processes per harness).
parallel="${GLASSPIV_FUZZ_PARALLEL:-$(( $(nproc) / jobs > 0 ? $(nproc) / jobs : 1 ))}"
summary_dir="$build_dir/fuzz-summary"
rm -rf "$summary_dir" && mkdir -p "$summary_dir"
echo "== fuzzing ${#harnesses[@]} harnesses, ${seconds} s each, ${parallel} at a time"
running=0
for h in "${harnesses[@]}"; do
  if [ "$running" -ge "$parallel" ]; then wait -n || true; running=$((running - 1)); fi
  fuzz_one "$h" &
  running=$((running + 1))
done
wait || true
status=0
for h in "${harnesses[@]}"; do
  if [ -f "$summary_dir/$h.finding" ]; then cat "$summary_dir/$h.finding"; status=1; fi
  [ -f "$summary_dir/$h" ] || { echo "fuzz_$h left no summary"; status=1; }
done
echo "== fuzz summary (${seconds} s per harness)"
cat "${harnesses[@]/#/$summary_dir/}" 2>/dev/null || true
exit "$status"
