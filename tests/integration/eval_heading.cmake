# `skyloc eval` reports the heading error of the correctly matched frames against the
# datasets' poses: a forest run taught level, repeated at dawn with the camera turned by
# 30 degrees. The truth is the simulator's yaw difference (30 degrees), not the strip code;
# measured at 160x120 over 60 frames: median 0.2, p90 0.6 degrees (both ways).
#   -DCMD=skyloc -DWORK=dir -DEMULATOR=...
include(${CMAKE_CURRENT_LIST_DIR}/metrics_json.cmake)
file(REMOVE_RECURSE ${WORK})
foreach(run "ref;--run;1" "query;--run;2;--yaw;30;--lighting;dawn")
  list(GET run 0 name)
  list(SUBLIST run 1 -1 extra)
  execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world forest --out ${WORK}/${name}
                  --spacing 1 --frames 60 --width 160 --height 120 ${extra}
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "skyloc simulate ${name} failed (${rc}): ${err}")
  endif()
endforeach()
if(EMULATOR)
  set(jobs --jobs 1)
endif()
execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${WORK}/ref --query ${WORK}/query
                --method sky --ds 5 --bands 64 --out ${WORK}/out ${jobs}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "skyloc eval failed (${rc}):\n${out}\n${err}")
endif()
read_metrics(${WORK}/out/metrics.json json)
foreach(way correlation surf)
  string(JSON estimated GET "${json}" runs 0 heading ${way} estimated)
  string(JSON median GET "${json}" runs 0 heading ${way} median_deg)
  string(JSON p90 GET "${json}" runs 0 heading ${way} p90_deg)
  if(estimated LESS 40 OR median GREATER 2 OR p90 GREATER 5)
    message(FATAL_ERROR "heading (${way}) over ${estimated} frames: median ${median}, p90 "
                        "${p90} degrees; expected >= 40 frames, <= 2 and <= 5\n${out}")
  endif()
endforeach()
if(NOT out MATCHES "heading sky filter ds 5, [0-9]+ correctly matched frames")
  message(FATAL_ERROR "eval printed no heading line:\n${out}")
endif()
file(REMOVE_RECURSE ${WORK})
