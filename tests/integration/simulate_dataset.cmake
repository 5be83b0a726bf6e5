# `skyloc simulate --mode both` writes two dataset folders with every frame, its pose
# row and camera.toml; a second run into the same folder refuses to overwrite it.
set(dir ${WORK_DIR}/simulate_dataset)
file(REMOVE_RECURSE ${dir})
execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world repetitive --seed 3 --frames 4
                        --width 64 --height 48 --mode both --bumps 10 --out ${dir}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "simulate failed (${rc}):\n${out}\n${err}")
endif()
foreach(mode uv visible)
  foreach(f frames.csv camera.toml frames/000000.png frames/000003.png)
    if(NOT EXISTS ${dir}/${mode}/${f})
      message(FATAL_ERROR "missing ${dir}/${mode}/${f}")
    endif()
  endforeach()
  file(STRINGS ${dir}/${mode}/frames.csv rows)
  list(LENGTH rows n)
  if(NOT n EQUAL 5)
    message(FATAL_ERROR "${mode}/frames.csv has ${n} lines, expected a header and 4 rows")
  endif()
  # The camera file records the simulated camera's turn on the robot (DefaultSimLens's
  # mount), so a replay describes in the frame the recorded roll and pitch are in.
  file(READ ${dir}/${mode}/camera.toml camera)
  if(NOT camera MATCHES "yaw_deg = 90(\\.0*)?\n")
    message(FATAL_ERROR "${mode}/camera.toml does not record the mount yaw of 90:\n${camera}")
  endif()
  list(GET rows 0 header)
  if(NOT header STREQUAL "index,file,timestamp_s,x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg")
    message(FATAL_ERROR "unexpected header: ${header}")
  endif()
endforeach()
# Both spectra were rendered from the same poses.
file(READ ${dir}/uv/frames.csv uv_rows)
file(READ ${dir}/visible/frames.csv visible_rows)
if(NOT uv_rows STREQUAL visible_rows)
  message(FATAL_ERROR "uv and visible runs have different poses")
endif()
execute_process(COMMAND ${EMULATOR} ${CMD} simulate --world repetitive --frames 2 --width 64
                        --height 48 --out ${dir}/uv
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "simulate overwrote an existing dataset")
endif()
file(REMOVE_RECURSE ${dir})
