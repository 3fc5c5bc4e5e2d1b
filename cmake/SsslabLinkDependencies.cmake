# The packages that ssslab's libraries link, from Debian 12 (scripts/setup.sh installs them).
# Read by the build (SsslabDependencies.cmake) and by the installed ssslabConfig.cmake, whose
# static libraries need the same packages at the consumer's link.
find_package(Threads REQUIRED)
find_package(TBB CONFIG REQUIRED)             # libtbb-dev: parallel batches
find_package(fmt CONFIG REQUIRED)             # libfmt-dev: formatting
find_package(CLI11 CONFIG REQUIRED)           # libcli11-dev: command line
find_package(tomlplusplus CONFIG REQUIRED)    # libtomlplusplus-dev: TOML with source positions
find_package(PkgConfig REQUIRED)
# libopenexr-dev: layered float images. CONFIG, and before anything appends Debian's OpenVDB cmake
# folder to CMAKE_MODULE_PATH: its FindOpenEXR.cmake would shadow the config package.
find_package(OpenEXR CONFIG REQUIRED)
# libopenimageio-dev: PNG previews and `ssslab compare` on any format. Debian's exported target
# lists /usr/include/opencv4, which the package does not install, and CMake would fail at generate
# time (debian-notes.md): the entry is dropped here, once.
find_package(OpenImageIO CONFIG REQUIRED)
foreach(_ssslab_oiio OpenImageIO::OpenImageIO OpenImageIO::OpenImageIO_Util)
  if(TARGET ${_ssslab_oiio})
    get_target_property(_ssslab_dirs ${_ssslab_oiio} INTERFACE_INCLUDE_DIRECTORIES)
    if(_ssslab_dirs)
      list(FILTER _ssslab_dirs EXCLUDE REGEX "opencv4")
      set_target_properties(${_ssslab_oiio} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_ssslab_dirs}")
    endif()
  endif()
endforeach()
find_package(embree 3 CONFIG REQUIRED)        # libembree-dev: ray queries against scene meshes
find_package(tinyobjloader CONFIG REQUIRED)  # libtinyobjloader-dev: OBJ meshes of scene files
pkg_check_modules(xxhash REQUIRED IMPORTED_TARGET libxxhash)  # libxxhash-dev: artifact content hashes
find_package(Eigen3 3.3 CONFIG REQUIRED)   # libeigen3-dev: linear algebra
find_package(spectra CONFIG REQUIRED)      # libspectra-dev: leading eigenpairs (Lanczos)
pkg_check_modules(fftw3 REQUIRED IMPORTED_TARGET fftw3)  # libfftw3-dev: exact 2D convolutions
pkg_check_modules(muparser REQUIRED IMPORTED_TARGET muparser)  # libmuparser-dev: profile models written as expressions

# OpenVDB (optional): Debian ships only a find module, in a folder whose FindTBB/FindOpenEXR would
# shadow the config packages found above (debian-notes.md): appended last, and only here.
# Defines OpenVDB::openvdb when found. The module sets BUILD_SHARED_LIBS ON in its caller's scope:
# the caller's value is put back.
macro(ssslab_find_openvdb)
  set(_ssslab_shared_libs "${BUILD_SHARED_LIBS}")
  find_path(SSSLAB_OPENVDB_MODULE_DIR FindOpenVDB.cmake
            PATHS /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/lib/cmake/OpenVDB NO_DEFAULT_PATH)
  find_package(Boost QUIET COMPONENTS iostreams)
  if(SSSLAB_OPENVDB_MODULE_DIR AND Boost_FOUND)
    list(APPEND CMAKE_MODULE_PATH ${SSSLAB_OPENVDB_MODULE_DIR})
    find_package(OpenVDB QUIET COMPONENTS openvdb)
  endif()
  set(BUILD_SHARED_LIBS "${_ssslab_shared_libs}")
endmacro()
