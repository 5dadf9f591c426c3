// Sanitizer defaults for the CHOKELOOPS_SANITIZE build (cmake/sanitize.cmake), compiled into its CLI and
// test binary so that every run (ctest, gtest discovery, the CLI started by the tests) gets them.
// Leak checking is off: OpenVDB and TBB keep global singletons alive at exit.
extern "C" const char* __asan_default_options() { return "detect_leaks=0:abort_on_error=1"; }
extern "C" const char* __ubsan_default_options() { return "print_stacktrace=1:halt_on_error=1"; }
