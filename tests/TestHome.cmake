# The build tree's stand-in for $HOME during a test run (FacetAddTest.cmake).
#   MODE=setup: make HOME and TMP empty directories and CACHE a directory.
#   MODE=check: fail, listing what is there, if anything was written to HOME.
if(MODE STREQUAL "setup")
  file(REMOVE_RECURSE ${HOME} ${TMP})
  file(MAKE_DIRECTORY ${HOME} ${TMP} ${CACHE})
elseif(MODE STREQUAL "check")
  file(GLOB_RECURSE written LIST_DIRECTORIES true RELATIVE ${HOME} ${HOME}/* ${HOME}/.*)
  if(written)
    list(JOIN written "\n  " listing)
    message(FATAL_ERROR "tests wrote to HOME (${HOME}); a test may write only inside the build tree:\n  ${listing}")
  endif()
  message(STATUS "HOME (${HOME}) is still empty")
else()
  message(FATAL_ERROR "TestHome.cmake: MODE must be setup or check")
endif()
