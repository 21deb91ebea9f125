# Fuzz targets (fuzz/README.md). One function registers a libFuzzer target for both kinds of build:
#
#   sdins_add_fuzz_target(NAME <name> SOURCE <file.cpp> LIBS <libs...>
#                         [CORPUS <seed dirs...>] [DICT <file>])
#
# Fuzz build (-DSDINS_FUZZ=ON, clang, preset `fuzz`): executable fuzz_<name> linked with
#   -fsanitize=fuzzer (the whole build carries -fsanitize=fuzzer-no-link,address,undefined), and
#   CTest fuzz_<name> that fuzzes for SDINS_FUZZ_SECONDS over a scratch corpus in the build tree
#   (new inputs go there, never into the committed seeds) plus the seed directories and the
#   committed regression inputs; a crash fails the test and leaves crash-<sha1> under
#   <build>/fuzz/artifacts/<name>/.
# Normal build (tests on): executable fuzz_replay_<name> = the same target + fuzz/replay_main.cpp,
#   and CTest fuzz_replay_<name> that runs every seed and every fuzz/regressions/<name>/ input once
#   (in the asan preset: under AddressSanitizer and UBSan).
set(SDINS_FUZZ_SECONDS 25 CACHE STRING "seconds each fuzz target runs in its CTest (fuzz build)")

function(sdins_add_fuzz_target)
  cmake_parse_arguments(F "" "NAME;SOURCE;DICT" "LIBS;CORPUS" ${ARGN})
  if(NOT F_NAME OR NOT F_SOURCE)
    message(FATAL_ERROR "sdins_add_fuzz_target: NAME and SOURCE are required")
  endif()
  set(regressions ${PROJECT_SOURCE_DIR}/fuzz/regressions/${F_NAME})
  set(inputs ${F_CORPUS})
  if(EXISTS ${regressions})
    list(APPEND inputs ${regressions})
  endif()
  if(SDINS_FUZZ)
    add_executable(fuzz_${F_NAME} ${F_SOURCE})
    target_link_libraries(fuzz_${F_NAME} PRIVATE ${F_LIBS})
    target_link_options(fuzz_${F_NAME} PRIVATE -fsanitize=fuzzer)
    set(work ${CMAKE_BINARY_DIR}/fuzz/corpus/${F_NAME})
    set(artifacts ${CMAKE_BINARY_DIR}/fuzz/artifacts/${F_NAME})
    file(MAKE_DIRECTORY ${work} ${artifacts})
    set(dict_arg "")
    if(F_DICT)
      set(dict_arg -dict=${F_DICT})
    endif()
    add_test(NAME fuzz_${F_NAME}
             COMMAND fuzz_${F_NAME} -max_total_time=${SDINS_FUZZ_SECONDS} -timeout=10 -rss_limit_mb=2048
                     -print_final_stats=1 -artifact_prefix=${artifacts}/ ${dict_arg} ${work} ${inputs})
    set_tests_properties(fuzz_${F_NAME} PROPERTIES TIMEOUT 300 LABELS fuzz)
  elseif(SDINS_BUILD_TESTS)
    add_executable(fuzz_replay_${F_NAME} ${F_SOURCE} ${PROJECT_SOURCE_DIR}/fuzz/replay_main.cpp)
    target_link_libraries(fuzz_replay_${F_NAME} PRIVATE ${F_LIBS})
    add_test(NAME fuzz_replay_${F_NAME} COMMAND fuzz_replay_${F_NAME} ${inputs})
    set_tests_properties(fuzz_replay_${F_NAME} PROPERTIES TIMEOUT 120 LABELS fuzz_replay)
  endif()
endfunction()
