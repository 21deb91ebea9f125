# The product's run-time data (cfg/data_dir.hpp): listed once here, staged into the build tree as
# ${CMAKE_BINARY_DIR}/share/sdins (so build/<preset>/tools/sdins finds ../share/sdins exactly as an
# installed PREFIX/bin/sdins finds PREFIX/share/sdins) and installed to ${CMAKE_INSTALL_DATADIR}/sdins.
include(GNUInstallDirs)

set(SDINS_DATA_STAGE "${CMAKE_BINARY_DIR}/share/sdins")
set(SDINS_DATA_INSTALL "${CMAKE_INSTALL_DATADIR}/sdins")
set(_sdins_data_stamps)

# sdins_data_files(SUBDIR FILES...): FILES go to <data dir>/SUBDIR.
function(sdins_data_files subdir)
  set(dst "${SDINS_DATA_STAGE}/${subdir}")
  string(MAKE_C_IDENTIFIER "${subdir}" id)
  set(stamp "${CMAKE_BINARY_DIR}/CMakeFiles/sdins_data_${id}.stamp")
  add_custom_command(OUTPUT ${stamp}
                     COMMAND ${CMAKE_COMMAND} -E make_directory ${dst}
                     COMMAND ${CMAKE_COMMAND} -E copy_if_different ${ARGN} ${dst}
                     COMMAND ${CMAKE_COMMAND} -E touch ${stamp}
                     DEPENDS ${ARGN}
                     COMMENT "Staging sdins data: ${subdir}"
                     VERBATIM)
  set(_sdins_data_stamps ${_sdins_data_stamps} ${stamp} PARENT_SCOPE)
  install(FILES ${ARGN} DESTINATION ${SDINS_DATA_INSTALL}/${subdir} COMPONENT sdins)
endfunction()

file(GLOB _alm CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/data/almanac/*)
file(GLOB _scn CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/sim/scenarios/*.toml ${PROJECT_SOURCE_DIR}/sim/scenarios/*.md)
file(GLOB _cfg CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/*.toml ${PROJECT_SOURCE_DIR}/config/*.md)
file(GLOB _cfg_ds CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/config/datasets/*.toml)
file(GLOB _lcm CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/hal/lcm/*.lcm)
file(GLOB _plot CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tools/plot/*.py)
sdins_data_files(almanac ${_alm})
sdins_data_files(scenarios ${_scn})
sdins_data_files(config ${_cfg})
if(_cfg_ds)
  sdins_data_files(config/datasets ${_cfg_ds})
endif()
sdins_data_files(can ${PROJECT_SOURCE_DIR}/hal/can/sdins.dbc)
sdins_data_files(lcm ${_lcm})
sdins_data_files(plot ${_plot})

# The marker that names the directory as sdins data (sim::kDataDirMarker).
set(_marker_src "${CMAKE_BINARY_DIR}/sdins-data.txt")
file(WRITE ${_marker_src}.in "sdins run-time data, version @PROJECT_VERSION@ (layout: cfg/include/cfg/data_dir.hpp)\n")
configure_file(${_marker_src}.in ${_marker_src} @ONLY)
sdins_data_files(. ${_marker_src})

add_custom_target(sdins_data ALL DEPENDS ${_sdins_data_stamps})
