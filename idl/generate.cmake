# Runs fastddsgen and checks that it wrote every file the build expects, naming what is missing.
# Invoked as: cmake -DFASTDDSGEN=... -DIDL=... -DOUT=... -DTMP=... -P generate.cmake
#
# TMP must be private to this build tree. fastddsgen 2.3.0 preprocesses the IDL with
# `cpp IDL <temp dir>/<name>.idl.cc` and then parses that file; its temp dir defaults to /tmp/,
# so every build tree of the host (other checkouts, worktrees, CI jobs) shares
# /tmp/tessera.idl.cc. A generation running at the same time truncates and rewrites it under
# this one's parser, which then sees no struct: it writes tessera.h/.cxx without any type and
# no tesseraPubSubTypes.* at all, mostly exiting 0 (or parses the other tree's IDL). Measured
# while another process re-preprocessed an IDL of the same name in a loop: 5 of 5 runs with
# the default temp dir lost the PubSubTypes files (3 of them exiting 0), 5 of 5 with a private
# one (-t) were complete.
set(expected tessera.h tessera.cxx tesseraPubSubTypes.h tesseraPubSubTypes.cxx)
file(MAKE_DIRECTORY ${OUT} ${TMP})
execute_process(COMMAND ${FASTDDSGEN} -replace -cs -t ${TMP} -d ${OUT} ${IDL} RESULT_VARIABLE rc)
set(missing "")
foreach(f ${expected})
  if(NOT EXISTS ${OUT}/${f})
    list(APPEND missing ${f})
  endif()
endforeach()
if(NOT rc EQUAL 0 OR NOT missing STREQUAL "")
  message(FATAL_ERROR "fastddsgen exited ${rc} and did not generate '${missing}' in ${OUT} from ${IDL}")
endif()
