# Helpers shared by every module (STYLE.md §2).

add_library(hl_warnings INTERFACE)
target_compile_options(hl_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wimplicit-fallthrough -Wvla
  # Designated initializers that omit defaulted fields are idiomatic C++20.
  -Wno-missing-field-initializers
  # GCC 12 reports impossible std::string overlaps at -O2 (GCC PR 105329).
  $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict>)
if(HL_WERROR)
  target_compile_options(hl_warnings INTERFACE -Werror)
endif()
if(HL_SANITIZE)
  string(REPLACE ";" "," _hl_san "${HL_SANITIZE}")
  target_compile_options(hl_warnings INTERFACE -fsanitize=${_hl_san} -fno-omit-frame-pointer)
  target_link_options(hl_warnings INTERFACE -fsanitize=${_hl_san})
endif()

# hl_add_module(<name> SOURCES ... DEPS PUBLIC ... PRIVATE ...)
# Creates target hl_<name> with alias hapticlab::<name>; public headers live in
# <name>/include/hapticlab/<name>/.
function(hl_add_module name)
  cmake_parse_arguments(M "" "" "SOURCES;DEPS" ${ARGN})
  add_library(hl_${name} STATIC ${M_SOURCES})
  add_library(hapticlab::${name} ALIAS hl_${name})
  target_include_directories(hl_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>)
  target_link_libraries(hl_${name} ${M_DEPS})
  target_link_libraries(hl_${name} PRIVATE hl_warnings)
endfunction()

# hl_add_test(<module> <source> [SERIAL] [ENVIRONMENT var=value] [DEPS ...] [TOOLS ...])
# adds tests/<module>/<source>_test.cpp to the module's one test executable, <module>_tests
# (one link per module instead of one per file: link time in the release, ASan and TSan
# builds). hl_add_module_tests() below creates the executables once every file is listed.
# DEPS: libraries the file needs besides hapticlab::<module> (linked into <module>_tests).
# TOOLS: targets the tests run (built before the executable, e.g. the hapticlab CLI).
# SERIAL: the file's tests run alone (ctest RUN_SERIAL), for tests whose loops run on the real
# clock and fault on missed deadlines when another test shares the machine's cores.
# ENVIRONMENT: one variable set for this file's tests only.
# SERIAL and ENVIRONMENT apply to the test suites the file defines (TEST, TEST_F, TEST_P
# names read from the file); they are discovered separately with a gtest filter.
# HL_TEST_ONLY (cache list of <module>/<source>): build only these files, e.g. the threaded
# tests in the ThreadSanitizer build (scripts/test).
set(HL_TEST_ONLY "" CACHE STRING "Only these test files (<module>/<source>;...); empty: all")
# HL_UNITY: compile each module's test files in batches of HL_UNITY_BATCH files, one compile
# unit per batch (CMake's UNITY_BUILD): gtest's, Eigen's and fmt's inline code is parsed and
# generated once per batch instead of once per file (docs/performance.md, "Build and CI";
# scripts/test uses it in CI). Each test file keeps its file-local names in a namespace of its
# own (tests/<module>/<name>_test.cpp: namespace ...::<name>_test), so they cannot meet.
option(HL_UNITY "Compile the module test files in unity batches" OFF)
set(HL_UNITY_BATCH 8 CACHE STRING "Test files per unity compile unit (HL_UNITY)")

function(hl_add_test module source)
  cmake_parse_arguments(T "SERIAL" "ENVIRONMENT" "DEPS;TOOLS" ${ARGN})
  if(HL_TEST_ONLY AND NOT "${module}/${source}" IN_LIST HL_TEST_ONLY)
    return()
  endif()
  set(file ${CMAKE_CURRENT_SOURCE_DIR}/${source}_test.cpp)
  if(NOT EXISTS ${file})
    set(file ${CMAKE_CURRENT_SOURCE_DIR}/${module}/${source}_test.cpp)
  endif()
  # A unity batch (HL_UNITY) is one compile unit: each file keeps its tests and helpers in a
  # namespace named after it, so that two files' file-local names cannot meet.
  get_filename_component(stem ${file} NAME_WE)
  file(STRINGS ${file} own REGEX "^namespace [A-Za-z_:]+::${stem} {$")
  if(NOT own)
    set(level WARNING)
    if(HL_UNITY)
      set(level FATAL_ERROR)
    endif()
    message(${level} "${file}: no namespace named after the file: put its code in "
            "`namespace hapticlab[::module]::${stem} { namespace { ... } }` (HL_UNITY)")
  endif()
  get_property(modules GLOBAL PROPERTY HL_TEST_MODULES)
  if(NOT module IN_LIST modules)
    set_property(GLOBAL APPEND PROPERTY HL_TEST_MODULES ${module})
  endif()
  set_property(GLOBAL APPEND PROPERTY HL_TEST_${module}_SOURCES ${file})
  set_property(GLOBAL APPEND PROPERTY HL_TEST_${module}_DEPS ${T_DEPS})
  set_property(GLOBAL APPEND PROPERTY HL_TEST_${module}_TOOLS ${T_TOOLS})
  if(T_SERIAL OR T_ENVIRONMENT)
    # The suites this file defines, as a gtest filter (parameterised suites carry a prefix).
    file(STRINGS ${file} lines REGEX "^(TEST|TEST_F|TEST_P)\\(")
    set(suites "")
    foreach(line IN LISTS lines)
      string(REGEX MATCH "^TEST(_F|_P)?\\( *([A-Za-z0-9_]+)" unused "${line}")
      set(suite "${CMAKE_MATCH_2}")
      if(CMAKE_MATCH_1 STREQUAL "_P")
        set(suite "*/${suite}")
      endif()
      if(NOT "${suite}.*" IN_LIST suites)
        list(APPEND suites "${suite}.*")
      endif()
    endforeach()
    list(JOIN suites ":" filter)
    set(serial FALSE)
    if(T_SERIAL)
      set(serial TRUE)
    endif()
    set(env "HL_TEST_DATA=${CMAKE_SOURCE_DIR}/tests/data")
    if(T_ENVIRONMENT)
      set(env "${T_ENVIRONMENT}")
    endif()
    # One group per file: filter|serial|environment.
    set_property(GLOBAL APPEND PROPERTY HL_TEST_${module}_GROUPS "${filter}|${serial}|${env}")
  endif()
endfunction()

# hl_add_module_tests(): one executable <module>_tests per module from its listed files. Each
# SERIAL or ENVIRONMENT file's suites are discovered with their own properties; the rest of
# the executable's tests with the default ones (every ctest name stays the gtest name).
function(hl_add_module_tests)
  get_property(modules GLOBAL PROPERTY HL_TEST_MODULES)
  foreach(module IN LISTS modules)
    get_property(sources GLOBAL PROPERTY HL_TEST_${module}_SOURCES)
    get_property(deps GLOBAL PROPERTY HL_TEST_${module}_DEPS)
    get_property(tools GLOBAL PROPERTY HL_TEST_${module}_TOOLS)
    get_property(groups GLOBAL PROPERTY HL_TEST_${module}_GROUPS)
    list(REMOVE_DUPLICATES deps)
    set(target ${module}_tests)
    add_executable(${target} ${sources})
    if(HL_UNITY)
      set_target_properties(${target} PROPERTIES UNITY_BUILD ON
                            UNITY_BUILD_BATCH_SIZE ${HL_UNITY_BATCH})
    endif()
    if(TARGET hapticlab::${module})
      target_link_libraries(${target} PRIVATE hapticlab::${module})
    endif()
    target_link_libraries(${target} PRIVATE ${deps} fmt::fmt hl_test_util GTest::gtest_main
                          hl_warnings)
    if(tools)
      list(REMOVE_DUPLICATES tools)
      add_dependencies(${target} ${tools})
    endif()
    set(excluded "")
    foreach(group IN LISTS groups)
      string(REPLACE "|" ";" fields "${group}")
      list(GET fields 0 filter)
      list(GET fields 1 serial)
      list(GET fields 2 env)
      gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60 TEST_FILTER "${filter}"
                           PROPERTIES ENVIRONMENT "${env}" RUN_SERIAL ${serial})
      if(excluded)
        string(APPEND excluded ":")
      endif()
      string(APPEND excluded "${filter}")
    endforeach()
    set(filter "*")
    if(excluded)
      set(filter "*-${excluded}")
    endif()
    gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60 TEST_FILTER "${filter}"
                         PROPERTIES ENVIRONMENT "HL_TEST_DATA=${CMAKE_SOURCE_DIR}/tests/data"
                                    RUN_SERIAL FALSE)
  endforeach()
endfunction()
