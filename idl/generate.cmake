# Runs fastddsgen and checks that it wrote every file the build expects. fastddsgen has been seen
# to leave a fresh build without tesseraPubSubTypes.cxx while the build went on (a parallel build
# under heavy load; the next build succeeded), so a missing output is retried once and then named.
# Invoked as: cmake -DFASTDDSGEN=... -DIDL=... -DOUT=... -P generate.cmake
set(expected tessera.h tessera.cxx tesseraPubSubTypes.h tesseraPubSubTypes.cxx)
foreach(attempt 1 2)
  file(MAKE_DIRECTORY ${OUT})
  execute_process(COMMAND ${FASTDDSGEN} -replace -cs -d ${OUT} ${IDL} RESULT_VARIABLE rc)
  set(missing "")
  foreach(f ${expected})
    if(NOT EXISTS ${OUT}/${f})
      list(APPEND missing ${f})
    endif()
  endforeach()
  if(rc EQUAL 0 AND missing STREQUAL "")
    return()
  endif()
  message(WARNING "fastddsgen (attempt ${attempt}) exited ${rc}; missing: ${missing}")
endforeach()
message(FATAL_ERROR "fastddsgen did not generate ${missing} in ${OUT} from ${IDL}")
