# find_package(svslam_lcm_types): the imported targets svslam::lcm_types, the C++ headers of
# svslam's LCM message types (#include <svslam_lcm/pose_t.hpp>), and svslam::lcm_types_c, the C
# types (#include <svslam_lcm_pose_t.h>, libsvslam_lcm_c.a), each with LCM itself (pkg-config
# lcm, Debian liblcm-dev; lcm.pc needs libglib2.0-dev). Installed to
# <prefix>/lib/cmake/svslam_lcm_types/ by svslam's `cmake --install`.
include(CMakeFindDependencyMacro)
find_dependency(PkgConfig)
get_filename_component(_svslam_lcm_prefix "${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
if(NOT TARGET svslam::lcm_types)
  pkg_check_modules(SVSLAM_LCM_LCM REQUIRED IMPORTED_TARGET lcm)
  add_library(svslam::lcm_types INTERFACE IMPORTED)
  set_target_properties(svslam::lcm_types PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${_svslam_lcm_prefix}/include/svslam/lcm"
    INTERFACE_LINK_LIBRARIES PkgConfig::SVSLAM_LCM_LCM)
endif()
# The C types: #include <svslam_lcm_pose_t.h>, svslam_lcm_pose_t_decode(), ...
if(NOT TARGET svslam::lcm_types_c)
  add_library(svslam::lcm_types_c STATIC IMPORTED)
  set_target_properties(svslam::lcm_types_c PROPERTIES
    IMPORTED_LOCATION "${_svslam_lcm_prefix}/lib/libsvslam_lcm_c.a"
    IMPORTED_LINK_INTERFACE_LANGUAGES C
    INTERFACE_INCLUDE_DIRECTORIES "${_svslam_lcm_prefix}/include/svslam/lcm"
    INTERFACE_LINK_LIBRARIES PkgConfig::SVSLAM_LCM_LCM)
endif()
set(svslam_lcm_types_JAR "${_svslam_lcm_prefix}/share/java/svslam_lcm_types.jar")
if(NOT EXISTS "${svslam_lcm_types_JAR}")
  set(svslam_lcm_types_JAR "")
endif()
unset(_svslam_lcm_prefix)
