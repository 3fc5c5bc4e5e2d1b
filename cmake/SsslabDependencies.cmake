# Dependencies come from Debian 12 packages (scripts/setup.sh installs them).
find_package(Threads REQUIRED)
find_package(TBB CONFIG REQUIRED)             # libtbb-dev: parallel batches
find_package(fmt CONFIG REQUIRED)             # libfmt-dev: formatting
find_package(CLI11 CONFIG REQUIRED)           # libcli11-dev: command line
find_package(tomlplusplus CONFIG REQUIRED)    # libtomlplusplus-dev: TOML with source positions
find_package(PkgConfig REQUIRED)
find_package(ZLIB REQUIRED)                  # zlib1g-dev: PNG images, gzipped test data
# libopenexr-dev: layered float images. CONFIG, and before anything appends Debian's OpenVDB cmake
# folder to CMAKE_MODULE_PATH: its FindOpenEXR.cmake would shadow the config package.
find_package(OpenEXR CONFIG REQUIRED)
find_package(embree 3 CONFIG REQUIRED)        # libembree-dev: ray queries against scene meshes
find_package(tinyobjloader CONFIG REQUIRED)  # libtinyobjloader-dev: OBJ meshes of scene files
pkg_check_modules(xxhash REQUIRED IMPORTED_TARGET libxxhash)  # libxxhash-dev: artifact content hashes
find_path(RANDOM123_INCLUDE_DIR Random123/philox.h REQUIRED)  # librandom123-dev: Philox streams
add_library(ssslab_random123 INTERFACE)
target_include_directories(ssslab_random123 SYSTEM INTERFACE ${RANDOM123_INCLUDE_DIR})
if(SSSLAB_BUILD_TESTS)
  find_package(GTest CONFIG REQUIRED)         # libgtest-dev, libgmock-dev
endif()
if(SSSLAB_BUILD_BENCHMARKS)
  find_package(benchmark CONFIG QUIET)        # libbenchmark-dev
  if(NOT benchmark_FOUND)
    message(STATUS "Google Benchmark not found: micro-benchmarks disabled (apt-get install libbenchmark-dev)")
  endif()
endif()

# Optional parts. They are detected here so that `ssslab --version` reports what this build can
# do; the modules that use them say so when a scene or experiment needs a missing part.
set(SSSLAB_HAVE_OPENVDB OFF)
if(SSSLAB_WITH_OPENVDB)
  # Debian ships only a find module, in a folder whose FindTBB/FindOpenEXR would shadow the
  # config packages found above (debian-notes.md): append it last, and only here.
  find_path(SSSLAB_OPENVDB_MODULE_DIR FindOpenVDB.cmake
            PATHS /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/lib/cmake/OpenVDB NO_DEFAULT_PATH)
  find_package(Boost QUIET COMPONENTS iostreams)
  if(SSSLAB_OPENVDB_MODULE_DIR AND Boost_FOUND)
    list(APPEND CMAKE_MODULE_PATH ${SSSLAB_OPENVDB_MODULE_DIR})
    find_package(OpenVDB QUIET COMPONENTS openvdb)
  endif()
  if(TARGET OpenVDB::openvdb)
    set(SSSLAB_HAVE_OPENVDB ON)
  else()
    message(STATUS "OpenVDB not found: heterogeneous media disabled (apt-get install libopenvdb-dev libboost-iostreams-dev)")
  endif()
endif()
set(SSSLAB_HAVE_GL OFF)
set(SSSLAB_HAVE_OSMESA OFF)
set(SSSLAB_HAVE_EGL OFF)
set(SSSLAB_GL_PLATFORMS "")
if(SSSLAB_WITH_GL)
  # The GL twin (realtime/gl) needs a headless platform (OSMesa, EGL or both) and glad2's
  # generator (Debian's python3-glad), which writes the loader at build time, offline
  # (--reproducible). Never libGL: linked before libOSMesa, glvnd's libGL answers every call with
  # nothing (../shared/debian-notes.md); glad loads every function through the platform.
  find_path(SSSLAB_OSMESA_INCLUDE GL/osmesa.h)
  find_library(SSSLAB_OSMESA_LIBRARY OSMesa)
  find_path(SSSLAB_EGL_INCLUDE EGL/egl.h)
  find_library(SSSLAB_EGL_LIBRARY EGL)
  find_program(SSSLAB_GLAD glad)
  if(SSSLAB_OSMESA_INCLUDE AND SSSLAB_OSMESA_LIBRARY)
    set(SSSLAB_HAVE_OSMESA ON)
    list(APPEND SSSLAB_GL_PLATFORMS osmesa)
  endif()
  if(SSSLAB_EGL_INCLUDE AND SSSLAB_EGL_LIBRARY)
    set(SSSLAB_HAVE_EGL ON)
    list(APPEND SSSLAB_GL_PLATFORMS egl)
  endif()
  if(SSSLAB_GL_PLATFORMS AND SSSLAB_GLAD)
    set(SSSLAB_HAVE_GL ON)
  elseif(NOT SSSLAB_GLAD)
    message(STATUS "glad not found: OpenGL renderer disabled (apt-get install python3-glad)")
  else()
    message(STATUS "OSMesa/EGL not found: OpenGL renderer disabled (apt-get install libosmesa6-dev libegl-dev)")
  endif()
endif()
string(REPLACE ";" " " SSSLAB_GL_PLATFORMS_STRING "${SSSLAB_GL_PLATFORMS}")
set(SSSLAB_HAVE_MPI OFF)
if(SSSLAB_WITH_MPI)
  find_package(MPI QUIET COMPONENTS CXX)
  if(MPI_CXX_FOUND)
    set(SSSLAB_HAVE_MPI ON)
  else()
    message(STATUS "MPI not found: multi-process runs disabled (apt-get install libopenmpi-dev)")
  endif()
endif()
