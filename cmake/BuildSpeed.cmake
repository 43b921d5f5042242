# Build speed without changing what is compiled (docs/ARCHITECTURE.md, "Build"):
#  - unity builds of the libraries, the CLI and the Python module: a target's sources are compiled in
#    batches, each batch one translation unit, so the headers (Eigen, OpenCV, CLI11, nlohmann-json) are
#    parsed and their inline functions compiled once per batch instead of once per file;
#  - precompiled headers: one for all libraries (cmake/pch/common.h), one for the test executables
#    (cmake/pch/tests.h), each built once and reused by every target of its kind;
#  - ccache when it is installed.
option(CROWDSLAM_UNITY "Unity (batched) builds of the project's targets" ON)
set(CROWDSLAM_UNITY_BATCH 8 CACHE STRING "Source files per unity translation unit")
option(CROWDSLAM_PCH "Precompiled headers for the heavy third-party headers (Eigen, OpenCV, GoogleTest)" ON)
option(CROWDSLAM_CCACHE "Compile through ccache when it is installed" ON)

if(CROWDSLAM_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  find_program(CROWDSLAM_CCACHE_PROGRAM ccache)
  if(CROWDSLAM_CCACHE_PROGRAM)
    # pch_defines/time_macros: let ccache cache the translation units that use a precompiled header.
    set(CMAKE_CXX_COMPILER_LAUNCHER
        "${CMAKE_COMMAND}" -E env "CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime"
        "${CROWDSLAM_CCACHE_PROGRAM}")
    message(STATUS "crowdslam: compiling through ${CROWDSLAM_CCACHE_PROGRAM}")
  endif()
endif()

# crowdslam_speed_up(target [LIBRARY|EXECUTABLE|TEST] [NO_PCH]): unity batches and the precompiled header
# of the target's kind. An executable (-fPIE where libraries are -fPIC) precompiles its own header.
function(crowdslam_speed_up target)
  cmake_parse_arguments(ARG "LIBRARY;EXECUTABLE;TEST;NO_PCH" "" "" ${ARGN})
  # Test files are not batched: their file-local helpers (test cameras, small sequences) share names.
  if(CROWDSLAM_UNITY AND NOT ARG_TEST)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${CROWDSLAM_UNITY_BATCH})
  endif()
  if(NOT CROWDSLAM_PCH OR ARG_NO_PCH)
    return()
  endif()
  target_compile_options(${target} PRIVATE -Winvalid-pch)
  # The precompiled headers' owners (made on first use) have the compile options of the targets that
  # reuse their header: GCC uses a precompiled header only when those match (-Winvalid-pch says so).
  if(ARG_LIBRARY)
    if(NOT TARGET crowdslam_pch_library)
      add_library(crowdslam_pch_library STATIC "${PROJECT_SOURCE_DIR}/cmake/pch/empty.cpp")
      target_link_libraries(crowdslam_pch_library PRIVATE Eigen3::Eigen opencv_core)
      crowdslam_target_options(crowdslam_pch_library)
      target_precompile_headers(crowdslam_pch_library PRIVATE "${PROJECT_SOURCE_DIR}/cmake/pch/common.h")
    endif()
    target_precompile_headers(${target} REUSE_FROM crowdslam_pch_library)
  elseif(ARG_TEST)
    if(NOT TARGET crowdslam_pch_tests)
      add_executable(crowdslam_pch_tests "${PROJECT_SOURCE_DIR}/cmake/pch/empty_main.cpp")
      target_link_libraries(crowdslam_pch_tests PRIVATE Eigen3::Eigen opencv_core GTest::gtest)
      crowdslam_target_options(crowdslam_pch_tests)
      target_precompile_headers(crowdslam_pch_tests PRIVATE "${PROJECT_SOURCE_DIR}/cmake/pch/tests.h")
    endif()
    target_precompile_headers(${target} REUSE_FROM crowdslam_pch_tests)
  else()
    target_precompile_headers(${target} PRIVATE "${PROJECT_SOURCE_DIR}/cmake/pch/common.h")
  endif()
endfunction()
