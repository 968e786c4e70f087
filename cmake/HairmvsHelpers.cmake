# Warnings only on our own targets, never on third-party headers.
function(hairmvs_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra)
  if(HAIRMVS_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()

# hairmvs_add_library(NAME SOURCES ... DEPS ...): one static library per concern.
function(hairmvs_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  hairmvs_set_warnings(${name})
endfunction()

# hairmvs_add_test(NAME SOURCES ... DEPS ... [LABELS ...]): a GoogleTest binary registered
# with CTest, run from the build folder. HAIRMVS_SHARED_DATA_DIR and COLMAP_EXECUTABLE are
# passed as compile definitions so tests find the shared data sets and the colmap binary.
function(hairmvs_add_test name)
  if(NOT HAIRMVS_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    HAIRMVS_SHARED_DATA_DIR="${HAIRMVS_SHARED_DATA_DIR}"
    HAIRMVS_COLMAP_EXECUTABLE="${COLMAP_EXECUTABLE}"
    HAIRMVS_BINARY_DIR="${CMAKE_BINARY_DIR}")
  hairmvs_set_warnings(${name})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  # The colmap runs under test log beside CTest's own logs: glog's default is the machine's
  # /tmp, four files a run (colmap sets logtostderr itself, so only the folder can be moved).
  # LABELS last: an empty one is dropped from the list, and would take the next key as its value.
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
    PROPERTIES TIMEOUT ${ARG_TIMEOUT}
               ENVIRONMENT "GLOG_log_dir=${CMAKE_BINARY_DIR}/Testing/Temporary"
               LABELS "${ARG_LABELS}")
endfunction()
