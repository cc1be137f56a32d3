# The build checks the layering (ARCHITECTURE.md "Libraries"):
#   - dpc_check_links(): at configure time, no core or service library links, even indirectly,
#     a library above it (the dpc tool's library; the DDS layer for the pure core);
#   - the dpc_layering target (built by `all`): no source of a core module includes a Fast DDS,
#     generated (dpc/msg), bus, Protobuf or tool header. It re-runs when a checked file changes.

# The libraries `target` links, directly or through others (targets only).
function(dpc_link_closure target out)
  set(seen "")
  set(queue ${target})
  while(queue)
    list(POP_FRONT queue current)
    if(NOT TARGET ${current} OR current IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${current})
    get_target_property(type ${current} TYPE)
    set(links "")
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(direct ${current} LINK_LIBRARIES)
      if(direct)
        list(APPEND links ${direct})
      endif()
    endif()
    get_target_property(interface ${current} INTERFACE_LINK_LIBRARIES)
    if(interface)
      list(APPEND links ${interface})
    endif()
    list(APPEND queue ${links})
  endwhile()
  list(REMOVE_ITEM seen ${target})
  set(${out} ${seen} PARENT_SCOPE)
endfunction()

# Fails the configuration if any of `targets` links one of the FORBIDDEN libraries.
function(dpc_check_links)
  cmake_parse_arguments(ARG "" "" "TARGETS;FORBIDDEN" ${ARGN})
  foreach(target IN LISTS ARG_TARGETS)
    dpc_link_closure(${target} closure)
    foreach(forbidden IN LISTS ARG_FORBIDDEN)
      if(forbidden IN_LIST closure)
        message(FATAL_ERROR "layering: ${target} links ${forbidden} (see ARCHITECTURE.md, Libraries)")
      endif()
    endforeach()
  endforeach()
endfunction()

# Adds to the dpc_layering target a check that no file in FILES includes a header matching
# FORBIDDEN (a regular expression), named RULE in the error.
set(DPC_LAYERING_STAMPS "" CACHE INTERNAL "")
function(dpc_check_includes)
  cmake_parse_arguments(ARG "" "RULE;FORBIDDEN" "FILES" ${ARGN})
  string(MAKE_C_IDENTIFIER "${ARG_RULE}" id)
  set(stamp ${CMAKE_BINARY_DIR}/layering/${id}.stamp)
  add_custom_command(
    OUTPUT ${stamp}
    COMMAND ${CMAKE_COMMAND} "-DRULE=${ARG_RULE}" "-DFORBIDDEN=${ARG_FORBIDDEN}"
            "-DFILES=${ARG_FILES}" -DSTAMP=${stamp} -P ${PROJECT_SOURCE_DIR}/cmake/check_includes.cmake
    DEPENDS ${ARG_FILES} ${PROJECT_SOURCE_DIR}/cmake/check_includes.cmake
    COMMENT "layering: ${ARG_RULE}"
    VERBATIM)
  set(DPC_LAYERING_STAMPS ${DPC_LAYERING_STAMPS} ${stamp} CACHE INTERNAL "")
endfunction()
