# One place for the project's compile settings and the two helpers every module uses.

add_library(demcal_warnings INTERFACE)
target_compile_options(demcal_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
  -Wno-sign-conversion)
if(DEMCAL_NATIVE AND NOT DEMCAL_SANITIZE)
  # GCC 12 reports false -Wmaybe-uninitialized positives inside Eigen's AVX-512 kernels, which
  # -march=native enables on this hardware.
  target_compile_options(demcal_warnings INTERFACE -march=native -Wno-maybe-uninitialized)
endif()
if(DEMCAL_SANITIZE OR DEMCAL_FUZZ)
  target_compile_options(demcal_warnings INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer)
  target_link_options(demcal_warnings INTERFACE -fsanitize=address,undefined)
endif()
if(DEMCAL_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "DEMCAL_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  # Coverage instrumentation for every library the harnesses link; the harnesses add the driver.
  target_compile_options(demcal_warnings INTERFACE -fsanitize=fuzzer-no-link)
endif()

# demcal_add_library(NAME core_contact SOURCES a.cpp b.cpp DEPS demcal::core_common)
# -> target demcal_core_contact with alias demcal::core_contact; headers are included
#    as "core/contact/x.hpp" from the repository root.
function(demcal_add_library)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;DEPS" ${ARGN})
  set(target demcal_${ARG_NAME})
  if(ARG_SOURCES)
    add_library(${target} STATIC ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} PUBLIC ${ARG_DEPS} PRIVATE demcal_warnings)
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${target} INTERFACE ${ARG_DEPS})
  endif()
  add_library(demcal::${ARG_NAME} ALIAS ${target})
endfunction()

# demcal_add_test(NAME contact_luding SOURCES test.cpp DEPS demcal::core_contact [LABELS peer] [TIMEOUT 60])
function(demcal_add_test)
  cmake_parse_arguments(ARG "" "NAME;TIMEOUT" "SOURCES;DEPS;LABELS" ${ARGN})
  set(target test_${ARG_NAME})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main demcal_warnings)
  target_compile_definitions(${target} PRIVATE
    DEMCAL_SOURCE_DIR="${PROJECT_SOURCE_DIR}" DEMCAL_BINARY_DIR="${PROJECT_BINARY_DIR}")
  add_test(NAME ${ARG_NAME} COMMAND ${target})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  set_tests_properties(${ARG_NAME} PROPERTIES TIMEOUT ${ARG_TIMEOUT})
  if(ARG_LABELS)
    set_tests_properties(${ARG_NAME} PROPERTIES LABELS "${ARG_LABELS}")
  endif()
endfunction()
