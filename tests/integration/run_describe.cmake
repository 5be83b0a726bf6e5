# Runs 'skyloc describe' (CMD with ARGS; ARGS and EMULATOR are |-separated lists), checks its exit code (EXPECT_RC), that
# stdout matches EXPECT_STDOUT and stderr EXPECT_STDERR (regexes, optional), that stdout has
# EXPECT_LINES lines (optional), and optionally hands stdout (saved to OUT) to
# FIXTURE CHECK_MODE OUT CHECK_BOUND (describe_fixture compare/differ).
string(REPLACE "|" ";" ARGS "${ARGS}")
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
execute_process(COMMAND ${EMULATOR} ${CMD} ${ARGS}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL EXPECT_RC)
  message(FATAL_ERROR "expected exit ${EXPECT_RC}, got ${rc}\nstdout: ${out}\nstderr: ${err}")
endif()
if(DEFINED EXPECT_STDOUT AND NOT out MATCHES "${EXPECT_STDOUT}")
  message(FATAL_ERROR "stdout does not match '${EXPECT_STDOUT}':\n${out}")
endif()
if(DEFINED EXPECT_STDERR AND NOT err MATCHES "${EXPECT_STDERR}")
  message(FATAL_ERROR "stderr does not match '${EXPECT_STDERR}':\n${err}")
endif()
if(DEFINED EXPECT_LINES)
  string(REGEX MATCHALL "\n" newlines "${out}")
  list(LENGTH newlines lines)
  if(NOT lines EQUAL EXPECT_LINES)
    message(FATAL_ERROR "expected ${EXPECT_LINES} lines on stdout, got ${lines}:\n${out}")
  endif()
endif()
if(DEFINED CHECK_MODE)
  file(WRITE ${OUT} "${out}")
  execute_process(COMMAND ${EMULATOR} ${FIXTURE} ${CHECK_MODE} ${OUT} ${CHECK_BOUND}
    RESULT_VARIABLE check_rc OUTPUT_VARIABLE check_out ERROR_VARIABLE check_err)
  message(STATUS "${check_out}${check_err}")
  if(NOT check_rc EQUAL 0)
    message(FATAL_ERROR "${CHECK_MODE} failed: ${check_out}${check_err}\n${out}")
  endif()
endif()
