# FindMETIS: Debian's libmetis-dev ships neither a CMake package nor a pkg-config file,
# so look for the header and the library and wrap them as the imported target METIS::METIS.
find_path(METIS_INCLUDE_DIR NAMES metis.h PATH_SUFFIXES metis)
find_library(METIS_LIBRARY NAMES metis)
if(METIS_INCLUDE_DIR AND EXISTS "${METIS_INCLUDE_DIR}/metis.h")
  file(STRINGS "${METIS_INCLUDE_DIR}/metis.h" _metis_version_lines
       REGEX "^#define METIS_VER_(MAJOR|MINOR|SUBMINOR)[ \t]+[0-9]+")
  foreach(_part MAJOR MINOR SUBMINOR)
    string(REGEX REPLACE ".*METIS_VER_${_part}[ \t]+([0-9]+).*" "\\1" _metis_${_part}
           "${_metis_version_lines}")
  endforeach()
  set(METIS_VERSION "${_metis_MAJOR}.${_metis_MINOR}.${_metis_SUBMINOR}")
endif()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(METIS REQUIRED_VARS METIS_LIBRARY METIS_INCLUDE_DIR
                                  VERSION_VAR METIS_VERSION)
if(METIS_FOUND AND NOT TARGET METIS::METIS)
  add_library(METIS::METIS UNKNOWN IMPORTED)
  set_target_properties(METIS::METIS PROPERTIES
    IMPORTED_LOCATION "${METIS_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${METIS_INCLUDE_DIR}")
endif()
mark_as_advanced(METIS_INCLUDE_DIR METIS_LIBRARY)
