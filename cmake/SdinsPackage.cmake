# CPack: the installed tool as a Debian package (`cpack -G DEB` in a configured build tree).
# Only the `sdins` component (bin/sdins and share/sdins) goes in; tests, benchmarks and the
# development recordings do not. Library dependencies come from dpkg-shlibdeps on the binary (liblcm,
# Open MPI, toml++, glib, libstdc++ ...); the packages the program runs but does not link are stated:
# python3 with matplotlib/numpy for the figures (plot scripts), RTKLIB's convbin for `sdins import
# rtklib` with a .ubx, mpirun for `mpirun sdins montecarlo`, cmake/g++ for `sdins audit stack`.
set(CPACK_PACKAGE_NAME "sdins")
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_VENDOR "sdins project")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "SDINS/GPS integrated navigation for bank-to-turn aircraft: flight software, simulator and tools")
set(CPACK_PACKAGE_DESCRIPTION
    "Strapdown INS mechanized at 200 Hz with a tightly coupled GPS extended Kalman filter (15- and 24-state), the\n"
    "truth simulator, SIL/HIL over CAN, LCM telemetry and logs, replay, Monte Carlo, the paper reproduction and\n"
    "the diagnosis of measured data. Run-time data (almanac, scenarios, filter configurations, DBC, LCM\n"
    "definitions, plot scripts) in /usr/share/sdins.")
set(CPACK_PACKAGE_CONTACT "sdins maintainers <sdins@localhost>")
set(CPACK_PACKAGE_INSTALL_DIRECTORY "sdins")
set(CPACK_COMPONENTS_ALL sdins)
set(CPACK_DEB_COMPONENT_INSTALL OFF)
set(CPACK_INSTALL_CMAKE_PROJECTS "${CMAKE_BINARY_DIR};sdins;sdins;/")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")
set(CPACK_GENERATOR "DEB")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION "science")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3, python3-matplotlib, python3-numpy")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "rtklib, openmpi-bin, can-utils")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "cmake, g++, ninja-build")
include(CPack)
