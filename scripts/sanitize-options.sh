# Sourced by scripts/test.sh (GLASSPIV_SANITIZE=ON) and tests/fuzz/fuzz.sh: the
# one configuration of the sanitizer build, so both use the same build folder
# and compile the libraries once. clang 14 (it builds this tree under ASan +
# UBSan in well under half GCC's time), -O1 (the sanitizers need no more), line
# tables for the reports, no benchmarks, the libFuzzer targets and coverage.
sanitize_build_dir="${GLASSPIV_SANITIZE_BUILD_DIR:-build-sanitize}"
sanitize_options=(
  -DGLASSPIV_SANITIZE=ON -DGLASSPIV_FUZZ=ON -DGLASSPIV_BUILD_BENCH=OFF
  -DCMAKE_C_COMPILER="${GLASSPIV_FUZZ_CC:-clang-14}" -DCMAKE_CXX_COMPILER="${GLASSPIV_FUZZ_CXX:-clang++-14}"
  "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -gline-tables-only" "-DCMAKE_C_FLAGS_RELEASE=-O1 -gline-tables-only"
)
