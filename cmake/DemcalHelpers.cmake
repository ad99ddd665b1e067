# One place for the project's compile settings and the two helpers every module uses.

add_library(demcal_warnings INTERFACE)
target_compile_options(demcal_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
  -Wno-sign-conversion)
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  # GCC 12 (Debian 12's) reports a false -Wrestrict inside std::string wherever "literal" +
  # std::string&& is inlined (GCC bugs 105329 and 105651), at call sites across the project.
  target_compile_options(demcal_warnings INTERFACE -Wno-restrict)
endif()
if(DEMCAL_NATIVE AND NOT DEMCAL_SANITIZE)
  # Without contracted multiply-adds the wider instructions keep the portable build's arithmetic:
  # a sphere run gives its bits (docs/engine.md, "The native build"). GCC 12 reports false
  # -Wmaybe-uninitialized positives inside Eigen's AVX-512 kernels, which -march=native enables
  # on this hardware.
  target_compile_options(demcal_warnings INTERFACE -march=native -ffp-contract=off
    -Wno-maybe-uninitialized)
endif()
if(DEMCAL_SANITIZE OR DEMCAL_FUZZ)
  # Undefined behaviour stops the program, as an address error does, so a test cannot pass over it.
  target_compile_options(demcal_warnings INTERFACE -fsanitize=address,undefined
    -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
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

# A GoogleTest executable's build: gtest with its main, the warnings, the source and build trees'
# paths (DEMCAL_SOURCE_DIR, DEMCAL_BINARY_DIR) and -O1 in optimised builds.
# A test's own code sets up, drives and checks; what it simulates or fits runs in the libraries it
# links, built at the build type's level (-O3 in Release). In ISO C++ mode (no contraction into
# fused multiply-adds) and without -ffast-math the level does not change a floating-point result.
# The test sources took 38 % of a clean build's compile time at -O3; at -O1 they take 28 % less.
function(demcal_test_executable target)
  target_link_libraries(${target} PRIVATE GTest::gtest GTest::gtest_main demcal_warnings)
  target_compile_definitions(${target} PRIVATE
    DEMCAL_SOURCE_DIR="${PROJECT_SOURCE_DIR}" DEMCAL_BINARY_DIR="${PROJECT_BINARY_DIR}")
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo>:-O1>)
endfunction()

# demcal_add_test(NAME contact_luding SOURCES test.cpp DEPS demcal::core_contact [LABELS peer] [TIMEOUT 60]
#                 [COST 90])
# COST: the seconds the test took in CI (2 cores). `ctest -j` starts tests in descending cost; a
# clean checkout has no timing history, so without it the long tests defined last would run
# alone at the end with a core idle. Given to the tests longer than about a minute.
function(demcal_add_test)
  cmake_parse_arguments(ARG "" "NAME;TIMEOUT;COST" "SOURCES;DEPS;LABELS" ${ARGN})
  set(target test_${ARG_NAME})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS})
  demcal_test_executable(${target})
  add_test(NAME ${ARG_NAME} COMMAND ${target})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  set_tests_properties(${ARG_NAME} PROPERTIES TIMEOUT ${ARG_TIMEOUT})
  if(ARG_LABELS)
    set_tests_properties(${ARG_NAME} PROPERTIES LABELS "${ARG_LABELS}")
  endif()
  if(ARG_COST)
    set_tests_properties(${ARG_NAME} PROPERTIES COST ${ARG_COST})
  endif()
endfunction()

# The demcal targets `target` links, directly or through others (aliases resolved), in `out`.
function(demcal_link_closure target out)
  set(seen)
  set(todo ${target})
  while(todo)
    list(POP_FRONT todo t)
    if(NOT TARGET ${t})
      continue()
    endif()
    get_target_property(real ${t} ALIASED_TARGET)
    if(real)
      set(t ${real})
    endif()
    if(t IN_LIST seen)
      continue()
    endif()
    list(APPEND seen ${t})
    get_target_property(type ${t} TYPE)
    set(props INTERFACE_LINK_LIBRARIES)
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      list(APPEND props LINK_LIBRARIES)
    endif()
    foreach(p ${props})
      get_target_property(deps ${t} ${p})
      if(deps)
        list(APPEND todo ${deps})
      endif()
    endforeach()
  endwhile()
  set(${out} ${seen} PARENT_SCOPE)
endfunction()

# Fails the configuration when `target` links any of the targets after FORBIDS (the dependency
# rule of docs/architecture.md: e.g. the coordinator never links the physics).
function(demcal_forbid_links target)
  cmake_parse_arguments(ARG "" "" "FORBIDS" ${ARGN})
  demcal_link_closure(${target} closure)
  foreach(f ${ARG_FORBIDS})
    if(f IN_LIST closure)
      message(FATAL_ERROR "${target} links ${f}: docs/architecture.md forbids it")
    endif()
  endforeach()
endfunction()

# Fails the configuration when a source or header under `dir` includes a header of one of the
# folders after FORBIDS (e.g. core/model never includes the lab runners or the engine).
function(demcal_forbid_includes dir)
  cmake_parse_arguments(ARG "" "" "FORBIDS" ${ARGN})
  file(GLOB files ${PROJECT_SOURCE_DIR}/${dir}/*.hpp ${PROJECT_SOURCE_DIR}/${dir}/*.cpp)
  list(JOIN ARG_FORBIDS "|" alternatives)
  foreach(f ${files})
    file(STRINGS ${f} hits REGEX "#include \"(${alternatives})/")
    if(hits)
      message(FATAL_ERROR "${f} includes ${hits}: docs/architecture.md forbids it")
    endif()
  endforeach()
endfunction()
