# Finds TetGen built as a library (Debian: libtet1.5-dev, header tetgen.h, library libtet),
# which ships no CMake config. Defines TetGen_FOUND and the imported target TetGen::TetGen.
#
# The header declares the switch-string tetrahedralize() entry point, and makes TetGen throw
# instead of calling exit(), only with TETLIBRARY defined, so the target carries it.

find_path(TetGen_INCLUDE_DIR tetgen.h PATH_SUFFIXES tetgen)
find_library(TetGen_LIBRARY NAMES tet tetgen)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(TetGen REQUIRED_VARS TetGen_LIBRARY TetGen_INCLUDE_DIR)

if(TetGen_FOUND AND NOT TARGET TetGen::TetGen)
  add_library(TetGen::TetGen UNKNOWN IMPORTED)
  set_target_properties(TetGen::TetGen PROPERTIES
    IMPORTED_LOCATION "${TetGen_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${TetGen_INCLUDE_DIR}"
    INTERFACE_COMPILE_DEFINITIONS TETLIBRARY)
endif()
mark_as_advanced(TetGen_INCLUDE_DIR TetGen_LIBRARY)
