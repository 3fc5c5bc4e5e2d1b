# `cmake --install`: the libraries, the public headers (include/ssslab/<module>/...), the ssslab
# command and a CMake package with imported targets, so a program outside this tree writes
#   find_package(ssslab CONFIG REQUIRED)
#   target_link_libraries(my_study PRIVATE ssslab::runner)
# (examples/custom_model/). ssslabConfig.cmake finds the packages the libraries link
# (cmake/SsslabLinkDependencies.cmake, installed beside it), so that static builds
# (-DBUILD_SHARED_LIBS=OFF) link too.
include(CMakePackageConfigHelpers)

# Installed programs and libraries find ssslab's shared libraries beside them.
set_target_properties(ssslab PROPERTIES INSTALL_RPATH "$ORIGIN/../${CMAKE_INSTALL_LIBDIR}")

set(SSSLAB_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/ssslab)
# Target name -> exported name: ssslab_core is ssslab::core.
set(_ssslab_exported ssslab_core ssslab_mcml ssslab_approx ssslab_volpath ssslab_realtime
    ssslab_runner ssslab_cli ssslab_random123 ssslab_warnings)
if(SSSLAB_HAVE_GL)
  list(APPEND _ssslab_exported ssslab_realtime_gl ssslab_glad)
endif()
foreach(_t ${_ssslab_exported})
  string(REPLACE "ssslab_" "" _name ${_t})
  set_target_properties(${_t} PROPERTIES EXPORT_NAME ${_name} INSTALL_RPATH "$ORIGIN")
endforeach()
install(TARGETS ${_ssslab_exported} EXPORT ssslabTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ssslab)
install(TARGETS ssslab RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Headers keep their module paths ("approx/model_spec.h"), as inside the tree.
foreach(_dir core mcml approx volpath realtime experiments/runner experiments/cli)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${_dir}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ssslab/${_dir}
          FILES_MATCHING PATTERN "*.h" PATTERN "shaders" EXCLUDE)
endforeach()
install(FILES ${CMAKE_BINARY_DIR}/generated/core/build_info.h
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ssslab/core)
if(SSSLAB_HAVE_GL)
  install(DIRECTORY ${CMAKE_BINARY_DIR}/generated/glad/include/
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ssslab)
endif()

install(EXPORT ssslabTargets NAMESPACE ssslab:: DESTINATION ${SSSLAB_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ssslabConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/ssslabConfig.cmake
                              INSTALL_DESTINATION ${SSSLAB_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/ssslabConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/ssslabConfig.cmake ${CMAKE_BINARY_DIR}/ssslabConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/SsslabLinkDependencies.cmake
        DESTINATION ${SSSLAB_INSTALL_CMAKEDIR})
