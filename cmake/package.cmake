# The installed package: `find_package(sluice)` gives sluice::io,
# sluice::runtime, sluice::render, sluice::stream and (where built) sluice::desktop and sluice::xr, with
# headers under include/sluice and the shaders embedded in the libraries.
# sluice::import (simulation output -> .sluice; links VTK where built with
# it) is a component too, with its worker executable in libexec/sluice.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# Position-independent code: a host may link the static libraries into a
# shared object (the Python module, the ParaView plugin, a host's plugin).
foreach(t sluice_io sluice_runtime sluice_render sluice_stream sluice_desktop sluice_xr sluice_import)
  if(TARGET ${t})
    set_target_properties(${t} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  endif()
endforeach()

set(sluice_targets sluice_io sluice_runtime)
set_target_properties(sluice_io PROPERTIES EXPORT_NAME io)
set_target_properties(sluice_runtime PROPERTIES EXPORT_NAME runtime)
install(DIRECTORY io/include/sluice/io DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sluice)
install(FILES io/include/sluice/error.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sluice)
install(DIRECTORY runtime/include/sluice/runtime DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sluice)
foreach(t ${sluice_targets})
  target_include_directories(${t} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
endforeach()
install(TARGETS ${sluice_targets} EXPORT sluiceTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(EXPORT sluiceTargets NAMESPACE sluice:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sluice)

# render (Vulkan), desktop (GLFW), xr (OpenXR) and import are components
# with export sets of their own: a host that asks only for io needs no
# Vulkan, one that asks only for render neither GLFW nor OpenXR.
foreach(component render stream desktop xr import)
  string(TOUPPER ${component} upper)
  set(SLUICE_PACKAGE_${upper} OFF)
  if(TARGET sluice_${component})
    set_target_properties(sluice_${component} PROPERTIES EXPORT_NAME ${component})
    target_include_directories(sluice_${component} INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
    install(DIRECTORY ${component}/include/sluice/${component} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/sluice)
    if(component STREQUAL "import")  # the worker is installed by import/CMakeLists.txt
      install(TARGETS sluice_import_worker EXPORT sluice_importTargets RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR}/sluice)
    endif()
    install(TARGETS sluice_${component} EXPORT sluice_${component}Targets
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
            LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(EXPORT sluice_${component}Targets NAMESPACE sluice:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sluice)
    set(SLUICE_PACKAGE_${upper} ON)
  endif()
endforeach()
set(SLUICE_PACKAGE_IMPORT_VTK ${SLUICE_WITH_VTK})
configure_package_config_file(cmake/sluiceConfig.cmake.in ${CMAKE_CURRENT_BINARY_DIR}/sluiceConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sluice)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/sluiceConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/sluiceConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/sluiceConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sluice)

# The build tree as a package too (sluice_DIR=<build>): the ParaView plugin
# is built against it.
export(EXPORT sluiceTargets NAMESPACE sluice:: FILE ${PROJECT_BINARY_DIR}/sluiceTargets.cmake)
if(TARGET sluice_render)
  export(EXPORT sluice_renderTargets NAMESPACE sluice:: FILE ${PROJECT_BINARY_DIR}/sluice_renderTargets.cmake)
  export(EXPORT sluice_streamTargets NAMESPACE sluice:: FILE ${PROJECT_BINARY_DIR}/sluice_streamTargets.cmake)
endif()
