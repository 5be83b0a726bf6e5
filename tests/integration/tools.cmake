# The lab's tools' whole-command tests (eval, surf1d, simulate, the experiments,
# FAB-MAP): included by CMakeLists.txt when SKYLOC_TOOLS is on, so the firmware-only (ARM)
# build registers none of them.

# skyloc eval on two generated 40-frame datasets: batch with pose truth (+-5 frames),
# streaming with CSV truth, batch with the distance rule.
add_executable(make_eval_datasets make_eval_datasets.cpp)
target_link_libraries(make_eval_datasets PRIVATE skyloc::drivers skyloc::warnings)
foreach(mode batch streaming distance)
  add_test(NAME cli.eval_${mode} COMMAND ${CMAKE_COMMAND}
    -DGEN=$<TARGET_FILE:make_eval_datasets> -DCMD=${skyloc_exe} -DMODE=${mode}
    -DWORK=${CMAKE_CURRENT_BINARY_DIR}/eval_${mode}
    "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/eval_check.cmake)
endforeach()
# eval --out: a non-empty folder needs --force; a full disk never leaves a truncated file.
skyloc_expect_output(cli.eval_out_folder COMMAND bash ${CMAKE_CURRENT_SOURCE_DIR}/eval_out.sh
  ${skyloc_exe} $<TARGET_FILE:make_eval_datasets> ${CMAKE_CROSSCOMPILING_EMULATOR}
  OUTPUT "all checks passed")
set_tests_properties(cli.eval_out_folder PROPERTIES TIMEOUT 300)
# eval --attitude dataset: the cap levelled by each frame's recorded roll/pitch.
skyloc_expect_output(cli.eval_attitude_dataset COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/eval_attitude.cmake OUTPUT "all checks passed")
set_tests_properties(cli.eval_attitude_dataset PROPERTIES TIMEOUT 600)
add_test(NAME cli.eval_missing_dataset_exits_1 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=eval;--reference;/nonexistent/ref;--query;/nonexistent/q;--out;${CMAKE_CURRENT_BINARY_DIR}/eval_never_written"
  -DEXPECT_RC=1 -DEXPECT_STDERR=/nonexistent/ref\ does\ not\ exist
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
# The streaming test's datasets are 64x48: a camera file for 640x480 is refused by name.
add_test(NAME cli.eval_camera_size_mismatch_exits_1 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe}
  "-DARGS=eval;--reference;${CMAKE_CURRENT_BINARY_DIR}/eval_streaming/reference;--query;${CMAKE_CURRENT_BINARY_DIR}/eval_streaming/query;--method;sky;--ds;1;--gt;${CMAKE_CURRENT_BINARY_DIR}/eval_streaming/gt.csv;--camera;${PROJECT_SOURCE_DIR}/config/camera-equidistant-185.toml;--out;${CMAKE_CURRENT_BINARY_DIR}/eval_mismatch"
  -DEXPECT_RC=1 -DEXPECT_STDERR=describes\ 640x480
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
set_tests_properties(cli.eval_streaming PROPERTIES FIXTURES_SETUP eval_streaming_data)
set_tests_properties(cli.eval_camera_size_mismatch_exits_1 PROPERTIES
  FIXTURES_REQUIRED eval_streaming_data)
# --bands cannot apply to the paper's grid (120 bands by definition): refused before any
# dataset is read.
file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/paper_grid.toml "[descriptor]\ngrid = \"paper\"\n")
add_test(NAME cli.eval_bands_on_paper_grid_exits_1 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe}
  "-DARGS=eval;--reference;/nonexistent/ref;--query;/nonexistent/q;--out;${CMAKE_CURRENT_BINARY_DIR}/eval_never_written;--config;${CMAKE_CURRENT_BINARY_DIR}/paper_grid.toml;--bands;64"
  -DEXPECT_RC=1 -DEXPECT_STDERR=grid\ =\ \"paper\"\ has\ 120\ bands
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.eval_bad_ds_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=eval;--ds;0" -DEXPECT_RC=2 -DEXPECT_STDERR=sequence\ length
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
# skyloc surf1d: the heading of a turned view by both methods, the plot, bad input.
skyloc_expect_output(cli.surf1d_heading COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/surf1d_command.cmake OUTPUT "all checks passed")
add_test(NAME cli.simulate_writes_datasets COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/simulate_dataset.cmake)
add_test(NAME cli.simulate_time_sampled COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/simulate_time.cmake)
# The help names every time-sampling flag.
skyloc_expect_output(cli.simulate_help_lists_sampling COMMAND ${CMAKE_CROSSCOMPILING_EMULATOR}
  ${skyloc_exe} simulate --help
  OUTPUT "--fps N.*--speed M/S.*--speed-band F.*--accel A.*--start-stop S.*--stops N.*--stop-seconds MIN,MAX.*--spacing M")
add_test(NAME cli.simulate_mixed_sampling_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=simulate;--world;city;--spacing;1;--fps;10;--out;unused"
  -DEXPECT_RC=2 "-DEXPECT_STDERR=--fps samples in time but --spacing samples in distance"
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.simulate_bad_stop_seconds_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=simulate;--world;city;--stop-seconds;5,2;--out;unused"
  -DEXPECT_RC=2 "-DEXPECT_STDERR=--stop-seconds '5,2': expected MIN,MAX"
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.simulate_bad_lateral_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=simulate;--world;forest;--lateral;7;--out;unused"
  -DEXPECT_RC=2 "-DEXPECT_STDERR=--lateral '7': expected a number in \\[0, 5\\]"
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.simulate_bad_world_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=simulate;--world;moon;--out;unused" -DEXPECT_RC=2
  -DEXPECT_STDERR=seville,\ city,\ forest\ or\ repetitive
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.simulate_seville_without_data_exits_1 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=simulate;--world;seville;--data;/nonexistent;--out;unused"
  -DEXPECT_RC=1 -DEXPECT_STDERR=--data
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.eval_heading COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK=${CMAKE_CURRENT_BINARY_DIR}/eval_heading "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/eval_heading.cmake)
add_test(NAME cli.eval_surf1d COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK=${CMAKE_CURRENT_BINARY_DIR}/eval_surf1d "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/eval_surf1d.cmake)

# One metrics.json schema: eval's and an experiment's files share it (docs/METRICS.md).
skyloc_expect_output(cli.metrics_schema_shared COMMAND ${CMAKE_COMMAND}
  -DGEN=$<TARGET_FILE:make_eval_datasets> -DCMD=${skyloc_exe}
  -DWORK=${CMAKE_CURRENT_BINARY_DIR}/metrics_schema "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/metrics_schema.cmake OUTPUT "all checks passed")
# The experiments.
add_test(NAME cli.experiment_writes_outputs COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/experiment_outputs.cmake)
add_test(NAME cli.experiment_speed_writes_outputs COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/experiment_speed.cmake)
add_test(NAME cli.experiment_heading_writes_outputs COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/experiment_heading.cmake)
add_test(NAME cli.experiment_surf1d_writes_outputs COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
  -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR} "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}"
  -P ${CMAKE_CURRENT_SOURCE_DIR}/experiment_surf1d.cmake)
add_test(NAME cli.experiment_unknown_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=experiment;moon;--out;unused" -DEXPECT_RC=2
  -DEXPECT_STDERR=unknown\ experiment
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)
add_test(NAME cli.experiment_bad_grid_exits_2 COMMAND ${CMAKE_COMMAND}
  -DCMD=${skyloc_exe} "-DARGS=experiment;speed;--out;unused;--grid;fine" -DEXPECT_RC=2
  "-DEXPECT_STDERR=--grid 'fine': expected oversampled, auto or paper"
  "-DEMULATOR=${CMAKE_CROSSCOMPILING_EMULATOR}" -P ${CMAKE_CURRENT_SOURCE_DIR}/expect_exit.cmake)

# FAB-MAP 2.0 (host builds only): train a vocabulary on one simulated visible-light run
# (cli.fabmap_train), then, side by side, evaluate two others and refuse a file that is
# not a vocabulary (cli.fabmap_eval), and run the tilt experiment's FAB-MAP column
# (cli.fabmap_experiment). As one test they took 150 s of one core under ASan, the longest
# test of that run. cli.fabmap_clean removes the vocabulary after them.
foreach(part train eval experiment clean)
  skyloc_expect_output(cli.fabmap_${part} COMMAND ${CMAKE_COMMAND} -DCMD=${skyloc_exe}
    -DWORK=${CMAKE_CURRENT_BINARY_DIR}/fabmap -DPART=${part}
    -P ${CMAKE_CURRENT_SOURCE_DIR}/fabmap_check.cmake
    OUTPUT "fabmap ${part}: passed")
endforeach()
set_tests_properties(cli.fabmap_train PROPERTIES FIXTURES_SETUP fabmap_vocabulary)
set_tests_properties(cli.fabmap_eval cli.fabmap_experiment PROPERTIES
                     FIXTURES_REQUIRED fabmap_vocabulary)
set_tests_properties(cli.fabmap_clean PROPERTIES FIXTURES_CLEANUP fabmap_vocabulary)
# COST: seconds, so a parallel run starts the long ones first (tests/test_costs.cmake).
set_tests_properties(cli.fabmap_train cli.fabmap_eval cli.fabmap_experiment PROPERTIES
                     TIMEOUT 300 COST 40)
set_tests_properties(cli.experiment_speed_writes_outputs cli.experiment_heading_writes_outputs
                     PROPERTIES COST 20)
