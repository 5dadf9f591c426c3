# CHOKELOOPS_SANITIZE=ON: only the input stage (mesh/.vdb reading, repair, level set, winding number), a
# `chokeloops` CLI with just the `levelset` command, and a test binary of the input tests, all under
# AddressSanitizer + UBSan. The full library's CGAL-heavy analysis files did not finish compiling in
# 25 min with ASan on the 2-core machine, and the bad-input suite needs none of them.
# Included from the top CMakeLists.txt, which then stops (no other targets in a sanitizer build).

set(CHOKELOOPS_SANITIZE_FLAGS -O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer)
file(GLOB CHOKELOOPS_INPUT_SOURCES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/io/*.cpp ${PROJECT_SOURCE_DIR}/src/field/*.cpp)
add_library(chokeloops_input STATIC ${CHOKELOOPS_INPUT_SOURCES})
target_include_directories(chokeloops_input PUBLIC ${PROJECT_SOURCE_DIR}/include PRIVATE ${PROJECT_SOURCE_DIR}/src)
target_compile_definitions(chokeloops_input PUBLIC CHOKELOOPS_VERSION="${PROJECT_VERSION}"
  CHOKELOOPS_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
target_compile_options(chokeloops_input PUBLIC ${CHOKELOOPS_SANITIZE_FLAGS})
target_link_options(chokeloops_input PUBLIC -fsanitize=address,undefined)
target_link_libraries(chokeloops_input PUBLIC ${CHOKELOOPS_INPUT_LINK_LIBRARIES})

# main.cpp restarts the program with huge pages when asked (src/pipeline/huge_pages.cpp, no other dependency)
add_executable(chokeloops ${PROJECT_SOURCE_DIR}/tools/main.cpp ${PROJECT_SOURCE_DIR}/tools/cmd_levelset.cpp
  ${PROJECT_SOURCE_DIR}/tools/args.cpp ${PROJECT_SOURCE_DIR}/src/pipeline/huge_pages.cpp
  ${PROJECT_SOURCE_DIR}/cmake/sanitize_options.cpp)
target_link_libraries(chokeloops PRIVATE chokeloops_input)

enable_testing()
include(${PROJECT_SOURCE_DIR}/cmake/test_binary.cmake)
file(GLOB CHOKELOOPS_INPUT_TESTS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/test_bad_input.cpp
  ${PROJECT_SOURCE_DIR}/tests/test_levelset_*.cpp ${PROJECT_SOURCE_DIR}/tests/test_winding_number.cpp)
# the CSG level-set tests also run the analysis, which this build leaves out (the full build has them)
list(FILTER CHOKELOOPS_INPUT_TESTS EXCLUDE REGEX "test_levelset_csg\\.cpp$")
chokeloops_add_test_binary(chokeloops_input_tests chokeloops_input 300 1800
  ${CHOKELOOPS_INPUT_TESTS} ${PROJECT_SOURCE_DIR}/cmake/sanitize_options.cpp)
