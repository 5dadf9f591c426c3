# A GoogleTest binary of the given sources, linked with `library`, told where the `chokeloops` CLI and the
# shared data are, and discovered by ctest. Used by tests/CMakeLists.txt and by the sanitizer build.
find_package(GTest REQUIRED)
include(GoogleTest)

function(chokeloops_add_test_binary name library discovery_timeout test_timeout)
  add_executable(${name} ${ARGN})
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/src ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(${name} PRIVATE ${library} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    CHOKELOOPS_CLI="$<TARGET_FILE:chokeloops>"
    CHOKELOOPS_DATA="${PROJECT_SOURCE_DIR}/data")
  add_dependencies(${name} chokeloops)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT ${discovery_timeout} PROPERTIES TIMEOUT ${test_timeout})
endfunction()
