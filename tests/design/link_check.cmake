# The boundary check (docs/architecture.md "Modules"): the real-time library hl_runner must
# not reach the statistics stack. At configure time this walks hl_runner's link graph as CMake
# resolves it (LINK_LIBRARIES and INTERFACE_LINK_LIBRARIES of every target it reaches, aliases
# resolved, $<LINK_ONLY:> and $<BUILD_INTERFACE:> unwrapped) and writes every target and
# library it finds to runner_link_closure.txt; the ctest test Boundary.RunnerLinksNoStatistics
# (tests/design/check_link_closure.cmake) fails when hl_stats, a Boost target or PLplot is in it.
# Boost.Math is header-only (Boost::headers), so the linker command alone would not show it:
# the target graph does.

function(_hl_link_walk target out_var)
  set(seen ${${out_var}})
  set(stack ${target})
  while(stack)
    list(POP_BACK stack t)
    get_target_property(aliased ${t} ALIASED_TARGET)
    if(aliased)
      set(t ${aliased})
    endif()
    if("${t}" IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${t})
    set(items "")
    get_target_property(type ${t} TYPE)
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(direct ${t} LINK_LIBRARIES)
      if(direct)
        list(APPEND items ${direct})
      endif()
    endif()
    get_target_property(iface ${t} INTERFACE_LINK_LIBRARIES)
    if(iface)
      list(APPEND items ${iface})
    endif()
    foreach(item IN LISTS items)
      # Unwrap the generator expressions CMake itself writes for link interfaces.
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" item "${item}")
      string(REGEX REPLACE "^\\$<BUILD_INTERFACE:(.*)>$" "\\1" item "${item}")
      string(REGEX REPLACE "^::@\\([^)]*\\)" "" item "${item}")
      if(item STREQUAL "" OR item STREQUAL "::@")
        continue()
      endif()
      if(TARGET ${item})
        list(APPEND stack ${item})
      elseif(NOT "${item}" IN_LIST seen)
        # A plain library (name, path or flag) or an expression kept as written.
        list(APPEND seen "${item}")
      endif()
    endforeach()
  endwhile()
  set(${out_var} ${seen} PARENT_SCOPE)
endfunction()

set(_hl_runner_closure "")
_hl_link_walk(hl_runner _hl_runner_closure)
list(JOIN _hl_runner_closure "\n" _hl_text)
file(WRITE ${CMAKE_BINARY_DIR}/runner_link_closure.txt "${_hl_text}\n")
add_test(NAME Boundary.RunnerLinksNoStatistics
         COMMAND ${CMAKE_COMMAND} -DCLOSURE=${CMAKE_BINARY_DIR}/runner_link_closure.txt
                 -P ${CMAKE_CURRENT_SOURCE_DIR}/design/check_link_closure.cmake)
