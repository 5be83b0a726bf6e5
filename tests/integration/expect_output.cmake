# Runs COMMAND (a '|'-separated list: a ';' would split add_test's argument) and requires
# both its exit code (EXPECT_RC, default 0) and that its output (stdout and stderr) matches
# EXPECT_OUTPUT. CTest's PASS_REGULAR_EXPRESSION alone ignores the exit code: a program
# that printed the right line and then crashed at exit would pass.
string(REPLACE "|" ";" command "${COMMAND}")
if(NOT DEFINED EXPECT_RC)
  set(EXPECT_RC 0)
endif()
execute_process(COMMAND ${command} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc STREQUAL "${EXPECT_RC}")
  message(FATAL_ERROR "expected exit ${EXPECT_RC}, got ${rc}")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "the output does not match '${EXPECT_OUTPUT}'")
endif()
