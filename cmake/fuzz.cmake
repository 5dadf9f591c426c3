# CHOKELOOPS_FUZZ=ON (with CXX=clang++): libFuzzer harnesses fuzz/fuzz_*.cpp for every input reader (meshes,
# .vdb, PDB/mmCIF, NIfTI/NRRD/MetaImage), and two for what the levelset stage does with a parsed mesh or grid
# (fuzz_mesh_levelset, fuzz_vdb_levelset: inputs decoded straight into tiny meshes and grids), over the input
# stage (src/io, src/field) built with -fsanitize=fuzzer-no-link,address,undefined. Run them with scripts/fuzz.sh.
# Included from the top CMakeLists.txt, which then stops (no other targets).
# The build type sets the optimisation (scripts/fuzz.sh: FUZZ_BUILD_TYPE, default RelWithDebInfo = -O2 -g;
# Debug gets -O1 here). Assertions stay on in every build type
# (NDEBUG is taken out): a failed assertion in our code or in CGAL/Eigen is a finding too.

if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  message(FATAL_ERROR "CHOKELOOPS_FUZZ needs clang (libFuzzer): configure with CXX=clang++")
endif()
foreach(config RELEASE RELWITHDEBINFO MINSIZEREL)
  string(REPLACE "-DNDEBUG" "" CMAKE_CXX_FLAGS_${config} "${CMAKE_CXX_FLAGS_${config}}")
endforeach()
set(CHOKELOOPS_FUZZ_OPT)
if(NOT CMAKE_BUILD_TYPE OR CMAKE_BUILD_TYPE STREQUAL "Debug")
  set(CHOKELOOPS_FUZZ_OPT -O1)
endif()
set(CHOKELOOPS_FUZZ_FLAGS ${CHOKELOOPS_FUZZ_OPT} -g -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
  -fno-sanitize-recover=undefined
  # gemmi's std::hash<ResidueId> shifts the residue number left, negative ones too (residue -1 is common):
  # undefined in C++17, two's-complement arithmetic in practice and in C++20, and only a hash. Not ours to fix.
  -fno-sanitize=shift-base
  # third-party false positives, each explained in the file
  -fsanitize-ignorelist=${PROJECT_SOURCE_DIR}/cmake/fuzz_ignorelist.txt
  # dense per-voxel arithmetic, whose branches are the same for every input of a size: no coverage there
  -fsanitize-coverage-ignorelist=${PROJECT_SOURCE_DIR}/cmake/fuzz_coverage_ignorelist.txt)
file(GLOB CHOKELOOPS_FUZZ_INPUT_SOURCES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/src/io/*.cpp
  ${PROJECT_SOURCE_DIR}/src/field/*.cpp)
add_library(chokeloops_fuzz_input STATIC ${CHOKELOOPS_FUZZ_INPUT_SOURCES})
# the lists change what the compiler emits, so an edit to them rebuilds what they apply to
set_source_files_properties(${CHOKELOOPS_FUZZ_INPUT_SOURCES} PROPERTIES OBJECT_DEPENDS
  "${PROJECT_SOURCE_DIR}/cmake/fuzz_ignorelist.txt;${PROJECT_SOURCE_DIR}/cmake/fuzz_coverage_ignorelist.txt")
target_include_directories(chokeloops_fuzz_input PUBLIC ${PROJECT_SOURCE_DIR}/include PRIVATE ${PROJECT_SOURCE_DIR}/src)
target_compile_definitions(chokeloops_fuzz_input PUBLIC CHOKELOOPS_VERSION="${PROJECT_VERSION}"
  CHOKELOOPS_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
target_compile_options(chokeloops_fuzz_input PUBLIC ${CHOKELOOPS_FUZZ_FLAGS})
target_link_libraries(chokeloops_fuzz_input PUBLIC ${CHOKELOOPS_INPUT_LINK_LIBRARIES})

function(chokeloops_add_fuzzer name source)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE chokeloops_fuzz_input)
  target_link_options(${name} PRIVATE -fsanitize=fuzzer,address,undefined)
  target_compile_definitions(${name} PRIVATE ${ARGN})
endfunction()

foreach(ext obj ply off stl)
  chokeloops_add_fuzzer(fuzz_${ext} ${PROJECT_SOURCE_DIR}/fuzz/fuzz_mesh_reader.cpp CHOKELOOPS_FUZZ_EXT=".${ext}")
endforeach()
chokeloops_add_fuzzer(fuzz_mesh_levelset ${PROJECT_SOURCE_DIR}/fuzz/fuzz_mesh_levelset.cpp)
chokeloops_add_fuzzer(fuzz_vdb ${PROJECT_SOURCE_DIR}/fuzz/fuzz_vdb_reader.cpp)
chokeloops_add_fuzzer(fuzz_vdb_levelset ${PROJECT_SOURCE_DIR}/fuzz/fuzz_vdb_levelset.cpp)
chokeloops_add_fuzzer(fuzz_pdb ${PROJECT_SOURCE_DIR}/fuzz/fuzz_molecule_reader.cpp CHOKELOOPS_FUZZ_EXT=".pdb")
chokeloops_add_fuzzer(fuzz_cif ${PROJECT_SOURCE_DIR}/fuzz/fuzz_molecule_reader.cpp CHOKELOOPS_FUZZ_EXT=".cif")
chokeloops_add_fuzzer(fuzz_nii ${PROJECT_SOURCE_DIR}/fuzz/fuzz_volume_reader.cpp CHOKELOOPS_FUZZ_EXT=".nii")
chokeloops_add_fuzzer(fuzz_nrrd ${PROJECT_SOURCE_DIR}/fuzz/fuzz_volume_reader.cpp CHOKELOOPS_FUZZ_EXT=".nrrd")
chokeloops_add_fuzzer(fuzz_mha ${PROJECT_SOURCE_DIR}/fuzz/fuzz_volume_reader.cpp CHOKELOOPS_FUZZ_EXT=".mha")
