# skyloc eval --attitude dataset: the gravity-aligned cap on the roll and pitch recorded with
# each frame. A level city run against a dawn run pitched 25 degrees nose up (the tilt
# experiment's setting, small): with the cap (the largest tilt 25 degrees) single images
# must match better than the hemisphere without it, which the tilt crops (measured at
# 96x72: ds 1 P@R100 0.92 without, 1.00 with). And a dataset without roll/pitch columns is
# refused by name.
set(dir ${WORK_DIR}/eval_attitude)
file(REMOVE_RECURSE ${dir})
foreach(spec "ref;1;noon;0" "query;2;dawn;25")
  list(GET spec 0 name)
  list(GET spec 1 run)
  list(GET spec 2 light)
  list(GET spec 3 tilt)
  execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world city --spacing 1 --frames 120
                          --width 96 --height 72 --run ${run} --lighting ${light} --tilt ${tilt}
                          --out ${dir}/${name}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "simulate ${name} failed (${rc}):\n${out}\n${err}")
  endif()
endforeach()

# The ds 1 row's P@100%recall of a run.
function(precision_at_full_recall attitude out_var)
  execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${dir}/ref --query ${dir}/query
                          --out ${dir}/out_${attitude} --method sky --ds 1 --max-advance 8
                          --attitude ${attitude} ${ARGN}
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "eval --attitude ${attitude} failed (${rc}):\n${out}\n${err}")
  endif()
  if(NOT out MATCHES "sky +filter +1 +120 +[0-9]+ +([0-9.]+)")
    message(FATAL_ERROR "eval --attitude ${attitude}: no ds 1 row in:\n${out}")
  endif()
  set(${out_var} ${CMAKE_MATCH_1} PARENT_SCOPE)
endfunction()
precision_at_full_recall(none without)
precision_at_full_recall(dataset with --max-tilt 25)
message(STATUS "ds 1 P@R100: hemisphere ${without}, gravity-aligned cap ${with}")
if(NOT with GREATER_EQUAL 0.98 OR NOT with GREATER without)
  message(FATAL_ERROR "the cap should match the tilted run better: ${with} vs ${without}")
endif()

# Strip the pose columns: no attitude left to level the cap with (the truth from a CSV).
file(STRINGS ${dir}/query/frames.csv rows)
set(stripped "")
foreach(row IN LISTS rows)
  string(REGEX REPLACE "^([^,]*,[^,]*,[^,]*),.*$" "\\1" row "${row}")
  string(APPEND stripped "${row}\n")
endforeach()
file(WRITE ${dir}/query/frames.csv "${stripped}")
set(truth "query_index,reference_index\n")
foreach(i RANGE 119)
  string(APPEND truth "${i},${i}\n")
endforeach()
file(WRITE ${dir}/truth.csv "${truth}")
execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${dir}/ref --query ${dir}/query
                        --out ${dir}/out_missing --method sky --ds 1 --attitude dataset
                        --gt ${dir}/truth.csv
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 1 OR NOT err MATCHES "000000.png has no roll and pitch recorded")
  message(FATAL_ERROR "a query without attitude: expected exit 1 naming the frame, got ${rc}:\n${err}")
endif()
file(REMOVE_RECURSE ${dir})
message(STATUS "all checks passed")
