# The stack-audit build (`sdins audit stack`, docs/audits.md; configure preset `stack-audit`):
# fsw/ compiled with GCC's per-function stack usage (.su) and call graph (.ci), plus the task
# entry wrappers (fsw/audit/stack_entries.cpp) and the audit's self-check fixtures
# (tests/stack/stack_fixtures.cpp), with the same flags. Nothing here is linked: the audit reads
# the .su/.ci files next to the objects and `size` of the fsw archive.
if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  message(FATAL_ERROR "SDINS_STACK_AUDIT needs GCC (-fcallgraph-info=su); the C++ compiler is ${CMAKE_CXX_COMPILER_ID}")
endif()
set(SDINS_STACK_AUDIT_FLAGS -fstack-usage -fcallgraph-info=su)
# The wrappers and fixtures get exactly the fsw flags (whatever fsw/CMakeLists.txt says today).
get_target_property(SDINS_FSW_OPTIONS sdins_fsw COMPILE_OPTIONS)
get_target_property(SDINS_FSW_DEFINITIONS sdins_fsw COMPILE_DEFINITIONS)
target_compile_options(sdins_fsw PRIVATE ${SDINS_STACK_AUDIT_FLAGS})

foreach(kind entries fixtures)
  if(kind STREQUAL "entries")
    set(src ${PROJECT_SOURCE_DIR}/fsw/audit/stack_entries.cpp)
  else()
    set(src ${PROJECT_SOURCE_DIR}/tests/stack/stack_fixtures.cpp)
  endif()
  add_library(sdins_stack_${kind} OBJECT ${src})
  target_link_libraries(sdins_stack_${kind} PRIVATE sdins_fsw)
  target_compile_options(sdins_stack_${kind} PRIVATE ${SDINS_FSW_OPTIONS} ${SDINS_STACK_AUDIT_FLAGS})
  target_compile_definitions(sdins_stack_${kind} PRIVATE ${SDINS_FSW_DEFINITIONS})
endforeach()
