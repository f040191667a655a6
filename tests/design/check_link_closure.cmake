# cmake -DCLOSURE=<runner_link_closure.txt> -P check_link_closure.cmake
cmake_minimum_required(VERSION 3.25)
# Fails when hl_runner's link closure (written by tests/design/link_check.cmake) names the
# statistics library, a Boost target or library, or PLplot.
file(STRINGS ${CLOSURE} entries)
if(NOT entries)
  message(FATAL_ERROR "${CLOSURE} is empty: the walk of hl_runner's link graph found nothing")
endif()
if(NOT "hl_core" IN_LIST entries OR NOT "hl_runner" IN_LIST entries)
  message(FATAL_ERROR "${CLOSURE} lacks hl_runner or hl_core: the walk is broken")
endif()
set(bad "")
foreach(e IN LISTS entries)
  string(TOLOWER "${e}" lower)
  if(lower MATCHES "^hl_stats$|^hl_design$|boost|plplot")
    list(APPEND bad "${e}")
  endif()
endforeach()
if(bad)
  list(JOIN bad ", " bad)
  message(FATAL_ERROR "hl_runner (the real-time library) links ${bad}: power analysis and "
                      "anything else that needs the statistics stack belongs in design/, above runner "
                      "(docs/architecture.md)")
endif()
list(LENGTH entries n)
message(STATUS "hl_runner's link closure (${n} entries) has no statistics library, Boost or PLplot")
