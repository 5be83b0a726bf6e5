# A small `skyloc experiment heading` writes its table and metrics, and its strip
# cross-correlation is right on most correctly matched frames at 160x120: measured median
# 1.6 degrees on x86-64 and armhf, 90th percentile 5.9 (x86-64) and 16.6 (armhf, whose
# renderer rounds differently: SIMULATOR.md on determinism) over ~150 frames, so the bound
# on the tail is loose here (the experiments are host_eval code now, so the test runs in
# native builds only; the bound stays what both targets passed); the heading goal's bar (median < 3, p90 < 10) is checked on the
# full-size run in docs/RESULTS.md. The truth is the simulator's poses, not the strip code.
include(${CMAKE_CURRENT_LIST_DIR}/metrics_json.cmake)
set(dir ${WORK_DIR}/experiment_heading)
file(REMOVE_RECURSE ${dir})
execute_process(COMMAND ${EMULATOR} ${CMD} experiment heading --frames 150 --width 160
                        --height 120 --bands 16 --out ${dir}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "experiment heading failed (${rc}):\n${out}\n${err}")
endif()
foreach(f results.md metrics.json frames.csv)
  if(NOT EXISTS ${dir}/${f})
    message(FATAL_ERROR "missing ${dir}/${f}")
  endif()
endforeach()
read_metrics(${dir}/metrics.json json)
string(JSON n LENGTH "${json}" rows)
if(NOT n EQUAL 2)
  message(FATAL_ERROR "metrics.json has ${n} rows, expected 2 (forest, repetitive)")
endif()
string(JSON frames GET "${json}" all correlation estimated)
string(JSON median GET "${json}" all correlation median_deg)
string(JSON p90 GET "${json}" all correlation p90_deg)
if(frames LESS 100 OR median GREATER_EQUAL 3 OR p90 GREATER_EQUAL 30)
  message(FATAL_ERROR "heading (cross-correlation) over ${frames} frames: median ${median}, "
                      "p90 ${p90} degrees; expected >= 100 frames, < 3 and < 30")
endif()
# Where the correlation is wrong (off by more than 10 degrees) the firmware must still ask
# 1D SURF: none of those frames may be called certain (this run has 8 of them).
string(JSON wrong GET "${json}" all wrong_frames)
string(JSON wrong_certain GET "${json}" all wrong_certain_frames)
string(JSON uncertain GET "${json}" all uncertain_frames)
if(wrong LESS 1 OR NOT wrong_certain EQUAL 0 OR uncertain LESS wrong)
  message(FATAL_ERROR "of ${wrong} frames whose correlation heading is wrong, "
                      "${wrong_certain} were called certain (expected some wrong, none certain; "
                      "${uncertain} uncertain in all)")
endif()
# frames.csv: one line per correctly matched frame (every frame the summaries count), with
# the header naming its columns (the truth beside the estimates), and a SURF heading on as many lines as the summary says.
file(STRINGS ${dir}/frames.csv lines)
list(LENGTH lines line_count)
list(GET lines 0 header)
string(JSON matched_frames GET "${json}" all correlation frames)
string(JSON surf_frames GET "${json}" all surf estimated)
set(with_surf 0)
foreach(line IN LISTS lines)
  if(line MATCHES "^[a-z]+,[0-9]+,[0-9]+,[-0-9.e]+,[01],[-0-9.e]+,[-0-9.e]+,[0-9]+$")
    math(EXPR with_surf "${with_surf} + 1")
  endif()
endforeach()
math(EXPR rows_in_file "${line_count} - 1")
if(NOT header STREQUAL "world,query_frame,route_frame,truth_deg,uncertain,correlation_deg,surf_deg,surf_inliers"
   OR NOT rows_in_file EQUAL matched_frames OR NOT with_surf EQUAL surf_frames)
  message(FATAL_ERROR "frames.csv: header '${header}', ${rows_in_file} frames (${with_surf} "
                      "with a SURF heading); expected ${matched_frames} (${surf_frames})")
endif()
file(REMOVE_RECURSE ${dir})
