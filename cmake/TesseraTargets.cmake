include(GNUInstallDirs)
# tessera_add_module(<name> SOURCES ... DEPENDS ...)
# Declares the library tessera_<name>, its alias tessera::<name>, its public include folder
# <name>/include, the project's warnings and C++ standard. Every module goes through here so
# the modules are built alike.
set(TESSERA_WARNINGS -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion)

function(tessera_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  set(target tessera_${name})
  if(ARG_SOURCES)
    add_library(${target} ${ARG_SOURCES})
    set(scope PUBLIC)
    target_compile_options(${target} PRIVATE ${TESSERA_WARNINGS})
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  else()
    add_library(${target} INTERFACE)
    set(scope INTERFACE)
  endif()
  add_library(tessera::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  target_compile_features(${target} ${scope} cxx_std_20)
  target_include_directories(${target} ${scope}
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  if(ARG_DEPENDS)
    target_link_libraries(${target} ${scope} ${ARG_DEPENDS})
  endif()
  set_property(GLOBAL APPEND PROPERTY TESSERA_MODULE_TARGETS ${target})
  set_property(GLOBAL APPEND PROPERTY TESSERA_MODULE_INCLUDE_DIRS ${CMAKE_CURRENT_SOURCE_DIR}/include)
endfunction()
