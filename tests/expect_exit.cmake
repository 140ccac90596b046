# Runs CMD (a ;-list) and fails unless it exits with EXPECT and its stderr contains STDERR_HAS.
execute_process(COMMAND ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "${EXPECT}")
  message(FATAL_ERROR "'${CMD}' exited ${rc}, expected ${EXPECT}\nstdout: ${out}\nstderr: ${err}")
endif()
if(DEFINED STDERR_HAS AND NOT err MATCHES "${STDERR_HAS}")
  message(FATAL_ERROR "stderr of '${CMD}' lacks '${STDERR_HAS}': ${err}")
endif()
