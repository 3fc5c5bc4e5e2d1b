# Warnings live in an INTERFACE target that every ssslab target links (pbrt, OpenVDB).
add_library(ssslab_warnings INTERFACE)
target_compile_options(ssslab_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align -Woverloaded-virtual
  -Wnull-dereference -Wformat=2 -Wimplicit-fallthrough -Wmisleading-indentation
  # GCC 12 reports std::string concatenation at -O3 as an overlapping memcpy (GCC bug 105329).
  $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict>)
if(SSSLAB_STRICT)
  target_compile_options(ssslab_warnings INTERFACE -Werror)
endif()
