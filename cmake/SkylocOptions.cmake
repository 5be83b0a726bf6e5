# Compiler options live on INTERFACE targets, never in global CMAKE_CXX_FLAGS, so a
# third-party subproject (GoogleTest from source in cross builds) keeps its own flags.

add_library(skyloc_warnings INTERFACE)
add_library(skyloc::warnings ALIAS skyloc_warnings)
target_compile_options(skyloc_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wsign-conversion -Wold-style-cast
  -Wnon-virtual-dtor -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion
  -Wformat=2 -Wimplicit-fallthrough -Wcast-qual -Wundef)
if(SKYLOC_WERROR)
  target_compile_options(skyloc_warnings INTERFACE -Werror)
endif()
# 32-bit ARM: GCC notes at every std::sort of 64-bit values that GCC 7.1 changed how such
# arguments are passed. Only code mixed with objects from GCC 6 or older could be hurt;
# everything here, the sysroot's libraries included, comes from GCC 12.
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
  target_compile_options(skyloc_warnings INTERFACE -Wno-psabi)
endif()

# Floating point is IEEE everywhere: host and ARM must agree with the same reference
# files. -ffp-contract=off stops GCC fusing a*b+c into FMA on aarch64 (x86-64 baseline
# has no FMA), which would otherwise make the two architectures round differently.
# -fno-math-errno and -fno-trapping-math change no value: they tell GCC that nothing here
# reads errno after maths (sqrt of a negative is NaN either way) and nothing enables
# floating-point traps or reads the exception flags. That lets sqrt be one instruction
# and a select like `var > 0 ? z : 0` run without a branch, so such loops vectorise.
add_library(skyloc_fp INTERFACE)
add_library(skyloc::fp ALIAS skyloc_fp)
target_compile_options(skyloc_fp INTERFACE -ffp-contract=off -fno-fast-math -fno-math-errno
                                           -fno-trapping-math)

add_library(skyloc_sanitize INTERFACE)
add_library(skyloc::sanitize ALIAS skyloc_sanitize)
# -O1: Eigen and the SH tables at -O0 make the suite ten times slower, and the
# sanitizers still see every access at -O1. The GoogleTest programs' own code (target
# property SKYLOC_TEST_PROGRAM, cmake/SkylocModule.cmake) at -Og: most of it is
# GoogleTest's assertions, and a unit of the dsp tests compiles in 22 s of CPU under ASan
# and UBSan instead of 35, while the dsp tests ran in the same 20 s. (-O0 compiled it in
# 15 s but ran the dsp tests in 164 s: their reference loops and the Eigen code they
# instantiate.) The code under test keeps -O1.
set(skyloc_sanitize_opt $<IF:$<BOOL:$<TARGET_PROPERTY:SKYLOC_TEST_PROGRAM>>,-Og,-O1>)
if(SKYLOC_SANITIZE STREQUAL "address")
  target_compile_options(skyloc_sanitize INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
    ${skyloc_sanitize_opt})
  target_link_options(skyloc_sanitize INTERFACE -fsanitize=address,undefined)
  target_compile_definitions(skyloc_sanitize INTERFACE SKYLOC_SANITIZED=1)
elseif(SKYLOC_SANITIZE STREQUAL "thread")
  target_compile_options(skyloc_sanitize INTERFACE -fsanitize=thread -fno-omit-frame-pointer
                                                   ${skyloc_sanitize_opt})
  target_link_options(skyloc_sanitize INTERFACE -fsanitize=thread)
  target_compile_definitions(skyloc_sanitize INTERFACE SKYLOC_SANITIZED=1)
endif()

find_program(SKYLOC_CCACHE ccache)
if(SKYLOC_CCACHE)
  set(CMAKE_C_COMPILER_LAUNCHER ${SKYLOC_CCACHE})
  set(CMAKE_CXX_COMPILER_LAUNCHER ${SKYLOC_CCACHE})
endif()
