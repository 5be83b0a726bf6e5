# One library target per top-level folder. Public headers live under
# <folder>/include/skyloc/<folder>/, sources under <folder>/src/. A module's sources
# are listed by glob so that adding a file is one step; CONFIGURE_DEPENDS re-runs the
# glob at build time.
function(skyloc_add_module name)
  cmake_parse_arguments(ARG "" "" "PUBLIC_DEPS;PRIVATE_DEPS;EXTRA_SOURCES" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  add_library(skyloc_${name} STATIC ${sources} ${ARG_EXTRA_SOURCES})
  add_library(skyloc::${name} ALIAS skyloc_${name})
  target_include_directories(skyloc_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(skyloc_${name}
    PUBLIC ${ARG_PUBLIC_DEPS}
    PRIVATE skyloc::warnings ${ARG_PRIVATE_DEPS})
  target_link_libraries(skyloc_${name} PUBLIC skyloc::fp skyloc::sanitize)
  # A module compiles as units of 8 files, as the tests do: parsing the standard library
  # and Eigen was half or more of most files' compile time (measured with -fsyntax-only:
  # 34-85 %), paid again by each of the five build kinds. File-local names must therefore
  # be unique within a module.
  set_target_properties(skyloc_${name} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8)
endfunction()

# A GoogleTest executable whose cases are registered one by one with CTest (under a cross
# build gtest_discover_tests runs the binary through CMAKE_CROSSCOMPILING_EMULATOR), or,
# with SKYLOC_GTEST_SHARDS = N > 0, as N CTest tests NAME.shardI, each one process running
# a fixed 1/N of the cases (GoogleTest's sharding) and writing them to
# test-cases/NAME.shardI.xml in the build folder, which ./skyloc.sh counts case by case.
# Why: a process start is 0.1-0.3 s of CPU under ASan (shadow memory, the leak check at
# exit) and under qemu-user (some forty shared libraries relocated on emulated code), paid
# by every case; the ASan build's cases took 276 s one by one and 61 s as one process per
# program (measured 2026-11-28). One CTest test per case stays the default: it is what
# `ctest -R CASE` and the label native need.
function(skyloc_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  # A test folder compiles as units of 8 files: each test file parses GoogleTest, GoogleMock
  # and often Eigen, which cost more than the tests themselves, and the five build kinds of
  # ./skyloc.sh test compile every test. Measured on the dsp tests, cold: 108 s of CPU
  # against 169 s file by file. File-local names must therefore be unique within a folder
  # (shared helpers live in tests/support). SKYLOC_TEST_PROGRAM: the sanitizer builds
  # compile this code at -Og (cmake/SkylocOptions.cmake says why).
  set_target_properties(${name} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 8
                                            SKYLOC_TEST_PROGRAM ON)
  # The test code at -O1 in the optimised native build (the code under test keeps -O2):
  # most of a test file's compile is GoogleTest's assertions, which -O2 spends longer
  # optimising for no gain there (host: 179 s of compile CPU for the test programs instead
  # of 275). Not in the cross builds: under qemu-user the tests' own loops and the inline
  # code they instantiate run on emulated floating point, and at -O1 the armhf firmware
  # and dsp cases took 59 and 46 s of CPU instead of 34 and 25 (measured 2026-11-28).
  if(NOT CMAKE_CROSSCOMPILING)
    target_compile_options(${name} PRIVATE $<$<CONFIG:RelWithDebInfo,Release>:-O1>)
  endif()
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} skyloc::warnings GTest::gtest_main GTest::gmock)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_compile_definitions(${name} PRIVATE
    SKYLOC_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SKYLOC_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  set(labels ${ARG_LABELS})
  if(CMAKE_CROSSCOMPILING)
    list(APPEND labels cross)
  endif()
  # Labels are attached by a ctest-time include rather than gtest_discover_tests'
  # PROPERTIES, which (CMake 3.25) splits a list value such as "unit;cross" apart.
  # Label native, besides: the cases whose subject the sanitizers change, which the plain
  # host build runs while the ASan build runs the rest (./skyloc.sh test): allocation
  # counting (under a sanitizer the counter sees operator new but not C's malloc), an
  # impossible allocation (ASan aborts by design) and mlockall (ASan makes it a no-op).
  if(SKYLOC_GTEST_SHARDS GREATER 0)
    math(EXPR last "${SKYLOC_GTEST_SHARDS} - 1")
    foreach(i RANGE ${last})
      set(test ${name}.shard${i})
      add_test(NAME ${test} COMMAND ${name} WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
      # COST: a shard is several of the longest cases together; it starts before the
      # whole-command tests of a parallel run.
      set_tests_properties(${test} PROPERTIES LABELS "${labels}" COST 30
        ENVIRONMENT "GTEST_TOTAL_SHARDS=${SKYLOC_GTEST_SHARDS};GTEST_SHARD_INDEX=${i};GTEST_OUTPUT=xml:${CMAKE_BINARY_DIR}/test-cases/${test}.xml")
    endforeach()
    return()
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 120 TEST_LIST ${name}_TESTS)
  set(label_script ${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake)
  file(WRITE ${label_script}
    "if(DEFINED ${name}_TESTS)\n"
    "  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${labels}\")\n"
    "  foreach(t IN LISTS ${name}_TESTS)\n"
    "    if(t MATCHES \"${SKYLOC_NATIVE_CASES}\")\n"
    "      set_tests_properties(\${t} PROPERTIES LABELS \"${labels};native\")\n"
    "    endif()\n"
    "  endforeach()\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${label_script})
endfunction()
