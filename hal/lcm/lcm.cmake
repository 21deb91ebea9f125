# LCM half of the HAL: message types, conversions, log I/O, telemetry (included by hal/CMakeLists.txt).
#
# Debian's LCM 1.3.1 ships no CMake package file, so the library comes from pkg-config (its
# lcm.pc needs glib-2.0: libglib2.0-dev). The C++ (and Python, for the tests) message code is
# generated from hal/lcm/*.lcm by lcm-gen into the build tree on every change; it is never
# checked in.
find_package(PkgConfig REQUIRED)
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
find_program(SDINS_LCM_GEN lcm-gen REQUIRED)

file(GLOB SDINS_LCM_TYPES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/lcm/*.lcm)
set(SDINS_LCM_GEN_DIR ${CMAKE_CURRENT_BINARY_DIR}/lcm_gen)
set(SDINS_LCM_GEN_OUTPUTS "")
foreach(type_file ${SDINS_LCM_TYPES})
  get_filename_component(type_name ${type_file} NAME_WE)
  list(APPEND SDINS_LCM_GEN_OUTPUTS ${SDINS_LCM_GEN_DIR}/cpp/sdins/${type_name}.hpp
       ${SDINS_LCM_GEN_DIR}/python/sdins/${type_name}.py)
endforeach()
# --cpp-std=c++11: static constexpr members for the .lcm constants.
add_custom_command(
  OUTPUT ${SDINS_LCM_GEN_OUTPUTS}
  COMMAND ${CMAKE_COMMAND} -E rm -rf ${SDINS_LCM_GEN_DIR}
  COMMAND ${SDINS_LCM_GEN} --cpp --cpp-std=c++11 --cpp-hpath ${SDINS_LCM_GEN_DIR}/cpp
          --python --ppath ${SDINS_LCM_GEN_DIR}/python ${SDINS_LCM_TYPES}
  DEPENDS ${SDINS_LCM_TYPES}
  COMMENT "lcm-gen: C++ and Python code of the sdins LCM message types"
  VERBATIM)
add_custom_target(sdins_lcm_gen DEPENDS ${SDINS_LCM_GEN_OUTPUTS})
add_dependencies(sdins_hal sdins_lcm_gen)
# SYSTEM: the generated code is not held to the project's warning flags.
target_include_directories(sdins_hal SYSTEM PUBLIC ${SDINS_LCM_GEN_DIR}/cpp)
target_link_libraries(sdins_hal PUBLIC PkgConfig::LCM)

# The project's warning flags for the LCM sources (the rest of hal/ sets its own).
file(GLOB SDINS_HAL_LCM_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/lcm_*.cpp)
set_source_files_properties(${SDINS_HAL_LCM_SOURCES} PROPERTIES COMPILE_OPTIONS
                            "-Wall;-Wextra;-Werror;-Wshadow;-Wconversion;-Wno-sign-conversion")

# For the tests: where the generated Python message code is (an independent encoder).
set_property(GLOBAL PROPERTY SDINS_LCM_PYTHON_DIR ${SDINS_LCM_GEN_DIR}/python)
