# The git revision is regenerated at every build (not only at configure time), so the provenance
# written beside every output names the code that produced it.
set(SSSLAB_REVISION_FILE ${CMAKE_BINARY_DIR}/generated/git_revision.cpp)
add_custom_target(ssslab_git_revision
  COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${CMAKE_SOURCE_DIR} -DOUT=${SSSLAB_REVISION_FILE}
          -P ${CMAKE_SOURCE_DIR}/cmake/WriteGitRevision.cmake
  BYPRODUCTS ${SSSLAB_REVISION_FILE}
  COMMENT "" VERBATIM)
