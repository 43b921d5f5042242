# Warnings and sanitizers for the project's own targets (call crowdslam_target_options(target)).
function(crowdslam_target_options target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-sign-compare)
  if(CMAKE_BUILD_TYPE STREQUAL "Release")
    target_compile_options(${target} PRIVATE -O3)
  endif()
endfunction()

if(CROWDSLAM_SANITIZE STREQUAL "address")
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
elseif(CROWDSLAM_SANITIZE STREQUAL "thread")
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
elseif(NOT CROWDSLAM_SANITIZE STREQUAL "")
  message(FATAL_ERROR "CROWDSLAM_SANITIZE must be '', 'address' or 'thread', got '${CROWDSLAM_SANITIZE}'")
endif()

# Helper: a library target for one folder of src/crowdslam.
#   crowdslam_add_library(NAME io SOURCES a.cpp b.cpp DEPS crowdslam_util OpenCV...)
#   Without SOURCES, every *.cpp in the calling folder is compiled (CONFIGURE_DEPENDS glob).
#   NO_PCH: no precompiled header (a library without Eigen and OpenCV among its dependencies).
function(crowdslam_add_library)
  cmake_parse_arguments(ARG "NO_PCH" "NAME" "SOURCES;DEPS" ${ARGN})
  set(no_pch "")
  if(ARG_NO_PCH)
    set(no_pch NO_PCH)
  endif()
  set(target crowdslam_${ARG_NAME})
  if(NOT ARG_SOURCES)
    file(GLOB ARG_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  endif()
  if(ARG_SOURCES)
    add_library(${target} STATIC ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} PUBLIC ${ARG_DEPS})
    crowdslam_target_options(${target})
    crowdslam_speed_up(${target} LIBRARY ${no_pch})
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR}/src)
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
  endif()
  add_library(crowdslam::${ARG_NAME} ALIAS ${target})
endfunction()

# Helper: one GoogleTest executable per module, registered with CTest.
#   crowdslam_add_test(NAME io SOURCES test_x.cpp DEPS crowdslam::io LABELS unit [SERIAL regex] [NO_PCH])
#   Without SOURCES, every test_*.cpp in the calling folder. Tests whose name matches SERIAL run alone
#   (RUN_SERIAL): threaded runs whose outcome depends on how the mapper keeps up, so that `ctest -j`
#   neighbours do not take their cores.
function(crowdslam_add_test)
  cmake_parse_arguments(ARG "NO_PCH" "NAME;SERIAL" "SOURCES;DEPS;LABELS" ${ARGN})
  set(no_pch "")
  if(ARG_NO_PCH)
    set(no_pch NO_PCH)
  endif()
  set(target test_${ARG_NAME})
  if(NOT ARG_SOURCES)
    file(GLOB ARG_SOURCES CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/test_*.cpp)
  endif()
  if(NOT ARG_SOURCES)
    return()
  endif()
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} crowdslam_test_support GTest::gtest_main)
  crowdslam_target_options(${target})
  crowdslam_speed_up(${target} TEST ${no_pch})
  gtest_discover_tests(${target} DISCOVERY_TIMEOUT 60)
  # Labels (module name + e.g. e2e) are set after discovery: passing a list through
  # gtest_discover_tests(PROPERTIES LABELS ...) keeps only its first element with CMake 3.25.
  set(labels_file "${CMAKE_CURRENT_BINARY_DIR}/${target}_labels.cmake")
  set(serial_check "")
  if(ARG_SERIAL)
    set(serial_check
      "  if(test_name MATCHES \"${ARG_SERIAL}\")\n"
      "    set_tests_properties(\"\${test_name}\" PROPERTIES RUN_SERIAL TRUE)\n"
      "  endif()\n")
  endif()
  file(WRITE "${labels_file}"
    "foreach(test_name IN LISTS ${target}_TESTS)\n"
    "  set_tests_properties(\"\${test_name}\" PROPERTIES LABELS \"${ARG_NAME};${ARG_LABELS}\")\n"
    ${serial_check}
    "endforeach()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${labels_file}")
endfunction()
