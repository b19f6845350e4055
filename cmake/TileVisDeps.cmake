# Every external dependency, found once. All come from Debian packages; the
# ./tilevis driver installs the missing ones.
find_package(Threads REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(fmt REQUIRED)
find_package(CLI11 REQUIRED)
find_package(OpenEXR 3 REQUIRED)

if(TILEVIS_MINIMAL)
  # Neither looked for nor required: SystemC, GLM, assimp, Boost, Google Benchmark (and CGAL,
  # which tests/visibility finds). GoogleTest is optional: without it no tests are built.
  find_package(GTest)
  return()
endif()

find_package(PkgConfig REQUIRED)
find_package(GTest REQUIRED)
find_package(glm REQUIRED)
find_package(assimp REQUIRED)
find_package(benchmark REQUIRED)
find_package(Boost 1.74 REQUIRED)   # header-only: multiprecision (exact test oracles), math (the sampler's quantiles)
pkg_check_modules(SYSTEMC REQUIRED IMPORTED_TARGET systemc)

add_library(tilevis_systemc INTERFACE)
target_link_libraries(tilevis_systemc INTERFACE PkgConfig::SYSTEMC)
target_compile_definitions(tilevis_systemc INTERFACE SC_CPLUSPLUS=201703L SC_INCLUDE_DYNAMIC_PROCESSES)
