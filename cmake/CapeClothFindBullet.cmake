# Finds Bullet for CapeCloth's build and for its installed CMake package, and defines the imported target
# CapeCloth::Bullet (Bullet's include directories, compile definitions and the libraries CapeCloth uses:
# BulletSoftBody, BulletDynamics, BulletCollision and LinearMath).
#
# Input:  CAPE_BULLET_DOUBLE  ON for Bullet built with BT_USE_DOUBLE_PRECISION (Debian ships it beside the
#                             single precision one: BulletConfig-float64.cmake, bullet-float64.pc,
#                             libBullet*-float64.so), OFF for single precision.
# Output: CapeCloth::Bullet   when found, and CAPE_BULLET_FOUND_BY saying where it came from;
#         CAPE_BULLET_MISSING when not found: one sentence saying what is needed.
#
# Bullet's own CMake package is tried first (its BulletConfig.cmake sets BULLET_* variables, no targets;
# relative paths in it are relative to BULLET_ROOT_DIR); pkg-config's `bullet` / `bullet-float64` otherwise.
include_guard(GLOBAL)

if(CAPE_BULLET_DOUBLE)
  set(_cape_bt_config BulletConfig-float64.cmake)
  set(_cape_bt_pc bullet-float64)
  set(_cape_bt_suffix -float64)
  set(_cape_bt_what "Bullet in double precision")
else()
  set(_cape_bt_config BulletConfig.cmake)
  set(_cape_bt_pc bullet)
  set(_cape_bt_suffix "")
  set(_cape_bt_what "Bullet in single precision")
endif()
# Link order: a library before the ones it uses.
set(_cape_bt_libs BulletSoftBody BulletDynamics BulletCollision LinearMath)
unset(CAPE_BULLET_FOUND_BY)
unset(CAPE_BULLET_MISSING)

if(NOT TARGET CapeCloth::Bullet)
  find_package(Bullet QUIET CONFIG CONFIGS ${_cape_bt_config})
  if(BULLET_FOUND AND DEFINED BULLET_ROOT_DIR)
    set(_cape_bt_includes "")
    foreach(dir IN LISTS BULLET_INCLUDE_DIRS)
      if(NOT IS_ABSOLUTE "${dir}")
        set(dir "${BULLET_ROOT_DIR}/${dir}")
      endif()
      list(APPEND _cape_bt_includes "${dir}")
    endforeach()
    set(_cape_bt_libdirs "")
    foreach(dir IN LISTS BULLET_LIBRARY_DIRS)
      if(NOT IS_ABSOLUTE "${dir}")
        set(dir "${BULLET_ROOT_DIR}/${dir}")
      endif()
      list(APPEND _cape_bt_libdirs "${dir}")
    endforeach()
    set(_cape_bt_found TRUE)
    set(_cape_bt_paths "")
    foreach(lib IN LISTS _cape_bt_libs)
      find_library(CAPE_BULLET_${lib}${_cape_bt_suffix}_LIBRARY NAMES ${lib}${_cape_bt_suffix}
                   PATHS ${_cape_bt_libdirs} NO_DEFAULT_PATH)
      if(CAPE_BULLET_${lib}${_cape_bt_suffix}_LIBRARY)
        list(APPEND _cape_bt_paths "${CAPE_BULLET_${lib}${_cape_bt_suffix}_LIBRARY}")
      else()
        set(_cape_bt_found FALSE)
      endif()
    endforeach()
    # BULLET_DEFINITIONS holds compiler flags ("-DBT_USE_DOUBLE_PRECISION"): keep the definitions.
    set(_cape_bt_defs "")
    separate_arguments(_cape_bt_flags UNIX_COMMAND "${BULLET_DEFINITIONS}")
    foreach(flag IN LISTS _cape_bt_flags)
      if(flag MATCHES "^-D(.+)$")
        list(APPEND _cape_bt_defs "${CMAKE_MATCH_1}")
      endif()
    endforeach()
    if(_cape_bt_found AND _cape_bt_includes)
      add_library(CapeCloth::Bullet INTERFACE IMPORTED GLOBAL)
      set_target_properties(CapeCloth::Bullet PROPERTIES
        INTERFACE_INCLUDE_DIRECTORIES "${_cape_bt_includes}"
        INTERFACE_LINK_LIBRARIES "${_cape_bt_paths}"
        INTERFACE_COMPILE_DEFINITIONS "${_cape_bt_defs}")
      set(CAPE_BULLET_FOUND_BY "Bullet's CMake package (${Bullet_DIR}/${_cape_bt_config}, Bullet ${BULLET_VERSION_STRING})")
    endif()
  endif()
endif()

if(NOT TARGET CapeCloth::Bullet)
  find_package(PkgConfig QUIET)
  if(PKG_CONFIG_FOUND)
    pkg_check_modules(CAPE_BULLET_PC QUIET IMPORTED_TARGET GLOBAL ${_cape_bt_pc})
    if(CAPE_BULLET_PC_FOUND)
      add_library(CapeCloth::Bullet INTERFACE IMPORTED GLOBAL)
      set_target_properties(CapeCloth::Bullet PROPERTIES INTERFACE_LINK_LIBRARIES PkgConfig::CAPE_BULLET_PC)
      set(CAPE_BULLET_FOUND_BY "pkg-config's ${_cape_bt_pc} (Bullet ${CAPE_BULLET_PC_VERSION})")
    endif()
  endif()
endif()

if(NOT TARGET CapeCloth::Bullet)
  string(CONCAT CAPE_BULLET_MISSING
      "CapeCloth's Bullet parts need ${_cape_bt_what} (LinearMath, BulletCollision, BulletDynamics, BulletSoftBody): "
      "neither Bullet's CMake package (${_cape_bt_config}, in the folder Bullet_DIR names) nor pkg-config's "
      "${_cape_bt_pc}.pc (found through PKG_CONFIG_PATH) was found. On Debian or Ubuntu: apt-get install libbullet-dev.")
endif()
