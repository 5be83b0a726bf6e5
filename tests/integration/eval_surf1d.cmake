# `skyloc eval --method surf1d`: the 1D SURF recognition score as a place
# recogniser beside sky and vanilla, single-image and with OpenSeqSLAM over its scores.
#  1. A route against itself: every frame's strip matches its own copy exactly (distance
#     0, the largest score there is), so "single" must pick the query's own frame, every
#     frame: the truth is the identity, not the matcher.
#     The landmark confirmation replay keeps every LOCALISED frame there.
#  2. The forest route against a dawn repeat turned by 30 degrees (the strip features do
#     not depend on the heading): both surf1d runs appear in metrics.json and pr.svg next
#     to sky and vanilla, with most matches correct (measured at 160x120 over 40 frames:
#     40 of 40 single, 36 of 36 with OpenSeqSLAM ds 5).
#   -DCMD=skyloc -DWORK=dir -DEMULATOR=...
include(${CMAKE_CURRENT_LIST_DIR}/metrics_json.cmake)
cmake_policy(SET CMP0057 NEW)  # if(... IN_LIST ...)
file(REMOVE_RECURSE ${WORK})
foreach(run "ref;--run;1" "query;--run;2;--yaw;30;--lighting;dawn")
  list(GET run 0 name)
  list(SUBLIST run 1 -1 extra)
  execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world forest --out ${WORK}/${name}
                  --spacing 1 --frames 40 --width 160 --height 120 ${extra}
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "skyloc simulate ${name} failed (${rc}): ${err}")
  endif()
endforeach()
if(EMULATOR)
  set(jobs --jobs 1)
endif()

execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${WORK}/ref --query ${WORK}/ref
                --method sky --method surf1d --ds 5 --matcher openseqslam --out ${WORK}/self
                ${jobs}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "skyloc eval (route against itself) failed (${rc}):\n${out}\n${err}")
endif()
file(STRINGS ${WORK}/self/matches.csv rows REGEX "^surf1d,1,.*,single,")
list(LENGTH rows n)
if(NOT n EQUAL 40)
  message(FATAL_ERROR "surf1d single matched ${n} of 40 frames of the route against itself")
endif()
foreach(row ${rows})
  string(REPLACE "," ";" f "${row}")
  list(GET f 2 q)
  list(GET f 3 r)
  if(NOT q EQUAL r)
    message(FATAL_ERROR "surf1d single matched frame ${q} to ${r}, not to itself: ${row}")
  endif()
endforeach()
# Landmark confirmation (docs/RESULTS.md): against itself every sky match is its own frame,
# whose strip scores far above the highest threshold, so no LOCALISED frame is lost.
if(NOT out MATCHES "landmark confirmation sky openseqslam ds 5: LOCALISED correct ([0-9]+) of ([0-9]+) without;[^\n]* score >= 400: ([0-9]+) of ([0-9]+);")
  message(FATAL_ERROR "eval printed no landmark confirmation line:\n${out}")
endif()
if(CMAKE_MATCH_2 LESS 20 OR NOT CMAKE_MATCH_1 EQUAL CMAKE_MATCH_2 OR
   NOT CMAKE_MATCH_3 EQUAL CMAKE_MATCH_1 OR NOT CMAKE_MATCH_4 EQUAL CMAKE_MATCH_2)
  message(FATAL_ERROR "landmark confirmation of a route against itself lost frames:\n${out}")
endif()

execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${WORK}/ref --query ${WORK}/query
                --method sky --method vanilla --method surf1d --ds 5 --matcher openseqslam
                --out ${WORK}/out ${jobs}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "skyloc eval failed (${rc}):\n${out}\n${err}")
endif()
read_metrics(${WORK}/out/metrics.json json)
string(JSON runs LENGTH "${json}" runs)
set(found "")
math(EXPR last "${runs} - 1")
foreach(i RANGE ${last})
  string(JSON method GET "${json}" runs ${i} method)
  string(JSON matcher GET "${json}" runs ${i} matcher)
  string(JSON correct GET "${json}" runs ${i} correct)
  string(JSON evaluated GET "${json}" runs ${i} evaluated)
  list(APPEND found "${method}/${matcher}")
  if(method STREQUAL "surf1d")
    math(EXPR need "${evaluated} * 8 / 10")
    if(evaluated LESS 30 OR correct LESS need)
      message(FATAL_ERROR "surf1d ${matcher}: ${correct} of ${evaluated} correct; expected "
                          ">= 80 % of >= 30\n${out}")
    endif()
  endif()
endforeach()
foreach(want sky/openseqslam vanilla/openseqslam surf1d/single surf1d/openseqslam)
  if(NOT want IN_LIST found)
    message(FATAL_ERROR "metrics.json has no ${want} run: ${found}")
  endif()
endforeach()
file(READ ${WORK}/out/pr.svg svg)
if(NOT svg MATCHES "surf1d single ds=1" OR NOT svg MATCHES "surf1d openseqslam ds=5")
  message(FATAL_ERROR "pr.svg has no surf1d curves")
endif()
file(REMOVE_RECURSE ${WORK})
