# `skyloc fabmap-train` + `skyloc eval --method fabmap` end to end on small simulated
# visible-light runs: the vocabulary from a forest run, evaluated on two city runs.
#   -DCMD=skyloc -DWORK=dir -DPART=train|eval|experiment|clean
# train makes WORK/v.fabmap (and a foreign file), eval and experiment use them (CTest runs
# the two side by side: FIXTURES_SETUP/REQUIRED in tests/integration/tools.cmake), clean
# removes WORK.
include(${CMAKE_CURRENT_LIST_DIR}/metrics_json.cmake)
function(run)
  execute_process(COMMAND ${CMD} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "skyloc ${ARGN} failed (${rc}):\n${out}\n${err}")
  endif()
  set(last_out "${out}" PARENT_SCOPE)
endfunction()
if(PART STREQUAL "train")
  file(REMOVE_RECURSE ${WORK})
  run(simulate --world forest --seed 2 --mode visible --frames 60 --out ${WORK}/train)
  run(fabmap-train --train ${WORK}/train --out ${WORK}/v.fabmap --words 150 --max-features 300)
  file(REMOVE_RECURSE ${WORK}/train)
  file(WRITE ${WORK}/foreign.fabmap "not a vocabulary at all\n")
  message(STATUS "fabmap ${PART}: passed")
  return()
elseif(PART STREQUAL "clean")
  file(REMOVE_RECURSE ${WORK})
  message(STATUS "fabmap ${PART}: passed")
  return()
elseif(NOT EXISTS ${WORK}/v.fabmap)
  message(FATAL_ERROR "no vocabulary at ${WORK}/v.fabmap: PART=train makes it")
endif()
if(PART STREQUAL "eval")
  run(simulate --world city --run 1 --mode visible --frames 60 --out ${WORK}/ref)
  run(simulate --world city --run 2 --mode visible --frames 60 --out ${WORK}/query)
  run(eval --reference ${WORK}/ref --query ${WORK}/query --vocab ${WORK}/v.fabmap
      --method fabmap --out ${WORK}/out)
  message(STATUS "${last_out}")
  read_metrics(${WORK}/out/metrics.json json)
  string(JSON method GET "${json}" runs 0 method)
  string(JSON matcher GET "${json}" runs 0 matcher)
  string(JSON correct GET "${json}" runs 0 correct)
  string(JSON evaluated GET "${json}" runs 0 evaluated)
  if(NOT method STREQUAL "fabmap" OR NOT matcher STREQUAL "fabmap2" OR NOT evaluated EQUAL 60)
    message(FATAL_ERROR "metrics.json: run 0 is ${method}/${matcher} with ${evaluated} matches")
  endif()
  # Measured 2026-11-25: 43 of 60 correct within +-5 frames; a random match is right for
  # about 11 of 60 (+-5 of 60 reference frames).
  if(correct LESS 30)
    message(FATAL_ERROR "fabmap matched only ${correct} of 60 query frames correctly")
  endif()
  foreach(f matches.csv pr.svg correspondence.svg)
    if(NOT EXISTS ${WORK}/out/${f})
      message(FATAL_ERROR "skyloc eval did not write ${f}")
    endif()
  endforeach()
  # A file that is not a vocabulary: one error naming the file, exit 1 (the unit tests
  # damage real vocabularies byte by byte: tests/tools/fabmap_vocabulary_test.cpp).
  execute_process(COMMAND ${CMD} eval --reference ${WORK}/ref --query ${WORK}/query
                  --vocab ${WORK}/foreign.fabmap --method fabmap --out ${WORK}/out2
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "foreign.fabmap is not a skyloc FAB-MAP vocabulary")
    message(FATAL_ERROR "a foreign vocabulary: exit ${rc}, stderr:\n${err}")
  endif()
  file(REMOVE_RECURSE ${WORK}/ref ${WORK}/query ${WORK}/out ${WORK}/out2)
elseif(PART STREQUAL "experiment")
  # `skyloc experiment tilt --vocab`: the FAB-MAP column beside sky and vanilla, on the same
  # runs and PR metrics (a tiny tilt: 20 frames a run; the vocabulary is the forest's, the
  # experiment's world is the city). Every row has a fabmap summary with finite numbers
  # (a NaN would print as nan and fail to parse) and one match per query frame.
  run(experiment tilt --frames 20 --width 160 --height 120 --bands 8 --spacing 4
      --vocab ${WORK}/v.fabmap --out ${WORK}/tilt)
  file(READ ${WORK}/tilt/results.md md)
  if(NOT md MATCHES "fabmap P@R100 \\|" OR NOT md MATCHES "fabmap R@P100 \\|")
    message(FATAL_ERROR "experiment tilt --vocab: no fabmap columns in results.md:\n${md}")
  endif()
  if(NOT EXISTS ${WORK}/tilt/pr_fabmap.svg)
    message(FATAL_ERROR "experiment tilt --vocab did not write pr_fabmap.svg")
  endif()
  read_metrics(${WORK}/tilt/metrics.json json)
  string(JSON rows LENGTH "${json}" rows)
  math(EXPR last "${rows} - 1")
  foreach(i RANGE ${last})
    string(JSON evaluated GET "${json}" rows ${i} fabmap evaluated)
    string(JSON p GET "${json}" rows ${i} fabmap precision_at_100_recall)
    string(JSON r GET "${json}" rows ${i} fabmap recall_at_100_precision)
    if(NOT evaluated EQUAL 20 OR p LESS 0 OR p GREATER 1 OR r LESS 0 OR r GREATER 1)
      message(FATAL_ERROR "tilt row ${i}: fabmap evaluated ${evaluated}, P@R100 ${p}, R@P100 ${r}")
    endif()
  endforeach()
  # The experiment refuses a foreign vocabulary the same way, and --vocab where it has no use.
  execute_process(COMMAND ${CMD} experiment tilt --frames 20 --vocab ${WORK}/foreign.fabmap
                  --out ${WORK}/tilt2 RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 1 OR NOT err MATCHES "foreign.fabmap is not a skyloc FAB-MAP vocabulary")
    message(FATAL_ERROR "experiment with a foreign vocabulary: exit ${rc}, stderr:\n${err}")
  endif()
  execute_process(COMMAND ${CMD} experiment speed --vocab ${WORK}/v.fabmap --out ${WORK}/speed
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 2 OR NOT err MATCHES "--vocab \\(FAB-MAP\\) is for tilt and manoeuvre")
    message(FATAL_ERROR "experiment speed --vocab: exit ${rc}, stderr:\n${err}")
  endif()
  file(REMOVE_RECURSE ${WORK}/tilt ${WORK}/tilt2 ${WORK}/speed)
else()
  message(FATAL_ERROR "PART='${PART}': expected train, eval, experiment or clean")
endif()
message(STATUS "fabmap ${PART}: passed")

