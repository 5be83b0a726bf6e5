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
  file(STRINGS ${f} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"(firmware|tools|cli)/")
  foreach(line ${includes})
    string(APPEND errors "\n  ${f}: '${line}' (platform/ and drivers/ may not include app/)")
  endforeach()
endforeach()
# app/: the robot's program (firmware/) includes neither the lab's tools nor the command
# line; the tools include the firmware but never the command line. The firmware-only ARM
# build leaves tools/ out, so a firmware file that includes a tool would not build there.
file(GLOB_RECURSE firmware_files ${SOURCE_DIR}/app/firmware/*.h ${SOURCE_DIR}/app/firmware/*.cpp)
foreach(f ${firmware_files})
  file(STRINGS ${f} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"(tools|cli)/")
  foreach(line ${includes})
    string(APPEND errors "\n  ${f}: '${line}' (the robot's program, app/firmware/, may not include the lab's tools or the command line)")
  endforeach()
endforeach()
file(GLOB_RECURSE tools_files ${SOURCE_DIR}/app/tools/*.h ${SOURCE_DIR}/app/tools/*.cpp)
foreach(f ${tools_files})
  file(STRINGS ${f} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"cli/")
  foreach(line ${includes})
    string(APPEND errors "\n  ${f}: '${line}' (app/tools/ may not include the command line, app/cli/)")
  endforeach()
endforeach()
if(errors)
  message(FATAL_ERROR "layering violations:${errors}")
endif()
message(STATUS "layering: ${SOURCE_DIR} is clean")
