# Runs CMD with ARGS (a ;-list) and checks the exit code and that stderr contains EXPECT_STDERR.
execute_process(COMMAND ${EMULATOR} ${CMD} ${ARGS}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL EXPECT_RC)
  message(FATAL_ERROR "expected exit ${EXPECT_RC}, got ${rc}\nstdout: ${out}\nstderr: ${err}")
endif()
if(DEFINED EXPECT_STDERR AND NOT err MATCHES "${EXPECT_STDERR}")
  message(FATAL_ERROR "stderr does not mention '${EXPECT_STDERR}':\n${err}")
endif()
