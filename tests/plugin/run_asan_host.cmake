# Builds a C host with AddressSanitizer the way docs/plugin.md tells hosts
# that dlopen the plugin to (the C++ runtime linked in, so that it is loaded
# before AddressSanitizer resolves its __cxa_throw interceptor), and runs its
# error paths against the plugin. Prints "skipped: ..." (the test's skip
# expression) when no C compiler here builds with -fsanitize=address.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
find_program(CLANG NAMES clang clang-18 clang-17 clang-16 clang-15 clang-14)
set(candidates ${CLANG} ${C_COMPILER})
set(host "")
foreach(cc IN LISTS candidates)
  if(NOT cc)
    continue()
  endif()
  set(exe ${WORK_DIR}/asan_host)
  execute_process(COMMAND ${cc} -std=c99 -g -fsanitize=address -fno-omit-frame-pointer -I${INCLUDE_DIR}
                          ${SOURCE} -o ${exe} -ldl -Wl,--push-state,--no-as-needed -lstdc++ -Wl,--pop-state
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0)
    set(host ${exe})
    message(STATUS "built the AddressSanitizer host with ${cc}")
    break()
  endif()
  message(STATUS "${cc} cannot build with -fsanitize=address:\n${err}")
endforeach()
if(NOT host)
  message(STATUS "skipped: no C compiler with AddressSanitizer (tried: ${candidates})")
  return()
endif()
execute_process(COMMAND ${host} ${PLUGIN}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT out MATCHES "dlopen host: ok")
  message(FATAL_ERROR "the AddressSanitizer host failed (${rc}):\n${out}\n${err}")
endif()
message(STATUS "${out}")
