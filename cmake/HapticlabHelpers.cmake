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

# hl_add_test(<module> <source>) builds tests/<module>/<source>_test.cpp.
# SERIAL: the tests run alone (ctest RUN_SERIAL), for tests whose loops run on the real
# clock and fault on missed deadlines when another test shares the machine's cores.
function(hl_add_test module source)
  cmake_parse_arguments(T "SERIAL" "" "DEPS" ${ARGN})
  set(target ${module}_${source}_test)
  add_executable(${target} ${CMAKE_CURRENT_SOURCE_DIR}/${module}/${source}_test.cpp)
  target_link_libraries(${target} PRIVATE hapticlab::${module} ${T_DEPS} fmt::fmt
                        hl_test_util GTest::gtest_main hl_warnings)
  set(serial FALSE)
  if(T_SERIAL)
    set(serial TRUE)
  endif()
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60
                       PROPERTIES ENVIRONMENT "HL_TEST_DATA=${CMAKE_CURRENT_SOURCE_DIR}/data"
                                  RUN_SERIAL ${serial})
endfunction()
