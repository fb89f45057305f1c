# `cmake --install build --prefix PREFIX`: the public headers (core/include/tessera and, with DDS,
# transport/include/tessera/dds), the libraries as exported targets Tessera::core and
# Tessera::dds, the executables, and PREFIX/lib/cmake/Tessera/TesseraConfig.cmake (+ version)
# so that `find_package(Tessera)` works for programs outside the tree (examples/).
# Internal headers (those beside the sources) are not installed: a public header never
# includes one (tests/public_headers_test.cmake checks it).
include(CMakePackageConfigHelpers)

set(TESSERA_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/Tessera)
set(TESSERA_EXPORTED tessera_core tessera_core_internal)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/core/include/tessera DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

if(TARGET tessera_transport)
  # Tessera::dds: host an agent, a coordinator or a whole run on this host from a program
  # (<tessera/dds/agent.hpp>, coordinator.hpp, launch.hpp). Its implementation is the in-tree
  # static libraries it links, exported along (their headers stay internal).
  add_library(tessera_dds INTERFACE)
  add_library(Tessera::dds ALIAS tessera_dds)
  set_target_properties(tessera_dds PROPERTIES EXPORT_NAME dds)
  target_include_directories(tessera_dds INTERFACE
    $<BUILD_INTERFACE:${CMAKE_SOURCE_DIR}/transport/include> $<INSTALL_INTERFACE:include>)
  target_link_libraries(tessera_dds INTERFACE tessera_agent_app tessera_coordinator_app
                                              tessera_launch tessera_core)
  list(APPEND TESSERA_EXPORTED tessera_dds tessera_agent_app tessera_coordinator_app
       tessera_launch tessera_agent_lib tessera_coordinator_lib tessera_session_process
       tessera_transport tessera_session_options tessera_process_tuning tessera_idl)
  install(DIRECTORY ${CMAKE_SOURCE_DIR}/transport/include/tessera
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(TARGETS tessera tessera-agent tessera-coordinator tessera-fork-server
          RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
else()
  install(TARGETS tessera RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

install(TARGETS ${TESSERA_EXPORTED} EXPORT TesseraTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT TesseraTargets NAMESPACE Tessera:: DESTINATION ${TESSERA_CMAKE_DIR})

set(TESSERA_CONFIG_WITH_DDS OFF)
if(TARGET tessera_transport)
  set(TESSERA_CONFIG_WITH_DDS ON)
endif()
configure_package_config_file(${CMAKE_SOURCE_DIR}/cmake/TesseraConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/TesseraConfig.cmake
                              INSTALL_DESTINATION ${TESSERA_CMAKE_DIR}
                              PATH_VARS CMAKE_INSTALL_BINDIR)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/TesseraConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/TesseraConfig.cmake ${CMAKE_BINARY_DIR}/TesseraConfigVersion.cmake
              ${CMAKE_SOURCE_DIR}/cmake/FindSuiteSparseCholmod.cmake
        DESTINATION ${TESSERA_CMAKE_DIR})
