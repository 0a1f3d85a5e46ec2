# mtled_left_out_plugin(CATEGORY category NAME name REASON text): a component this build leaves out, the reason a
# sentence that says so ("not built: ...") (an optional
# dependency missing or switched off). The names and reasons go to left-out.txt beside the plugins, which the kernel
# reads when a scene names such a component, so the message says why it is missing instead of "unknown". A reason
# holds no semicolon (CMake would split it).
function(mtled_left_out_plugin)
  cmake_parse_arguments(ARG "" "CATEGORY;NAME;REASON" "" ${ARGN})
  set_property(GLOBAL APPEND PROPERTY MTLED_LEFT_OUT_PLUGINS "${ARG_CATEGORY} ${ARG_NAME}: ${ARG_REASON}")
endfunction()

# mtled_add_plugin(CATEGORY category NAME name SOURCES src... [LINK_LIBRARIES libs...]
#                  [OUTPUT_DIRECTORY dir] [NO_INSTALL])
#
# Builds one mtled component as its own run-time-loaded module, `mtled-CATEGORY-NAME.so`. The file name is the
# component: the kernel maps a scene's "type" to the file without loading anything else. Symbols are
# hidden except the handshake and registration entry points exported by MTLED_PLUGIN (mtled/plugin.hpp).
function(mtled_add_plugin)
  cmake_parse_arguments(ARG "NO_INSTALL" "CATEGORY;NAME;OUTPUT_DIRECTORY" "SOURCES;LINK_LIBRARIES" ${ARGN})
  set(name ${ARG_NAME})
  set(category ${ARG_CATEGORY})
  # CATEGORY is checked where the categories are listed: MTLED_PLUGIN's static_assert against kPluginCategories.
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "mtled_add_plugin(${name}): SOURCES is required")
  endif()
  if(NOT name MATCHES "^[a-z][a-z0-9_]*$")
    message(FATAL_ERROR "mtled_add_plugin(${name}): names are lower_snake_case")
  endif()
  set(target mtled_${category}_${name})
  add_library(${target} MODULE ${ARG_SOURCES})
  set_target_properties(${target} PROPERTIES
    PREFIX ""
    OUTPUT_NAME "mtled-${category}-${name}"
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    INSTALL_RPATH "$ORIGIN/../..")
  if(TARGET mtled_core)  # inside the mtled build
    target_link_libraries(${target} PRIVATE mtled_core mtled_warnings ${ARG_LINK_LIBRARIES})
    if(NOT ARG_NO_INSTALL)
      set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${MTLED_PLUGIN_OUTPUT_DIR})
      install(TARGETS ${target} LIBRARY DESTINATION ${MTLED_PLUGIN_INSTALL_DIR})
      set_property(GLOBAL APPEND PROPERTY MTLED_PLUGIN_TARGETS ${target})
    endif()
  else()  # a third-party plugin built against an installed mtled
    target_link_libraries(${target} PRIVATE mtled::core ${ARG_LINK_LIBRARIES})
  endif()
  if(ARG_OUTPUT_DIRECTORY)
    set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${ARG_OUTPUT_DIRECTORY})
  endif()
  target_compile_definitions(${target} PRIVATE MTLED_PLUGIN_NAME="${name}" MTLED_PLUGIN_CATEGORY="${category}")
endfunction()
