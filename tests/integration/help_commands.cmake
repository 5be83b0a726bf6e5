# Every command `skyloc --help` lists answers its own --help with exit 0 (a command that
# is listed but left out of this build, or a stub, fails here), and --help itself exits 0.
# With EXPECT_ABSENT (a ;-list), none of those commands may be listed: the firmware-only
# ARM build lists no lab tool.
execute_process(COMMAND ${EMULATOR} ${CMD} --help RESULT_VARIABLE rc OUTPUT_VARIABLE out
  ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "skyloc --help exited ${rc}\n${out}${err}")
endif()
string(REGEX MATCHALL "\n  [a-z0-9-]+ " listed "${out}")
if(NOT listed)
  message(FATAL_ERROR "skyloc --help lists no command:\n${out}")
endif()
set(names "")
foreach(entry ${listed})
  string(STRIP "${entry}" name)
  list(APPEND names ${name})
  execute_process(COMMAND ${EMULATOR} ${CMD} ${name} --help RESULT_VARIABLE rc
    OUTPUT_VARIABLE cmd_out ERROR_VARIABLE cmd_err)
  if(NOT rc EQUAL 0 OR NOT cmd_out MATCHES "usage: skyloc ${name}")
    message(FATAL_ERROR "'skyloc ${name} --help' exited ${rc}; stdout:\n${cmd_out}\nstderr:\n${cmd_err}")
  endif()
  if(cmd_out MATCHES "not in this build" OR cmd_err MATCHES "not in this build")
    message(FATAL_ERROR "'skyloc ${name}' is listed but not in this build")
  endif()
endforeach()
string(REPLACE "|" ";" absent "${EXPECT_ABSENT}")
foreach(name ${absent})
  list(FIND names "${name}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "'${name}' is listed by skyloc --help in a build without it: ${names}")
  endif()
endforeach()
message(STATUS "skyloc --help lists ${names}, each answering --help")
