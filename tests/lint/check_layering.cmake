# dsp/ must build for any target with nothing but the C++ standard library and Eigen:
# an OS, POSIX, Linux or driver header there is a layering error.
set(forbidden_in_dsp
  "unistd\\.h" "fcntl\\.h" "sys/" "linux/" "poll\\.h" "pthread\\.h" "time\\.h" "signal\\.h"
  "dirent\\.h" "libcamera/" "gpiod" "skyloc/drivers/" "skyloc/platform/" "skyloc/app"
  "<fstream>" "<iostream>" "<thread>" "<mutex>" "<filesystem>" "<cstdio>")
file(GLOB_RECURSE dsp_files ${SOURCE_DIR}/dsp/*.h ${SOURCE_DIR}/dsp/*.cpp)
set(errors "")
foreach(f ${dsp_files})
  file(STRINGS ${f} includes REGEX "^[ \t]*#[ \t]*include")
  foreach(line ${includes})
    foreach(pattern ${forbidden_in_dsp})
      if(line MATCHES "${pattern}")
        string(APPEND errors "\n  ${f}: '${line}' (dsp/ may not include ${pattern})")
      endif()
    endforeach()
  endforeach()
endforeach()
file(GLOB_RECURSE lower_files ${SOURCE_DIR}/platform/*.h ${SOURCE_DIR}/platform/*.cpp
     ${SOURCE_DIR}/drivers/*.h ${SOURCE_DIR}/drivers/*.cpp)
foreach(f ${lower_files})
  # skyloc/host_eval/ is app/host_eval's: host-only evaluation, not in the ARM builds.
  file(STRINGS ${f} includes REGEX "^[ \t]*#[ \t]*include.*(app/|commands\\.h|skyloc/host_eval/)")
  foreach(line ${includes})
    string(APPEND errors "\n  ${f}: '${line}' (only app/ may include app/ and skyloc/host_eval/)")
  endforeach()
endforeach()
if(errors)
  message(FATAL_ERROR "layering violations:${errors}")
endif()
message(STATUS "layering: ${SOURCE_DIR} is clean")
