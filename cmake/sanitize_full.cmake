# CHOKELOOPS_SANITIZE_FULL=ON: the normal build (library, CLI, test binary; no Python extension, no benches)
# with every translation unit at -O1 -g under AddressSanitizer + UBSan, assertions on (use it with
# CMAKE_BUILD_TYPE=Debug, as scripts/test-sanitize.sh does). cmake/sanitize_options.cpp, linked into the CLI
# and the test binary, sets the sanitizer defaults (no leak check: OpenVDB and TBB keep global singletons).
# Included from the top CMakeLists.txt before the targets are defined. Compiling the CGAL-heavy analysis
# files this way takes long on two cores (scripts/test-sanitize.sh builds only the CLI and the test binary).
add_compile_options(-O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer)
add_link_options(-fsanitize=address,undefined)
