# A small `skyloc experiment surf1d` (24 images a place, 15 degrees apart, at 320x240
# instead of 88 at 640x480) writes its table, metrics and ROC plot; the pair counts are
# the protocol's (only neighbours are under 20 degrees apart), and the scores separate
# matching pairs from the rest better than chance on both cameras (AUC > 0.6; the
# full-size run is in docs/RESULTS.md).
include(${CMAKE_CURRENT_LIST_DIR}/metrics_json.cmake)
set(dir ${WORK_DIR}/experiment_surf1d)
file(REMOVE_RECURSE ${dir})
execute_process(COMMAND ${EMULATOR} ${CMD} experiment surf1d --images 24 --width 320 --height 240
                        --fisheye-width 240 --fisheye-height 240 --out ${dir}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "experiment surf1d failed (${rc}):\n${out}\n${err}")
endif()
foreach(f results.md metrics.json roc.svg)
  if(NOT EXISTS ${dir}/${f})
    message(FATAL_ERROR "missing ${dir}/${f}")
  endif()
endforeach()
read_metrics(${dir}/metrics.json json)
# Forward: 2 places x 24 matched pairs (each image and the next, round the circle) and
# 2 x (276 - 24) unmatched. Fisheye: 2 x 276 same-place pairs, 24 x 24 across places.
foreach(check "forward;matched_pairs;48" "forward;unmatched_pairs;504"
              "fisheye;matched_pairs;552" "fisheye;unmatched_pairs;576")
  list(GET check 0 camera)
  list(GET check 1 key)
  list(GET check 2 expected)
  string(JSON v GET "${json}" ${camera} ${key})
  if(NOT v EQUAL expected)
    message(FATAL_ERROR "${camera} ${key} = ${v}, expected ${expected}")
  endif()
endforeach()
foreach(camera forward fisheye)
  foreach(key auc_nn auc_ransac)
    string(JSON v GET "${json}" ${camera} ${key})
    if(v LESS_EQUAL 0.6 OR v GREATER 1.0)
      message(FATAL_ERROR "${camera} ${key} = ${v}: expected within (0.6, 1]\n${out}")
    endif()
  endforeach()
endforeach()
file(REMOVE_RECURSE ${dir})
