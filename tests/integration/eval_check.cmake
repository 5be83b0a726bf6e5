# The `skyloc eval` integration test: generate two small dataset folders, evaluate the
# query run against the reference run, and check the outputs a person would open.
#   -DGEN=make_eval_datasets -DCMD=skyloc -DWORK=dir -DMODE=batch|streaming -DEMULATOR=...
include(${CMAKE_CURRENT_LIST_DIR}/metrics_json.cmake)
file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${EMULATOR} ${GEN} ${WORK} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "dataset generator failed (${rc}): ${err}")
endif()
if(MODE STREQUAL "streaming")
  # Ground truth from the CSV file; the firmware's causal engine.
  set(args --gt ${WORK}/gt.csv --streaming --method vanilla --method sky --bands 16)
elseif(MODE STREQUAL "distance")
  # Correct when the matched reference was recorded within 1.6 m of the query (the query
  # runs 0.5 m beside the reference, frames 1 m apart: +-1 frame). The default matcher,
  # the route filter, which matches every frame from the first.
  set(args --tolerance-m 1.6 --method vanilla)
else()
  # Ground truth from the recorded poses (nearest reference, +-5 frames).
  set(args --batch --method vanilla)
endif()
execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${WORK}/reference
                --query ${WORK}/query --ds 1 --ds 10 --out ${WORK}/out ${args}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "skyloc eval failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")
foreach(f matches.csv metrics.json pr.svg correspondence.svg)
  if(NOT EXISTS ${WORK}/out/${f})
    message(FATAL_ERROR "skyloc eval did not write ${f}")
  endif()
endforeach()
read_metrics(${WORK}/out/metrics.json json)
string(JSON runs LENGTH "${json}" runs)
# Runs are method-major (sky before vanilla), then in --ds order.
if(MODE STREQUAL "streaming")
  set(expected_runs 4)
  set(vanilla10 3)
else()
  set(expected_runs 2)
  set(vanilla10 1)
endif()
if(NOT runs EQUAL expected_runs)
  message(FATAL_ERROR "metrics.json has ${runs} runs, expected ${expected_runs}")
endif()
# Vanilla at ds = 10: exposure change and noise do not fool it.
string(JSON method GET "${json}" runs ${vanilla10} method)
string(JSON ds GET "${json}" runs ${vanilla10} ds)
string(JSON evaluated GET "${json}" runs ${vanilla10} evaluated)
string(JSON precision GET "${json}" runs ${vanilla10} precision_at_100_recall)
if(NOT method STREQUAL "vanilla" OR NOT ds EQUAL 10)
  message(FATAL_ERROR "run ${vanilla10} is ${method} ds ${ds}, expected vanilla ds 10")
endif()
if(MODE STREQUAL "distance")
  set(expected_evaluated 40)  # the filter matches every frame
else()
  set(expected_evaluated 31)  # OpenSeqSLAM: 40 frames minus the 9 without a full window
endif()
if(NOT evaluated EQUAL expected_evaluated)
  message(FATAL_ERROR "vanilla ds 10 evaluated ${evaluated} queries, expected ${expected_evaluated}")
endif()
if(precision LESS 0.9)
  message(FATAL_ERROR "vanilla ds 10 precision at 100% recall is ${precision}, expected >= 0.9")
endif()
file(STRINGS ${WORK}/out/matches.csv header LIMIT_COUNT 1)
if(NOT header STREQUAL "method,ds,query_index,reference_index,score,uniqueness,correct,matcher,state")
  message(FATAL_ERROR "matches.csv header: ${header}")
endif()
string(JSON truth GET "${json}" ground_truth)
if(MODE STREQUAL "distance" AND NOT truth MATCHES "within 1.6 m")
  message(FATAL_ERROR "metrics.json ground_truth is '${truth}', expected the distance rule")
endif()
file(READ ${WORK}/out/correspondence.svg svg)
if(NOT svg MATCHES "vanilla [a-z]+ ds=10" OR NOT svg MATCHES "#1a9e1a")
  message(FATAL_ERROR "correspondence.svg lacks the vanilla ds=10 panel or its green dots")
endif()

# A ground truth that covers 2 of the 40 query frames still scores, but says so.
if(MODE STREQUAL "streaming")
  file(STRINGS ${WORK}/gt.csv gt_lines)
  list(SUBLIST gt_lines 0 3 gt_partial)
  list(JOIN gt_partial "\n" gt_partial)
  file(WRITE ${WORK}/gt_partial.csv "${gt_partial}\n")
  execute_process(COMMAND ${EMULATOR} ${CMD} eval --reference ${WORK}/reference
                  --query ${WORK}/query --ds 10 --out ${WORK}/out_partial --gt ${WORK}/gt_partial.csv
                  --streaming --method vanilla
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "skyloc eval with a partial ground truth failed (${rc}):\n${out}\n${err}")
  endif()
  if(NOT err MATCHES "warning: the ground truth \\([^)]*\\) covers 2 of 40 query frames")
    message(FATAL_ERROR "eval with a ground truth of 2 of 40 queries did not warn:\n${err}")
  endif()
endif()
