// Sanitizer defaults for the sanitizer builds (cmake/sanitize.cmake, cmake/sanitize_full.cmake), compiled into
// their CLI and test binary so that every run (ctest, gtest discovery, the CLI started by the tests) gets them.
// Leak checking is off: OpenVDB and TBB keep global singletons alive at exit.
// UBSan skips the two third-party reports the fuzz build leaves out at compile time (cmake/fuzz_ignorelist.txt,
// cmake/fuzz.cmake): oneTBB's concurrent_hash_map downcasting its sentinel bucket pointer 0x3 (alignment) and
// gemmi's residue hash shifting negative numbers (shift-base); the list is cmake/ubsan_suppressions.txt.
extern "C" const char* __asan_default_options() { return "detect_leaks=0:abort_on_error=1"; }
extern "C" const char* __ubsan_default_options() {
  return "print_stacktrace=1:halt_on_error=1:suppressions=" CHOKELOOPS_SOURCE_DIR "/cmake/ubsan_suppressions.txt";
}
