# skyloc surf1d on two rendered frames of one place, the second with the camera turned by
# --yaw 40 (the simulator's heading offset, counter-clockwise): both heading methods must
# say the robot turned +40 degrees (within 2), and --plot writes an SVG with the matches.
set(dir ${WORK_DIR}/surf1d_command)
file(REMOVE_RECURSE ${dir})
foreach(yaw 0 40)
  execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world forest --spacing 1 --frames 1
                          --start 20 --width 160 --height 120 --yaw ${yaw} --out ${dir}/yaw${yaw}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "simulate --yaw ${yaw} failed (${rc}):\n${out}\n${err}")
  endif()
endforeach()
execute_process(COMMAND ${EMULATOR} ${CMD} surf1d ${dir}/yaw0/frames/000000.png
                        ${dir}/yaw40/frames/000000.png --plot ${dir}/matches.svg
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "surf1d failed (${rc}):\n${out}\n${err}")
endif()
foreach(method "1D SURF inliers" "strip correlation")
  if(NOT out MATCHES "heading \\(${method}\\)[^\n]*the robot ([-+][0-9.]+) deg")
    message(FATAL_ERROR "no heading by ${method} in:\n${out}")
  endif()
  set(robot ${CMAKE_MATCH_1})
  if(robot LESS 38 OR robot GREATER 42)
    message(FATAL_ERROR "${method}: the robot turned ${robot} deg, expected 40 +- 2:\n${out}")
  endif()
endforeach()
file(READ ${dir}/matches.svg svg)
if(NOT svg MATCHES "<svg" OR NOT svg MATCHES "stroke=\"#2ca02c\"")
  message(FATAL_ERROR "the plot has no inlier match lines")
endif()
execute_process(COMMAND ${EMULATOR} ${CMD} surf1d ${dir}/yaw0/frames/000000.png ${dir}/missing.png
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "missing.png")
  message(FATAL_ERROR "a missing image: expected exit 1 naming it, got ${rc}:\n${err}")
endif()
execute_process(COMMAND ${EMULATOR} ${CMD} surf1d ${dir}/yaw0/frames/000000.png
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "give two images")
  message(FATAL_ERROR "one image: expected exit 2, got ${rc}:\n${err}")
endif()
file(REMOVE_RECURSE ${dir})
message(STATUS "all checks passed")
