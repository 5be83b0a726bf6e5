# read_metrics(PATH VAR): a metrics.json (docs/METRICS.md) without its precision-recall
# curves, for the checks that read its numbers. CMake's string(JSON) parses the whole
# document at every call and the curves are nearly all of it: the speed experiment's 96
# rows are 6 MB, 68 KB without them, and its checks took a minute of CPU against 9 s for
# the run itself. metrics_schema.cmake checks the curves' shape on the whole file.
function(read_metrics path var)
  file(READ ${path} json)
  # A curve is one array of flat objects: nothing in it closes a bracket.
  string(REGEX REPLACE "\"curve\": \\[[^]]*\\]" "\"curve\": []" json "${json}")
  set(${var} "${json}" PARENT_SCOPE)
endfunction()
