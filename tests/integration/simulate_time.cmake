# `skyloc simulate --fps 10` samples in time: frames.csv timestamps step by 0.1 s, and the
# robot starts standing (--start-stop 1.5): the first 1.5 s x 10 fps frames (+1: the frame
# at t = 1.5 s is still standing) have one identical pose, the next one has moved.
set(dir ${WORK_DIR}/simulate_time)
file(REMOVE_RECURSE ${dir})
execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world city --fps 10 --speed 1.5
                        --start-stop 1.5 --stops 1 --stop-seconds 2,3 --frames 30 --width 32
                        --height 24 --out ${dir}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "simulate failed (${rc}):\n${out}\n${err}")
endif()
file(STRINGS ${dir}/frames.csv rows)
list(LENGTH rows n)
if(NOT n EQUAL 31)
  message(FATAL_ERROR "frames.csv has ${n} lines, expected a header and 30 rows")
endif()
list(REMOVE_AT rows 0)
set(index 0)
set(standing 0)
set(moved FALSE)
foreach(row IN LISTS rows)
  string(REPLACE "," ";" fields "${row}")
  list(GET fields 2 timestamp)
  # Timestamps are index / 10, written with enough digits to compare as text.
  math(EXPR tenths "${index}")
  math(EXPR whole "${tenths} / 10")
  math(EXPR frac "${tenths} % 10")
  if(NOT timestamp MATCHES "^${whole}\\.${frac}0*$")
    message(FATAL_ERROR "frame ${index}: timestamp ${timestamp}, expected ${whole}.${frac}")
  endif()
  list(SUBLIST fields 3 6 pose)
  if(index EQUAL 0)
    set(first_pose "${pose}")
  elseif(NOT moved AND pose STREQUAL first_pose)
    math(EXPR standing "${standing} + 1")
  else()
    set(moved TRUE)
  endif()
  math(EXPR index "${index} + 1")
endforeach()
# Frames 1..15 repeat frame 0 (t = 0.1 .. 1.5 s): 15 more frames; 16 would still be standing.
if(NOT standing EQUAL 15 OR NOT moved)
  message(FATAL_ERROR "${standing} frames repeat the first pose (moved: ${moved}); expected 15 "
                      "then motion")
endif()
file(READ ${dir}/simulation.toml toml)
foreach(key "sampling = \"time\"" "fps = 10.0" "cruise_mps = 1.5" "start_stop_s = 1.5"
            "stop_seconds = \\[2.0+, 3.0+\\]")
  if(NOT toml MATCHES "${key}")
    message(FATAL_ERROR "simulation.toml lacks ${key}:\n${toml}")
  endif()
endforeach()
file(REMOVE_RECURSE ${dir})
